"""The scenario criteria catch a regression: each run of worlds/scenarios/regression_guard.yaml
(the tag parker, the sign parker, the follower) passes its windows, and the same run made worse
by a known error, each way, fails on exactly the window that bounds that error and on the side
the error pushes it. The errors: told a standoff 5 mm longer or shorter (launch args), a camera
5 mm left or right of where the robot description says (parkers: lateral; follower: mean
cross-track), a camera turned 0.5 deg left or right (parkers: heading) or 1 deg (follower:
mean cross-track). `make test` plays the tag parker's baseline and its 5 mm long fault; the
rest is `full`."""

import json
import subprocess
from pathlib import Path

import pytest
import yaml

from harness.scenario_file import load_scenarios, merged
from harness.testing import REPO

GUARD = REPO / "worlds" / "scenarios" / "regression_guard.yaml"
STANDOFF = 0.5  # the parker's default ~standoff, m


def standoff(metres: float) -> dict:
    return {"behaviour": {"args": {"standoff": metres}}}


def mounting_error(**error: float) -> dict:
    return {"perturbations": {"mounting_error": error}}


# fault name: (guard run, what is made worse, the criterion it must fail, the side: +1 above
# the window's max, -1 below its min). The side follows the geometry: a standoff told longer
# parks further out (+); a camera left of its described place makes the node put the line or
# the marker's normal 5 mm further left than it is, so the base ends 5 mm right of it.
FAULTS = {
    "tag_long": ("parker_tag", standoff(STANDOFF + 0.005), "parking.standoff_error", +1),
    "tag_short": ("parker_tag", standoff(STANDOFF - 0.005), "parking.standoff_error", -1),
    "tag_camera_left": ("parker_tag", mounting_error(y_offset_m=0.005), "parking.lateral", +1),
    "tag_camera_right": ("parker_tag", mounting_error(y_offset_m=-0.005), "parking.lateral", -1),
    "tag_camera_turned_left": (
        "parker_tag", mounting_error(yaw_deg=0.5), "parking.heading_error_deg", -1
    ),
    "tag_camera_turned_right": (
        "parker_tag", mounting_error(yaw_deg=-0.5), "parking.heading_error_deg", +1
    ),
    "sign_long": ("parker_sign", standoff(STANDOFF + 0.005), "parking.standoff_error", +1),
    "sign_short": ("parker_sign", standoff(STANDOFF - 0.005), "parking.standoff_error", -1),
    "sign_camera_left": ("parker_sign", mounting_error(y_offset_m=0.005), "parking.lateral", +1),
    "sign_camera_right": (
        "parker_sign", mounting_error(y_offset_m=-0.005), "parking.lateral", -1
    ),
    "sign_camera_turned_left": (
        "parker_sign", mounting_error(yaw_deg=0.5), "parking.heading_error_deg", -1
    ),
    "sign_camera_turned_right": (
        "parker_sign", mounting_error(yaw_deg=-0.5), "parking.heading_error_deg", +1
    ),
    "line_camera_left": ("follower", mounting_error(y_offset_m=0.005), "cross_track.mean_left", -1),
    "line_camera_right": (
        "follower", mounting_error(y_offset_m=-0.005), "cross_track.mean_left", +1
    ),
    "line_camera_turned_left": (
        "follower", mounting_error(yaw_deg=1.0), "cross_track.mean_left", -1
    ),
    "line_camera_turned_right": (
        "follower", mounting_error(yaw_deg=-1.0), "cross_track.mean_left", +1
    ),
}  # fmt: skip
QUICK = {"parker_tag", "tag_long"}


def run_specs() -> dict[str, dict]:
    """Every guard run and every fault, as a scenario spec named after it."""
    guard = {s.name.split("/")[-1]: s.spec for s in load_scenarios(GUARD)}
    specs = {name: merged(spec, {"name": name}) for name, spec in guard.items()}
    for fault, (run, worse, _, _) in FAULTS.items():
        specs[fault] = merged(guard[run], {**worse, "name": fault})
    return specs


def play(names: list[str], out: Path) -> dict[str, dict]:
    """Plays the named runs in one run_scenario call (2 at once); their result.json."""
    specs = run_specs()
    paths = []
    for name in names:
        paths.append(out / f"{name}.yaml")
        paths[-1].write_text(yaml.safe_dump(specs[name]))
    command = ["rosrun", "harness", "run_scenario", *map(str, paths), "--out", str(out)]
    subprocess.run([*command, "--jobs", "2"], timeout=3600, stdout=subprocess.DEVNULL)
    return {name: json.loads((out / name / "result.json").read_text()) for name in names}


def failures(results: dict[str, dict]) -> list[str]:
    """What differs from the guard's claim: a baseline that fails, a fault that fails anything
    but its criterion, or fails it on the other side."""
    wrong, specs = [], run_specs()
    for name, result in results.items():
        failed = {row["metric"]: row for row in result["criteria"] if not row["passed"]}
        if name not in FAULTS:
            wrong += [f"{name}: baseline fails {sorted(failed)}"] if failed else []
            continue
        _, _, metric, side = FAULTS[name]
        if set(failed) != {metric}:
            wrong.append(f"{name}: fails {sorted(failed)}, not just {metric}")
            continue
        value, window = failed[metric]["value"], specs[name]["criteria"][metric]
        if not (value > window["max"] if side > 0 else value < window["min"]):
            wrong.append(f"{name}: {metric} = {value} is out on the other side")
    return wrong


def test_tag_parker_five_millimetres_long_fails_the_standoff_window(tmp_path):
    assert failures(play(sorted(QUICK), tmp_path)) == []


@pytest.mark.full
def test_every_fault_fails_exactly_its_window(tmp_path):
    names = [name for name in run_specs() if name not in QUICK]
    assert failures(play(names, tmp_path)) == []
