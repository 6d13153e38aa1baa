"""The scenario criteria catch a regression: a parker run made deliberately worse through its
launch args (told a standoff 5 mm longer, it parks ~8 mm long, as a parker whose stopping
tolerance had doubled might) must fail on exactly the criterion that bounds it, while the same
run unchanged passes (tests/test_scenarios.py). The old 1 cm bound let this through."""

import json
import subprocess
from pathlib import Path

import yaml

from harness.scenario import load_scenarios, merged

FAMILY = Path(__file__).resolve().parents[1] / "worlds" / "scenarios" / "parker_tag.yaml"
RUN = "parker_tag/d1_off10_b0"


def test_parking_five_millimetres_long_fails_the_standoff_bound(tmp_path):
    (scenario,) = [s for s in load_scenarios(FAMILY) if s.name == RUN]
    worse = merged(scenario.spec, {"name": "worse", "behaviour": {"args": {"standoff": 0.505}}})
    path = tmp_path / "worse.yaml"
    path.write_text(yaml.safe_dump(worse))
    subprocess.run(
        ["rosrun", "harness", "run_scenario", str(path), "--out", str(tmp_path)],
        timeout=900,
        stdout=subprocess.DEVNULL,
    )
    result = json.loads((tmp_path / "worse" / "result.json").read_text())
    failed = {row["metric"] for row in result["criteria"] if not row["passed"]}
    assert failed == {"parking.standoff_error"}
    assert 0.006 < result["metrics"]["parking"]["standoff_error"] < 0.01  # inside the old bound
