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
SCENARIOS = sorted(
    path
    for pattern in ("follower_*.yaml", "dumpster_*.yaml", "beacons_*.yaml", "parker_*.yaml")
    for path in SCENARIO_DIR.glob(pattern)
)


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
