"""The sign detector's fronto-parallel sweep (the gtest
`SignDetectorTest.NoFlipsOverAFrontoParallelSweep`: one tracking detector over 45 face-on views
at 2-3 m) run with OpenCV's SIMD kernels as this CPU
has them and with AVX and above disabled (`OPENCV_CPU_DISABLE`): both runs pass the gtest's own
bounds (truth: the synthetic sign's known pose), and the per-position angle errors of the two
instruction sets agree within ANGLE_TOLERANCE_DEG.

A tracked alignment that kept the last frame's tilt put the 3 m, 0.1 m lateral view 3.5 deg off
without AVX2 and 0.5 deg with it; aligned to convergence the two agree within 0.5 deg (the fresh
search's own results differ by up to 0.2 deg).

Needs the built workspace (`rosrun follow_bot follow_bot_core_test`). Run with -s to print the
per-position table.
"""

import os
import re
import subprocess

import pytest

GTEST = "SignDetectorTest.NoFlipsOverAFrontoParallelSweep"
# Without AVX2 OpenCV 4.6 takes its SSE4 kernels (AVX-512 too is off, where the CPU has it).
WITHOUT_AVX = "AVX512_SKX,AVX2,FMA3,AVX"
# Measured: 0.50 deg at most between this CPU's AVX2 kernels and SSE4 (3.07 before tracked
# frames aligned to convergence).
ANGLE_TOLERANCE_DEG = 1.0
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
    return {"native": sweep(""), "without AVX": sweep(WITHOUT_AVX)}


def test_sweep_errors_do_not_depend_on_the_instruction_set(sweeps, record_property):
    native, without = sweeps["native"], sweeps["without AVX"]
    lines = ["range lateral | tracked native, without AVX | searched native, without | bound"]
    worst = 0.0
    for key, row in native.items():
        other = without[key]
        difference = abs(float(row["angle"]) - float(other["angle"]))
        worst = max(worst, difference)
        lines.append(
            f"{key[0]:.1f} {key[1]:+.1f} | {row['angle']} {other['angle']} | "
            f"{row['searched']} {other['searched']} | {row['bound']}"
        )
        assert difference <= ANGLE_TOLERANCE_DEG, f"{key}: {row['angle']} vs {other['angle']} deg"
    record_property("summary", f"sign sweep, native vs {WITHOUT_AVX} off: worst {worst:.3f} deg")
    print("\n".join(lines))
