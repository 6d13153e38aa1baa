"""Randomised sweeps (harness.sweep, a family file's `sweep`) and the report over many runs."""

import json
import re

import numpy as np
import pytest

from harness.geometry import polyline_length
from harness.report import distributions, markdown, summarise, wilson_interval, worst, write_summary
from harness.scenario import ScenarioError
from harness.scenario_file import load_scenarios
from harness.sweep import Distribution, draw, member_name, member_seed, parse_sweep
from harness.validation import ValidationError
from harness.world import WORLDS_DIR
from harness.world_file import load_world

FAMILY = """
base: {world: parking, driver: {constant: [0.2, 0.0]}, duration: 2.0, start: {from: goal_tag}}
sweep:
  seed: 16
  runs: RUNS
  vary:
    start.distance: {uniform: [0.8, 3.0]}
    start.off_deg: {normal: [0.0, 20.0], clip: [-45.0, 45.0]}
    perturbations.gain: {choice: [0.5, 1.0, 1.5]}
"""


def family(tmp_path, runs=5, text=FAMILY):
    path = tmp_path / "fam.yaml"
    path.write_text(text.replace("RUNS", str(runs)))
    return path


def test_member_seeds_come_from_the_sweep_seed_and_index_alone():
    assert member_seed(16, 0) == 3788087768  # numpy SeedSequence([16, 0]): stable across runs
    assert member_seed(16, 1) == 908846979
    assert member_seed(17, 0) != member_seed(16, 0)
    assert member_name("parker_tag_sweep", 7, 42) == "parker_tag_sweep/007_seed42"
    assert member_name("f", 1234, 5) == "f/1234_seed5"


def test_sweep_members_are_named_seeded_and_replayable(tmp_path):
    runs = load_scenarios(family(tmp_path, runs=5))
    again = load_scenarios(family(tmp_path, runs=5))
    more = load_scenarios(family(tmp_path, runs=50))
    assert [s.name for s in runs] == [member_name("fam", i, member_seed(16, i)) for i in range(5)]
    assert runs == again  # same file, same draws
    assert runs == more[:5]  # a member does not depend on how many others there are
    assert [s.parameters for s in runs] == [s.parameters for s in more[:5]]
    first = runs[0]
    assert first.seed == 3788087768 and first.perturbations.noise_seed == 3788087768
    assert first.spec["seed"] == first.seed and first.spec["name"] == first.name
    drawn = first.parameters
    assert list(drawn) == ["start.distance", "start.off_deg", "perturbations.gain"]
    assert first.spec["start"] == {
        "from": "goal_tag",
        "distance": drawn["start.distance"],
        "off_deg": drawn["start.off_deg"],
    }
    assert first.perturbations.gain == drawn["perturbations.gain"]
    # The start pose follows from the drawn distance: the tag centre is at (3, 0).
    x, y, _ = first.start
    assert np.hypot(x - 3.0, y) == pytest.approx(drawn["start.distance"])
    assert drawn["start.distance"] == pytest.approx(1.4579385406316092)  # member 0 of seed 16


def test_the_shipped_sweep_draws_its_documented_ranges():
    runs = load_scenarios(WORLDS_DIR / "sweeps" / "parker_tag_sweep.yaml")
    assert len(runs) == 200 and runs[0].name.startswith("parker_tag_sweep/000_seed")
    d = np.array([[s.parameters[f"start.{k}"] for k in ("distance", "off_deg", "bearing_deg")]
                  for s in runs])  # fmt: skip
    assert np.all(d.min(axis=0) >= [0.8, -45, -60]) and np.all(d.max(axis=0) <= [3.0, 45, 60])
    assert np.all(d.min(axis=0) < [0.85, -42, -56]) and np.all(d.max(axis=0) > [2.95, 42, 56])
    family = load_scenarios(WORLDS_DIR / "scenarios" / "parker_tag.yaml")[0]
    assert all(s.world_path == family.world_path and s.behaviour == family.behaviour for s in runs)
    # Judged by the parker's spec (1 cm / 1 deg, parked), the runner's command limits as usual.
    spec = {
        "parking.standoff_error": (-0.01, 0.01),
        "parking.lateral": (-0.01, 0.01),
        "parking.heading_error_deg": (-1.0, 1.0),
        "parking.still_since": (None, 38.0),
    }
    for s in runs:
        bounds = {c.metric: (c.minimum, c.maximum) for c in s.criteria}
        assert {m: bounds[m] for m in spec} == spec
        family_rest = {c for c in family.criteria if c.metric not in spec}
        assert family_rest <= set(s.criteria)
        assert (s.duration, s.stop_when) == (40.0, "still")


def test_the_harsh_follower_sweep_bounds_each_speed_by_twice_its_clean_lap():
    runs = load_scenarios(WORLDS_DIR / "sweeps" / "follower_harsh_sweep.yaml")
    assert len(runs) >= 100
    course = load_world(WORLDS_DIR / "course.yaml")
    loop = polyline_length(course.centreline(), True)
    speeds = set()
    for s in runs:
        speed = float(s.behaviour.args["max_linear"])
        speeds.add(speed)
        bounds = {c.metric: (c.minimum, c.maximum, c.equals) for c in s.criteria}
        assert bounds["lap.lap_time"][1] == pytest.approx(2.0 * loop / speed, rel=0.002)
        assert s.duration == bounds["lap.lap_time"][1]
        assert bounds["cross_track.rms"][1] == 0.02 and bounds["cross_track.max"][1] == 0.08
        assert bounds["lap.complete"][2] is True
        # The start lies on the line, heading along it.
        x, y, yaw = s.start
        assert np.min(np.hypot(*(course.centreline() - [x, y]).T)) < 0.005
        assert s.parameters["realism.actuation_delay"] == pytest.approx(0.1, abs=0.05)
    assert speeds == {0.15, 0.2, 0.25, 0.3, 0.35, 0.4, 0.45, 0.5}
    # Every member its own room: the profile's draws differ from member to member.
    assert len({s.parameters["realism.shadow_depth"] for s in runs}) == len(runs)


# (parker_sign_harsh_sweep too, but its starts by intent load the sign world per member: ~1 min)
@pytest.mark.parametrize("name", ["beacons_follow_green", "beacons_red_stop", "dumpster"])
def test_the_harsh_behaviour_sweeps_extend_their_families(name):
    runs = load_scenarios(WORLDS_DIR / "sweeps" / f"{name}_harsh_sweep.yaml")
    family = load_scenarios(WORLDS_DIR / "scenarios" / f"{name}.yaml")[0]
    assert len(runs) == 100
    for s in runs:
        assert dict(s.perturbations.realism)["actuation_delay"] == (0.05, 0.15)
        assert (s.world_path, s.behaviour) == (family.world_path, family.behaviour)
        assert {c.metric for c in family.criteria} <= {c.metric for c in s.criteria}


def test_distribution_shapes():
    rng = np.random.default_rng(1)
    n = 20_000
    uniform = np.array([Distribution("uniform", (-2.0, 4.0)).draw(rng) for _ in range(n)])
    assert uniform.min() >= -2.0 and uniform.max() < 4.0
    assert uniform.mean() == pytest.approx(1.0, abs=0.05)
    assert uniform.std() == pytest.approx(6.0 / np.sqrt(12), rel=0.02)
    normal = np.array([Distribution("normal", (1.0, 0.5)).draw(rng) for _ in range(n)])
    assert normal.mean() == pytest.approx(1.0, abs=0.02)
    assert normal.std() == pytest.approx(0.5, rel=0.02)
    clipped = np.array(
        [Distribution("normal", (0.0, 1.0), clip=(-1.0, 1.0)).draw(rng) for _ in range(n)]
    )
    assert clipped.min() == -1.0 and clipped.max() == 1.0
    assert np.mean(clipped == 1.0) == pytest.approx(0.1587, abs=0.01)  # P(z > 1)
    parsed = parse_sweep({"seed": 0, "runs": 1, "vary": {"c": {"choice": ["a", "b", "c"],
                                                               "weights": [1, 0, 3]}}})  # fmt: skip
    picks = [parsed.vary["c"].draw(rng) for _ in range(n)]
    assert picks.count("b") == 0
    assert picks.count("a") / n == pytest.approx(0.25, abs=0.015)
    even = parse_sweep({"seed": 0, "runs": 1, "vary": {"c": {"choice": [{"k": 1}, 2]}}})
    assert even.vary["c"].draw(np.random.default_rng(3)) in ({"k": 1}, 2)
    assert draw(even, 0) == draw(even, 0)


@pytest.mark.parametrize(
    ("vary", "words"),
    [
        ("{a: 1.0}", "sweep.vary.a: give exactly one of uniform, normal, choice"),
        ("{a: {uniform: [2, 1]}}", "sweep.vary.a.uniform: needs low < high"),
        ("{a: {uniform: [1, 2], clip: [0, 1]}}", "sweep.vary.a.clip: unknown field"),
        ("{a: {normal: [0, -1]}}", "sweep.vary.a.normal: sigma must be >= 0"),
        ("{a: {normal: [0, 1], clip: [1, 1]}}", "sweep.vary.a.clip: needs low < high"),
        ("{a: {choice: []}}", "sweep.vary.a.choice: needs at least 1 entries"),
        ("{a: {choice: [1, 2], weights: [1]}}", "sweep.vary.a.weights: must have 2"),
        ("{a: {choice: [1, 2], weights: [0, 0]}}", "sweep.vary.a.weights: must not all be 0"),
        ("{}", "sweep.vary: must name at least one field"),
    ],
)
def test_sweep_errors_name_the_field(tmp_path, vary, words):
    text = f"base: {{world: course, driver: {{constant: [0.1, 0]}}, duration: 1.0}}\n" \
           f"sweep: {{seed: 1, runs: 2, vary: {vary}}}\n"  # fmt: skip
    with pytest.raises(ScenarioError, match=re.escape(words)):
        load_scenarios(family(tmp_path, text=text))


def test_sweep_needs_seed_and_runs_and_no_matrix(tmp_path):
    with pytest.raises(ValidationError, match="sweep.seed: missing required field"):
        parse_sweep({"runs": 2, "vary": {"a": {"uniform": [0, 1]}}})
    with pytest.raises(ValidationError, match="sweep.runs: must be >= 1"):
        parse_sweep({"seed": 1, "runs": 0, "vary": {"a": {"uniform": [0, 1]}}})
    text = FAMILY + "matrix: {duration: {a: 1.0}}\n"
    with pytest.raises(ScenarioError, match="a file holds a matrix or a sweep, not both"):
        load_scenarios(family(tmp_path, text=text))


@pytest.mark.parametrize(
    ("successes", "runs", "low", "high"),
    [
        (0, 10, 0.0, 0.27753),
        (10, 10, 0.72247, 1.0),
        (8, 10, 0.49016, 0.94332),
        (190, 200, 0.91042, 0.97262),
        (0, 0, 0.0, 1.0),
    ],
)
def test_wilson_interval(successes, runs, low, high):
    assert wilson_interval(successes, runs) == pytest.approx((low, high), abs=1e-5)


def result(name, passed, metric, margin, seed=None, error=None):
    row = {"metric": "parking.lateral", "value": metric, "rule": ">= -0.004 and <= 0.004",
           "passed": passed, "margin": margin}  # fmt: skip
    out = {"scenario": name, "seed": seed, "source": "/w/fam.yaml", "passed": passed,
           "parameters": {"start.distance": 1.0 + metric}}  # fmt: skip
    if error:
        return {**out, "error": error}
    values = {"parking": {"lateral": metric, "position_error": abs(metric)}, "ok": True,
              "pose": [1.0, 2.0], "commands": {"missed_replies": 0}, "sim_time": 2.0}  # fmt: skip
    return {**out, "criteria": [row], "metrics": values}


def test_report_quantiles_worst_runs_and_plots(tmp_path):
    results = [
        result("fam/000_seed1", True, 0.001, 0.75, seed=1),
        result("fam/001_seed2", True, 0.003, 0.25, seed=2),
        result("fam/002_seed3", False, 0.005, -0.25, seed=3),
        result("fam/003_seed4", False, 0.0, None, seed=4, error="roscore did not start"),
        result("fam/004_seed5", True, -0.002, 0.5, seed=5),
    ]
    summary = summarise(results)
    assert summary["overall"] == {
        "runs": 5, "passed": 3, "failed": 1, "errors": 1, "success_rate": 0.6,
        "success_interval_95": list(wilson_interval(3, 5)),
        "failures_by_criterion": {"parking.lateral": {"runs": 1, "only": 1}},
    }  # fmt: skip
    lateral = distributions(summary["runs"])["parking.lateral"]
    assert lateral["count"] == 4 and lateral["mean"] == pytest.approx(0.00175)
    quantiles = (lateral["q00"], lateral["q50"], lateral["q100"])
    assert quantiles == pytest.approx((-0.002, 0.002, 0.005))
    assert lateral["q25"] == pytest.approx(0.00025)  # numpy's linear interpolation
    assert set(summary["distributions"]) == {
        "parking.lateral",
        "parking.position_error",
        "pose.0",
        "pose.1",
        "commands.missed_replies",
        "sim_time",
    }  # fmt: skip  (no booleans)
    assert [r["name"] for r in worst(summary["runs"], 4)] == [
        "fam/003_seed4", "fam/002_seed3", "fam/001_seed2", "fam/004_seed5",
    ]  # fmt: skip
    text = markdown(summary, {"parking.lateral": "plots/parking.lateral.png"})
    assert "3 of 5 passed (1 failed, 1 could not run): success rate 0.600" in text
    assert "| parking.lateral | 1 | 1 |" in text
    assert "rosrun harness run_scenario /w/fam.yaml --select fam/002_seed3" in text
    assert "| [parking.lateral](plots/parking.lateral.png) | 4 | 0.00175 | -0.002 |" in text

    write_summary(tmp_path, results)
    written = json.loads((tmp_path / "summary.json").read_text())
    assert written["worst"][:2] == ["fam/003_seed4", "fam/002_seed3"]
    assert (tmp_path / "plots" / "parking.lateral.png").stat().st_size > 5_000
    assert (tmp_path / "plots" / "parameters.png").stat().st_size > 5_000
    assert "![drawn values](plots/parameters.png)" in (tmp_path / "report.md").read_text()
