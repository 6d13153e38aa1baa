"""The behaviours in the closed loop, each judged by its scenario's own criteria.

Every follower_*, dumpster_*, beacons_* and parker_* scenario in worlds/scenarios is played by
run_scenario (its own roscore, the behaviour's launch file, the simulator in lockstep); the test
reads result.json and fails with every unmet criterion listed.
"""

import json
import subprocess
from pathlib import Path

import pytest

SCENARIO_DIR = Path(__file__).resolve().parents[1] / "worlds" / "scenarios"
# How many scenarios each family holds: a glob that finds fewer (a rename, a bad pattern) fails
# test_every_family_has_its_scenarios instead of silently running nothing.
FAMILY_SIZES = {"follower": 13, "dumpster": 9, "beacons": 9, "parker": 27}
FAMILIES = {family: sorted(SCENARIO_DIR.glob(f"{family}_*.yaml")) for family in FAMILY_SIZES}
SCENARIOS = [path for paths in FAMILIES.values() for path in paths]


def test_every_family_has_its_scenarios():
    assert {family: len(paths) for family, paths in FAMILIES.items()} == FAMILY_SIZES


@pytest.mark.parametrize("scenario", SCENARIOS, ids=[p.stem for p in SCENARIOS])
def test_behaviour_scenario(scenario, tmp_path):
    subprocess.run(
        ["rosrun", "harness", "run_scenario", str(scenario), "--out", str(tmp_path)],
        timeout=600,
        stdout=subprocess.DEVNULL,
    )  # its exit code only repeats what result.json says
    result = json.loads((tmp_path / scenario.stem / "result.json").read_text())
    failed = [f"{c['metric']} = {c['value']} (want {c['rule']})" for c in result["criteria"]
              if not c["passed"]]  # fmt: skip
    assert not failed, f"{scenario.stem}: " + "; ".join(failed)
    # Every run, whatever its own criteria: no command beyond the limits, none non-finite.
    commands = result["metrics"]["commands"]
    assert commands["non_finite"] == 0
    assert commands["max_abs_v"] <= 0.7 + 1e-9
    assert commands["max_abs_w"] <= 3.14159266
