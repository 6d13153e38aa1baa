"""The sign detector's fronto-parallel sweep (the gtest
`SignDetectorTest.NoFlipsOverAFrontoParallelSweep`: one tracking detector over 45 face-on views
at 2-3 m) run with OpenCV's SIMD kernels as this CPU has them and with ever fewer of them
(`OPENCV_CPU_DISABLE`, OpenCV's own feature names): every run passes the gtest's own bounds
(truth: the synthetic sign's known pose), and the per-position angle errors of every instruction
set agree with the native ones within ANGLE_TOLERANCE_DEG.

When the alignment's Gauss-Newton system was solved in floats (cv::findTransformECC), the 3 m,
0.1 m lateral view came out 3.5 deg off with SSE4 kernels and 0.5 deg with AVX2 (3.07 deg apart
at worst over the sweep); solved in doubles on centred coordinates, 0.001 deg at worst.

Needs the built workspace (`rosrun follow_bot follow_bot_core_test`). Run with -s to print the
per-position table. Four sweeps of the gtest (~40 s): `make test-full` only; `make test` runs
the native one as the gtest itself.
"""

import os
import re
import subprocess

import pytest

pytestmark = pytest.mark.full

GTEST = "SignDetectorTest.NoFlipsOverAFrontoParallelSweep"
# OpenCV 4.6 dispatches SSE4.1 and up at run time; each step down disables the set above it
# (AVX-512 only where the CPU has it: elsewhere OpenCV warns and goes on).
DISABLED = {
    "native": "",
    "without AVX2": "AVX512-SKX,AVX2,FMA3",
    "SSE4": "AVX512-SKX,AVX2,FMA3,AVX",
    "SSE2": "AVX512-SKX,AVX2,FMA3,AVX,FP16,SSE4.2,SSE4.1,POPCNT,SSSE3,SSE3",
}
# Measured: 0.001 deg at most between any two of them.
ANGLE_TOLERANCE_DEG = 0.05
LINE = re.compile(
    r"range (?P<range>\S+) lateral (?P<lateral>\S+) (?P<how>tracked|searched)\s*: "
    r"angle (?P<angle>[0-9.]+) deg, searched (?P<searched>[0-9.]+), bound (?P<bound>[0-9.]+)"
)


def sweep(disabled: str) -> dict:
    """Per (range, lateral): the gtest's printed angles, with these OpenCV CPU features off."""
    env = dict(os.environ, OPENCV_CPU_DISABLE=disabled)
    run = subprocess.run(
        ["rosrun", "follow_bot", "follow_bot_core_test", f"--gtest_filter={GTEST}"],
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert run.returncode == 0, f"OPENCV_CPU_DISABLE={disabled!r}:\n{run.stdout[-3000:]}"
    rows = {
        (float(m["range"]), round(float(m["lateral"]), 1)): m.groupdict()
        for m in LINE.finditer(run.stdout)
    }
    assert len(rows) == 45, run.stdout[-3000:]
    return rows


@pytest.fixture(scope="module")
def sweeps():
    return {name: sweep(disabled) for name, disabled in DISABLED.items()}


def test_sweep_errors_do_not_depend_on_the_instruction_set(sweeps, record_property):
    native = sweeps["native"]
    lines = [
        "range lateral | tracked: " + ", ".join(sweeps) + " | searched: " + ", ".join(sweeps)
        + " | bound"
    ]  # fmt: skip
    worst = 0.0
    for key, row in native.items():
        for name, other in sweeps.items():
            difference = abs(float(row["angle"]) - float(other[key]["angle"]))
            worst = max(worst, difference)
            assert (
                difference <= ANGLE_TOLERANCE_DEG
            ), f"{key}: {row['angle']} native vs {other[key]['angle']} deg {name}"
        lines.append(
            f"{key[0]:.1f} {key[1]:+.1f} | "
            + " ".join(s[key]["angle"] for s in sweeps.values())
            + " | "
            + " ".join(s[key]["searched"] for s in sweeps.values())
            + f" | {row['bound']}"
        )
    record_property(
        "summary", f"sign sweep over {len(sweeps)} instruction sets: worst {worst:.3f} deg apart"
    )
    print("\n".join(lines))
