"""The simulator node in lockstep with the scripted constant-Twist node (real ROS processes).

Each run gets its own roscore from run_scenario; the recorded trajectory must equal the
closed-form unicycle arc, and two runs of one scenario must be identical.
"""

import json
import math
import subprocess
from pathlib import Path

import numpy as np
import pytest

SCENARIO = Path(__file__).resolve().parents[1] / "worlds" / "scenarios" / "constant_arc.yaml"


def run(out: Path) -> dict:
    subprocess.run(
        ["rosrun", "harness", "run_scenario", str(SCENARIO), "--out", str(out)],
        check=True,
        timeout=300,
    )
    return dict(np.load(out / "constant_arc" / "record.npz"))


@pytest.fixture(scope="module")
def runs(tmp_path_factory) -> tuple[dict, dict, Path]:
    first = tmp_path_factory.mktemp("first")
    return run(first), run(tmp_path_factory.mktemp("second")), first


def test_trajectory_is_the_closed_form_arc(runs):
    record, _, _ = runs
    v, w = 0.3, 0.5
    t = record["t"]
    assert len(t) == 120  # 4 s at 30 Hz, a reply to every frame
    np.testing.assert_allclose(record["x"], v / w * np.sin(w * t), atol=1e-9)
    np.testing.assert_allclose(record["y"], v / w * (1 - np.cos(w * t)), atol=1e-9)
    np.testing.assert_allclose(record["yaw"], w * t, atol=1e-9)
    assert not record["missed"].any()
    assert (record["replies"] == 1).all()


def test_two_runs_are_identical(runs):
    first, second, _ = runs
    assert first.keys() == second.keys()
    for key in first.keys() - {"loop_wall"}:  # every simulated quantity, not the wall clock
        np.testing.assert_array_equal(first[key], second[key], err_msg=key)


def test_result_json_and_plot_are_written(runs):
    _, _, out = runs
    result = json.loads((out / "constant_arc" / "result.json").read_text())
    assert result["passed"] is True
    assert math.isclose(result["metrics"]["sim_time"], 4.0)
    assert (out / "constant_arc" / "run.png").stat().st_size > 10_000


@pytest.mark.parametrize("world", ["rgb", "dumpster", "parking"])
def test_every_shipped_world_plays_with_the_scripted_driver(world, tmp_path):
    scenario = SCENARIO.parent / f"drive_{world}.yaml"
    subprocess.run(
        ["rosrun", "harness", "run_scenario", str(scenario), "--out", str(tmp_path)],
        check=True,
        timeout=300,
        stdout=subprocess.DEVNULL,
    )
    out = tmp_path / f"drive_{world}"
    assert json.loads((out / "result.json").read_text())["passed"] is True
    assert (out / "run.png").stat().st_size > 10_000


def test_parallel_runs_equal_serial_runs(tmp_path):
    """--jobs 2 plays each scenario in its own ROS graph at the same time as another: lockstep
    makes every simulated quantity and metric identical to one-at-a-time runs."""
    parker = tmp_path / "parker_short.yaml"
    parker.write_text(
        "name: parker_short\nworld: parking\nstart: {from: goal_tag, distance: 1.0, off_deg: 10}\n"
        "behaviour: {launch: follow_bot parker.launch}\nduration: 6.0\ngoal: goal_tag\n"
    )
    results = {}
    for jobs in (1, 2):
        out = tmp_path / f"jobs{jobs}"
        command = ["rosrun", "harness", "run_scenario", str(SCENARIO), str(parker), "--out", out]
        subprocess.run([*command, f"--jobs={jobs}"], timeout=600, stdout=subprocess.DEVNULL)
        summary = json.loads((out / "summary.json").read_text())
        assert [run["name"] for run in summary["runs"]] == ["constant_arc", "parker_short"]
        results[jobs] = {
            name: (dict(np.load(out / name / "record.npz")), run["metrics"])
            for name, run in zip(("constant_arc", "parker_short"), summary["runs"], strict=True)
        }
    for name, (serial_record, serial_metrics) in results[1].items():
        parallel_record, parallel_metrics = results[2][name]
        for key in serial_record.keys() - {"loop_wall"}:
            np.testing.assert_array_equal(serial_record[key], parallel_record[key], err_msg=key)
        for wall_clock in ("wall_time", "loop_wall_time"):
            serial_metrics.pop(wall_clock), parallel_metrics.pop(wall_clock)
        assert serial_metrics == parallel_metrics, name
    assert results[1]["parker_short"][1]["commands"]["max_abs_v"] > 0  # the parker drove


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
