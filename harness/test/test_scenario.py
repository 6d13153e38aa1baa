"""Scenario parsing, criteria and the ROS-free simulation stepper."""

import math
import re
from dataclasses import replace

import numpy as np
import pytest

from harness.evaluation import check, metrics, stop_on_sight
from harness.geometry import polyline_length
from harness.scenario import Criterion, ScenarioError
from harness.scenario_file import load_scenarios
from harness.scenario_parse import parse_scenario, scenario_world
from harness.simulation import Perturbations, Simulation, with_line_gaps
from harness.world_file import load_world, resolve_world_path

MINIMAL = {"world": "course", "driver": {"constant": [0.2, 0.0]}, "duration": 2.0}


def with_(**changes):
    data = dict(MINIMAL)
    for key, value in changes.items():
        if value is None:
            data.pop(key)
        else:
            data[key] = value
    return data


def test_minimal_scenario_gets_documented_defaults():
    s = parse_scenario(MINIMAL)
    assert s.world_path == resolve_world_path("course")
    assert s.constant_command == (0.2, 0.0)
    assert (s.rate_hz, s.lockstep, s.stop_when, s.standoff) == (30.0, True, "duration", 0.5)
    assert s.perturbations == Perturbations()
    assert s.camera_transport is None  # the world's


def test_camera_transport_overrides_the_worlds():
    s = parse_scenario(with_(camera_transport={"transport": "compressed", "jpeg_quality": 80}))
    assert (s.camera_transport.name, s.camera_transport.jpeg_quality) == ("compressed", 80)


def test_camera_mounting_moves_the_worlds_camera():
    course = load_world(resolve_world_path("course")).camera
    assert scenario_world(parse_scenario(MINIMAL)).camera == course
    s = parse_scenario(with_(camera_mounting={"height_m": 0.5, "pitch_deg": 10}))
    camera = scenario_world(s).camera
    assert (camera.height_m, camera.pitch) == (0.5, math.radians(10.0))
    assert (camera.x_offset_m, camera.K.tolist()) == (course.x_offset_m, course.K.tolist())


def test_mounting_error_moves_only_the_rendered_camera():
    s = parse_scenario(with_(perturbations={"mounting_error": {"y_offset_m": 0.005, "yaw_deg": 1}}))
    # The robot description and the node are told the world's mounting...
    described = scenario_world(s).camera
    assert (described.y_offset_error_m, described.yaw_error) == (0.0, 0.0)
    # ...while the simulator renders from the camera 5 mm left, turned 1 deg left.
    rendered = Simulation(scenario_world(s), perturbations=s.perturbations).renderer.camera
    assert rendered.y_offset_error_m == 0.005
    assert rendered.yaw_error == pytest.approx(math.radians(1.0))
    assert replace(rendered, y_offset_error_m=0.0, yaw_error=0.0) == described


def test_behaviour_launch_and_args():
    s = parse_scenario(
        with_(driver=None, behaviour={"launch": "follow_bot follower.launch", "args": {"a": 1}})
    )
    assert (s.behaviour.package, s.behaviour.launch_file, s.behaviour.args) == (
        "follow_bot",
        "follower.launch",
        {"a": "1"},
    )


@pytest.mark.parametrize(
    ("data", "words"),
    [
        (with_(duration=None), "duration: missing required field"),
        (with_(duration=-1), "duration: must be > 0"),
        (with_(world="nowhere"), "world: no world file 'nowhere'"),
        (with_(colour=1), "colour: unknown field"),
        (with_(behaviour={"launch": "x y.launch"}), "give exactly one"),
        (with_(driver=None), "give exactly one"),
        (with_(driver=None, behaviour={"launch": "onlyone"}), "behaviour.launch: must be"),
        (with_(perturbations={"dropout": [[2.0, 1.0]]}), "perturbations.dropout[0]: end must"),
        (with_(perturbations={"gain": "bright"}), "perturbations.gain: must be a number"),
        (with_(criteria={"cross_track.rms": {}}), "criteria.cross_track.rms: needs min"),
        (with_(criteria={"x": {"maximum": 1}}), "criteria.x.maximum: unknown field"),
        (with_(stop_when="never"), "stop_when: must be one of"),
        (with_(camera_transport={"transport": "h264"}), "camera_transport.transport: must be"),
        (with_(camera_mounting={"pitch_deg": 90}), "camera_mounting.pitch_deg: must be < 89"),
        (with_(camera_mounting={"roll_deg": 5}), "camera_mounting.roll_deg: unknown field"),
        ("just text", "must be a mapping"),
    ],
)
def test_malformed_scenarios_name_the_field(data, words):
    with pytest.raises(ScenarioError) as error:
        parse_scenario(data)
    assert words in str(error.value)


def test_stop_when_still_waits_as_long_as_the_still_since_bounds_demand():
    """The early end keeps the full run's judgement: still for duration - bound at the end."""
    assert parse_scenario(with_(stop_when="still")).still_stop_s == 3.0
    bounded = with_(
        stop_when="still", duration=45.0,
        criteria={"target.still_since": {"max": 30.0}, "parking.still_since": {"max": 40.0}},
    )  # fmt: skip
    assert parse_scenario(bounded).still_stop_s == 15.0
    late = with_(stop_when="still", duration=25.0, criteria={"target.still_since": {"max": 24.0}})
    assert parse_scenario(late).still_stop_s == 3.0  # never shorter than a behaviour's hold


def test_criteria_bounds_and_missing_values():
    values = {"a": {"b": 0.5}, "flag": True, "none": None}
    assert Criterion("a.b", maximum=1.0).check(values) == (0.5, True)
    assert Criterion("a.b", minimum=0.6).check(values) == (0.5, False)
    assert Criterion("flag", equals=True).check(values) == (True, True)
    assert Criterion("none", maximum=1.0).check(values) == (None, False)
    assert Criterion("absent.key", maximum=1.0).check(values) == (None, False)
    assert Criterion("a.b", maximum=float("nan")).check({"a": {"b": float("nan")}})[1] is False


def test_simulation_withholds_frames_during_dropout_and_ignores_nan_commands():
    world = load_world(resolve_world_path("course"))
    sim = Simulation(world, rate_hz=10.0, start=(0.0, 0.0, 0.0),
                     perturbations=Perturbations(dropouts=((0.2, 0.4),)))  # fmt: skip
    flowing = []
    for k in range(6):
        flowing.append(sim.frames_flowing())
        command = (math.nan, 0.0) if k == 0 else (1.0, 0.0)
        sim.step(command, frame=flowing[-1], replies=1, missed=False)
    assert flowing == [True, True, False, False, True, True]
    run = sim.record.arrays()
    assert math.isnan(run["v"][0]) and run["x"][1] == 0.0  # NaN recorded, robot held still
    assert run["x"][2] == pytest.approx(0.07)  # then 0.7 m/s (the robot's own limit) for 0.1 s


def test_metrics_report_dropout_stop_delay_and_reply_counts():
    world = load_world(resolve_world_path("course"))
    scenario = parse_scenario(
        with_(perturbations={"dropout": [[1.0, 2.0]]}, criteria={"replies.extra": {"equals": 0}})
    )
    t = np.arange(0, 3, 0.1)
    v = np.where((t >= 1.15) & (t < 2.0), 0.0, 0.2)
    run = {
        "t": t, "x": 0.2 * t, "y": np.zeros_like(t), "yaw": np.zeros_like(t),
        "v": v, "w": np.zeros_like(t), "frame": (t < 1.0) | (t >= 2.0),
        "replies": np.ones_like(t, dtype=int), "missed": np.zeros_like(t, dtype=bool),
        # cmd_vel: one per frame, the watchdog's stop at 1.1 s, one stray command at 1.5 s
        "commands": ((t < 1.0) | (t >= 2.0) | np.isclose(t, 1.1) | np.isclose(t, 1.5)).astype(int),
    }  # fmt: skip
    values = metrics(scenario, world, run)
    assert values["dropouts"][0]["stop_delay"] == pytest.approx(0.2)
    assert values["dropouts"][0]["moving_after_stop"] == 0
    assert values["dropouts"][0]["commands_after_stop"] == 1  # cmd_vel, not status replies
    assert values["replies"] == {"frames": 20, "extra": 0, "missing": 0}
    assert "cross_track" in values and "lap" in values
    # The runner's own criteria come first, the file's replies.extra takes their place.
    # margin: the fraction of the bound's size still free (0.7 - 0.2 of 0.7 for max_abs_v).
    assert check(scenario, values) == [
        {"metric": "commands.non_finite", "value": 0, "rule": "== 0", "passed": True,
         "margin": 1.0},
        {"metric": "commands.max_abs_v", "value": 0.2, "rule": "<= 0.7", "passed": True,
         "margin": pytest.approx(5 / 7)},
        {"metric": "commands.max_abs_w", "value": 0.0, "rule": "<= 3.14159", "passed": True,
         "margin": 1.0},
        {"metric": "replies.missing", "value": 0, "rule": "== 0", "passed": True, "margin": 1.0},
        {"metric": "replies.extra", "value": 0, "rule": "== 0", "passed": True, "margin": 1.0},
    ]  # fmt: skip


def test_line_gaps_leave_the_scored_centreline_whole():
    world = load_world(resolve_world_path("course"))
    painted = with_line_gaps(world, ((3.0, 0.3), (10.0, 0.5)))
    lengths = sorted(polyline_length(line.points, False) for line in painted.ground.lines)
    total = polyline_length(world.centreline(), True)
    assert len(lengths) == 2 and not any(line.closed for line in painted.ground.lines)
    assert sum(lengths) == pytest.approx(total - 0.8, abs=0.03)
    assert world.ground.lines[0].closed  # the original, used for scoring, is untouched


def test_stop_on_sight_times_the_stop_from_the_first_glimpse():
    world = load_world(resolve_world_path("red_in_view"))
    red = next(o for o in world.objects if o.name == "red")
    t = np.arange(0.0, 3.0, 0.1)
    yaw = np.minimum(-1.0472 + 0.5 * t, -0.6)  # turning left toward the red ball, then still
    run = {"t": t, "x": np.zeros_like(t), "y": np.zeros_like(t), "yaw": yaw,
           "v": np.zeros_like(t), "w": np.where(t < 1.0, 0.5, 0.0)}  # fmt: skip
    watch = stop_on_sight(world, red, run)
    assert 0.0 < watch["first_in_view"] < 1.0
    assert watch["stop_delay"] == pytest.approx(1.0 - watch["first_in_view"])
    assert watch["moving_in_view_after_stop"] == 0
    never = stop_on_sight(world, red, dict(run, yaw=np.full_like(t, 3.0)))
    assert never["first_in_view"] is None and never["steps_in_view"] == 0


def test_matrix_expands_to_named_runs_over_the_base(tmp_path):
    family = tmp_path / "fam.yaml"
    family.write_text(
        """
labels: {perturbations.gain: "gain{:g}"}
base: {world: course, driver: {constant: [0.2, 0.0]}, duration: 2.0,
       criteria: {lap.complete: {equals: false}}}
matrix:
  - perturbations.gain: [0.5, 1.5]
    duration: {short: 1.0, long: 3.0}
  - variant:
      slow: {driver: {constant: [0.1, 0.0]}, criteria: {steps: {min: 1}}}
"""
    )
    runs = {s.name: s for s in load_scenarios(family)}
    assert list(runs) == [
        "fam/gain0.5_short", "fam/gain0.5_long", "fam/gain1.5_short", "fam/gain1.5_long",
        "fam/slow",
    ]  # fmt: skip
    assert runs["fam/gain1.5_long"].perturbations.gain == 1.5
    assert runs["fam/gain1.5_long"].duration == 3.0
    slow = runs["fam/slow"]
    assert (slow.constant_command, slow.duration) == ((0.1, 0.0), 2.0)
    assert slow.perturbations.gain is None
    assert [c.metric for c in slow.criteria][-2:] == ["lap.complete", "steps"]  # variant adds one
    assert slow.spec["name"] == "fam/slow" and slow.spec["world"] == str(slow.world_path)


@pytest.mark.parametrize(
    "matrix, words",
    [
        ("{perturbations.gain: [0.5]}", "matrix.perturbations.gain: give its values labels"),
        ("[{duration: {a: 1.0}}, {duration: {a: 2.0}}]", "two runs are named 'fam/a'"),
    ],
)
def test_matrix_errors_name_the_axis(tmp_path, matrix, words):
    family = tmp_path / "fam.yaml"
    family.write_text(f"base: {MINIMAL}\nmatrix: {matrix}\n")
    with pytest.raises(ScenarioError, match=re.escape(words)):
        load_scenarios(family)


def test_measured_values_bound_each_member_beside_the_specification(tmp_path):
    family = tmp_path / "fam.yaml"
    family.write_text(
        f"""
base: {MINIMAL}
matrix: {{duration: {{short: 1.0, long: 3.0}}}}
measured:
  floor: {{cross_track.rms: 0.0005, cross_track.max: 0.003}}
  runs:
    short: {{cross_track.rms: 0.0001, cross_track.max: -0.004}}
"""
    )
    runs = {s.name: s for s in load_scenarios(family)}
    rms, worst = runs["fam/short"].criteria[-2:]
    # 3 x 0.1 mm is under the 0.5 mm floor; 3 x |-4 mm| is over the 3 mm one
    assert (rms.metric, rms.maximum, rms.absolute) == ("cross_track.rms", 0.0005, True)
    assert (worst.metric, worst.maximum) == ("cross_track.max", pytest.approx(0.012))
    assert worst.check({"cross_track": {"max": -0.0119}}) == (-0.0119, True)
    assert worst.check({"cross_track": {"max": -0.0121}}) == (-0.0121, False)
    assert worst.describe() == "|value| <= 0.012"
    assert not any(c.absolute for c in runs["fam/long"].criteria)  # not measured: the spec only


@pytest.mark.parametrize(
    "measured, words",
    [
        ("{floor: {a: 1}, runs: {medium: {a: 1}}}", "measured.runs.medium: the family has no run"),
        ("{floor: {a: 1}, runs: {short: {b: 1}}}", "measured.runs.short.b: measured.floor gives"),
        ("{floor: {a: 0}, runs: {}}", "measured.floor.a: must be > 0"),
    ],
)
def test_measured_errors_name_the_member(tmp_path, measured, words):
    family = tmp_path / "fam.yaml"
    matrix = "{duration: {short: 1.0}}"
    family.write_text(f"base: {MINIMAL}\nmatrix: {matrix}\nmeasured: {measured}\n")
    with pytest.raises(ScenarioError, match=re.escape(words)):
        load_scenarios(family)


def test_start_by_intent_is_distance_off_normal_and_bearing():
    tag_x, tag_y = 3.0, 0.0  # goal_tag faces -x (yaw pi) in the parking world
    start = {"from": "goal_tag", "distance": 2.0, "off_deg": 20.0, "bearing_deg": 60.0}
    x, y, yaw = parse_scenario(dict(MINIMAL, world="parking", start=start)).start
    assert math.hypot(x - tag_x, y - tag_y) == pytest.approx(2.0)
    assert math.degrees(math.atan2(y - tag_y, x - tag_x)) == pytest.approx(-160.0)  # pi + 20 deg
    bearing = math.degrees(math.atan2(tag_y - y, tag_x - x) - yaw)
    assert bearing == pytest.approx(60.0)
    with pytest.raises(ScenarioError, match=r"start\.from: world 'parking' has no object 'nope'"):
        parse_scenario(dict(MINIMAL, world="parking", start=dict(start, **{"from": "nope"})))


def test_a_still_since_bound_must_fall_before_the_end():
    # still_since is "still from then to the end": a bound at the end says only that the last
    # command was zero.
    still = {"target": "green", "world": "green_red"}
    at_end = {"target.still_since": {"max": 2.0}}
    with pytest.raises(ScenarioError, match=r"criteria\.target\.still_since: needs a max before"):
        parse_scenario(dict(MINIMAL, **still, criteria=at_end))
    with pytest.raises(ScenarioError, match=r"criteria\.parking\.still_since: needs a max before"):
        parse_scenario(dict(MINIMAL, criteria={"parking.still_since": {"min": 0.0}}))
    before = parse_scenario(dict(MINIMAL, **still, criteria={"target.still_since": {"max": 1.5}}))
    assert before.criteria[-1] == Criterion("target.still_since", maximum=1.5)


def test_lap_progress_counts_only_within_the_cross_track_bound():
    world = load_world(resolve_world_path("course"))
    line = world.centreline()
    closed = np.vstack([line, line[:50]])  # a lap and half a metre
    t = np.arange(len(closed)) * 0.1
    heading = np.arctan2(*np.diff(closed, axis=0, append=closed[1:2]).T[::-1])
    run = {
        "t": t, "x": closed[:, 0], "y": closed[:, 1], "yaw": heading,
        "v": np.full_like(t, 0.2), "w": np.zeros_like(t), "frame": np.ones_like(t, dtype=bool),
        "replies": np.ones_like(t, dtype=int), "missed": np.zeros_like(t, dtype=bool),
    }  # fmt: skip
    normal = np.column_stack([-np.sin(heading), np.cos(heading)])
    off = dict(run, x=closed[:, 0] + 0.1 * normal[:, 0], y=closed[:, 1] + 0.1 * normal[:, 1])
    bounded = parse_scenario(with_(criteria={"cross_track.max": {"max": 0.05}}))
    assert metrics(bounded, world, run)["lap"]["complete"] is True
    assert metrics(bounded, world, off)["lap"]["complete"] is False  # 10 cm off: no progress
    assert metrics(parse_scenario(MINIMAL), world, off)["lap"]["complete"] is True  # 0.25 m
