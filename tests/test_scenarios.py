"""The behaviours in the closed loop, each judged by its scenario's own criteria.

Every follower_*, dumpster_*, beacons_* and parker_* scenario in worlds/scenarios is played by
run_scenario: all the selected ones in one call with --jobs (each in its own ROS graph: its own
roscore, the behaviour's launch file, the simulator in lockstep), then one test per scenario reads
its result.json and fails with every unmet criterion listed.
"""

import json
import os
import subprocess
from pathlib import Path

import pytest

SCENARIO_DIR = Path(__file__).resolve().parents[1] / "worlds" / "scenarios"
# How many scenarios each family holds: a glob that finds fewer (a rename, a bad pattern) fails
# test_every_family_has_its_scenarios instead of silently running nothing.
FAMILY_SIZES = {"follower": 13, "dumpster": 9, "beacons": 9, "parker": 27}
FAMILIES = {family: sorted(SCENARIO_DIR.glob(f"{family}_*.yaml")) for family in FAMILY_SIZES}
SCENARIOS = [path for paths in FAMILIES.values() for path in paths]
JOBS = int(os.environ.get("SCENARIO_JOBS", os.cpu_count() or 1))


def test_every_family_has_its_scenarios():
    assert {family: len(paths) for family, paths in FAMILIES.items()} == FAMILY_SIZES


@pytest.fixture(scope="session")
def results(request, tmp_path_factory) -> Path:
    """Plays every scenario this session selected in one run_scenario call; its output folder."""
    selected = sorted(
        {
            item.callspec.params["scenario"]
            for item in request.session.items
            if getattr(item, "originalname", "") == "test_behaviour_scenario"
        }
    )
    out = tmp_path_factory.mktemp("scenarios")
    subprocess.run(
        ["rosrun", "harness", "run_scenario", *map(str, selected), f"--jobs={JOBS}", "--out", out],
        timeout=900 * len(selected) / JOBS,
        stdout=subprocess.DEVNULL,
    )  # its exit code only repeats what the result.json files say
    return out


@pytest.mark.parametrize("scenario", SCENARIOS, ids=[p.stem for p in SCENARIOS])
def test_behaviour_scenario(scenario, results):
    result = json.loads((results / scenario.stem / "result.json").read_text())
    failed = [f"{c['metric']} = {c['value']} (want {c['rule']})" for c in result["criteria"]
              if not c["passed"]]  # fmt: skip
    assert not failed, f"{scenario.stem}: " + "; ".join(failed)
    # Every run, whatever its own criteria: no command beyond the limits, none non-finite.
    commands = result["metrics"]["commands"]
    assert commands["non_finite"] == 0
    assert commands["max_abs_v"] <= 0.7 + 1e-9
    assert commands["max_abs_w"] <= 3.14159266
