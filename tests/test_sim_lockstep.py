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
