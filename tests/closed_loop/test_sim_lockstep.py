"""The simulator node in lockstep with the scripted constant-Twist node (real ROS processes).

Each run gets its own roscore from run_scenario; the recorded trajectory must equal the
closed-form unicycle arc, and a run played alone or beside another must be identical.
"""

import json
import math
import subprocess
from pathlib import Path

import numpy as np
import pytest

from harness.report import without_wall_clock
from harness.testing import REPO

# Infrastructure checks of a minute or more each: `make test-full` plays them, so `make test`
# keeps within its 12 minutes with every bad-input, fault and scenario-family test.
pytestmark = pytest.mark.full

SCENARIO = REPO / "worlds" / "scenarios" / "constant_arc.yaml"


PARKER = (
    "name: parker_short\nworld: parking\nstart: {from: goal_tag, distance: 1.0, off_deg: 10}\n"
    "behaviour: {launch: follow_bot parker.launch}\nduration: 6.0\ngoal: goal_tag\n"
)
NAMES = ("constant_arc", "parker_short")


@pytest.fixture(scope="module")
def runs(tmp_path_factory) -> dict[int, tuple[Path, dict]]:
    """The scripted arc and a short parker run, played one at a time (--jobs 1) and then both
    at once (--jobs 2, each in its own ROS graph): per jobs, the output folder and summary."""
    folder = tmp_path_factory.mktemp("lockstep")
    parker = folder / "parker_short.yaml"
    parker.write_text(PARKER)
    played = {}
    for jobs in (1, 2):
        out = folder / f"jobs{jobs}"
        command = ["rosrun", "harness", "run_scenario", str(SCENARIO), str(parker), "--out", out]
        subprocess.run([*command, f"--jobs={jobs}"], timeout=600, stdout=subprocess.DEVNULL)
        played[jobs] = out, json.loads((out / "summary.json").read_text())
    return played


def record(out: Path, name: str) -> dict:
    return dict(np.load(out / name / "record.npz"))


def test_trajectory_is_the_closed_form_arc(runs):
    out, _ = runs[1]
    arc = record(out, "constant_arc")
    v, w = 0.3, 0.5
    t = arc["t"]
    assert len(t) == 120  # 4 s at 30 Hz, a reply to every frame
    np.testing.assert_allclose(arc["x"], v / w * np.sin(w * t), atol=1e-9)
    np.testing.assert_allclose(arc["y"], v / w * (1 - np.cos(w * t)), atol=1e-9)
    np.testing.assert_allclose(arc["yaw"], w * t, atol=1e-9)
    assert not arc["missed"].any()
    assert (arc["replies"] == 1).all()


def test_result_json_and_plot_are_written(runs):
    out, _ = runs[1]
    result = json.loads((out / "constant_arc" / "result.json").read_text())
    assert result["passed"] is True
    assert math.isclose(result["metrics"]["sim_time"], 4.0)
    assert (out / "constant_arc" / "run.png").stat().st_size > 10_000


def test_parallel_runs_equal_serial_runs(runs):
    """Lockstep makes every simulated quantity and metric of a run identical whether it played
    alone or at the same time as another (two runs of one scenario repeat exactly)."""
    for jobs, (_, summary) in runs.items():
        assert [run["name"] for run in summary["runs"]] == list(NAMES), jobs
    for index, name in enumerate(NAMES):
        (serial_out, serial), (parallel_out, parallel) = runs[1], runs[2]
        serial_record, parallel_record = record(serial_out, name), record(parallel_out, name)
        assert serial_record.keys() == parallel_record.keys()
        for key in serial_record.keys() - {"loop_wall"}:  # not the wall clock
            np.testing.assert_array_equal(serial_record[key], parallel_record[key], err_msg=key)
        serial_metrics, parallel_metrics = (
            without_wall_clock(summary["runs"][index]["metrics"]) for summary in (serial, parallel)
        )
        assert serial_metrics == parallel_metrics, name
    assert serial["runs"][1]["metrics"]["commands"]["max_abs_v"] > 0  # the parker drove


WORLDS = ("rgb", "dumpster", "parking")


@pytest.fixture(scope="module")
def driven(tmp_path_factory) -> Path:
    """Every shipped world's scripted-driver scenario, played in one run_scenario call."""
    out = tmp_path_factory.mktemp("driven")
    scenarios = [str(SCENARIO.parent / f"drive_{world}.yaml") for world in WORLDS]
    command = ["rosrun", "harness", "run_scenario", *scenarios, "--out", str(out), "--jobs=2"]
    subprocess.run(command, check=True, timeout=600, stdout=subprocess.DEVNULL)
    return out


@pytest.mark.parametrize("world", WORLDS)
def test_every_shipped_world_plays_with_the_scripted_driver(world, driven):
    out = driven / f"drive_{world}"
    assert json.loads((out / "result.json").read_text())["passed"] is True
    assert (out / "run.png").stat().st_size > 10_000


def test_stop_when_still_ends_the_run_after_three_still_seconds(tmp_path):
    """`stop_when: still` (sweeps of parking behaviours): a robot commanded still from the
    start ends its 20 s run once the last 3 s of commands were zero, a frame after 3 s."""
    still = tmp_path / "still.yaml"
    still.write_text(
        "name: still\nworld: course\ndriver: {constant: [0.0, 0.0]}\nduration: 20.0\n"
        "stop_when: still\n"
    )
    command = ["rosrun", "harness", "run_scenario", str(still), "--out", str(tmp_path)]
    subprocess.run(command, check=True, timeout=300, stdout=subprocess.DEVNULL)
    metrics = json.loads((tmp_path / "still" / "result.json").read_text())["metrics"]
    assert metrics["sim_time"] == pytest.approx(3.0 + 1 / 30, abs=1e-6)
    assert metrics["steps"] == 91
