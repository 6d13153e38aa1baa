"""What the behaviours show in rviz.

The rviz configs (follow_bot/rviz/*.rviz, one per behaviour) parse as YAML and display only topics
their node has: its ~markers and ~debug_image among the topics its --help lists as out, the
camera image among those it lists as in, each named as the node's launch file remaps it.

In the closed loop (worlds/scenarios/rviz_markers.yaml, played by run_scenario --markers), each
behaviour's ~markers, placed on the floor by the simulator's true pose at their frame, agree with
the world they were rendered from: the follower's remembered path and band sightings lie on the
course's painted centreline, the beacon chaser's ball on the green ball with the range to it, the
parker's marker on the goal tag with the parking goal standoff in front of it.
"""

import math
import re
import subprocess
from pathlib import Path

import numpy as np
import pytest
import roslaunch.config
import yaml

from follow_bot.cfg import ParkerConfig
from harness.marker_map import load_frames, to_world
from harness.testing import REPO
from harness.world_file import load_world, resolve_world_path

RVIZ = sorted((REPO / "follow_bot" / "rviz").glob("*.rviz"))
BEHAVIOURS = ("follower", "beacon_chaser", "parker")
TOPIC_KEYS = ("Topic", "Marker Topic", "Image Topic")

# Bounds: the worst measured over a run (2026-11-27, lockstep), times 2-3, rounded up.
PATH_OFF_LINE_M = 0.002  # measured 0.5 mm: path points and sightings to the painted centreline
BALL_CENTRE_M = 0.04  # measured 1.8 cm, the ball 1.4-4 m away
BALL_RANGE_M = 0.05  # measured 2.1 cm (the text's 5 mm rounding included)
TAG_CENTRE_M = 0.004  # measured 1.5 mm, the tag 0.5-1.5 m away
PARKING_GOAL_M = 0.025  # measured 1.0 cm
TAG_NORMAL_DEG = 3.0  # measured 1.1 deg (1.2 m away)
STANDOFF_M = ParkerConfig.defaults["standoff"]  # the scenario leaves ~standoff at its default


def displayed_topics(config: dict) -> list[str]:
    return [
        display[key]
        for display in config["Visualization Manager"]["Displays"]
        for key in TOPIC_KEYS
        if key in display
    ]


def node_topics(node: str) -> dict[str, set[str]]:
    """The node's topics by direction (in, out), global names as its launch file remaps them."""
    launch = REPO / "follow_bot" / "launch" / f"{node}.launch"
    config = roslaunch.config.load_config_default([str(launch)], None, verbose=False)
    (spec,) = [n for n in config.nodes if n.name == node]
    remaps = dict(spec.remap_args)
    namespace = spec.namespace.rstrip("/") + "/"
    help_text = subprocess.run(
        ["rosrun", "follow_bot", node, "--help"], capture_output=True, text=True, check=True
    ).stdout
    topics: dict[str, set[str]] = {"in": set(), "out": set()}
    for direction, name in re.findall(r"^  (in|out) +(\S+)", help_text, re.M):
        name = remaps.get(name, name)
        if name.startswith("~"):
            name = f"{namespace}{node}/{name[1:]}"
        elif not name.startswith("/"):
            name = namespace + name
        topics[direction].add(name)
    return topics


def test_every_behaviour_has_an_rviz_config():
    assert [p.stem for p in RVIZ] == sorted(BEHAVIOURS)


@pytest.mark.parametrize("path", RVIZ, ids=lambda p: p.name)
def test_an_rviz_config_displays_only_topics_of_its_node(path):
    config = yaml.safe_load(path.read_text())
    topics = node_topics(path.stem)
    shown = displayed_topics(config)
    assert f"/{path.stem}/markers" in shown
    for topic in shown:
        assert topic in topics["in"] | topics["out"], (topic, topics)
        if topic.endswith(("/markers", "/debug_image")):
            assert topic in topics["out"], topic
    classes = {d["Class"] for d in config["Visualization Manager"]["Displays"]}
    assert {"rviz/TF", "rviz/MarkerArray", "rviz/Image"} <= classes
    assert config["Visualization Manager"]["Global Options"]["Fixed Frame"] in ("odom", "base_link")


@pytest.fixture(scope="module")
def runs(tmp_path_factory) -> Path:
    """The rviz_markers runs played with their markers recorded; the output folder."""
    out = tmp_path_factory.mktemp("rviz_markers")
    scenarios = REPO / "worlds" / "scenarios" / "rviz_markers.yaml"
    subprocess.run(
        ["rosrun", "harness", "run_scenario", str(scenarios), "--markers", "--out", str(out)],
        check=True, stdout=subprocess.DEVNULL,
    )  # fmt: skip
    return out / "rviz_markers"


def placed(runs: Path, name: str) -> list[dict]:
    """The run's marker frames on the floor, by the simulator's pose; every frame is there."""
    run = dict(np.load(runs / name / "record.npz"))
    frames = to_world(load_frames(runs / name / "markers.json"), run)
    assert len(frames) >= 0.9 * run["frame"].sum(), "the recorder missed frames"
    return frames


def markers(frames: list[dict], ns: str, kind: str) -> list[tuple[dict, dict]]:
    return [(f, m) for f in frames for m in f["markers"] if m["ns"] == ns and m["type"] == kind]


def distance_to_polyline(point: np.ndarray, line: np.ndarray) -> float:
    start, end = line[:-1], line[1:]
    along = end - start
    t = np.clip(((point - start) * along).sum(1) / (along * along).sum(1), 0.0, 1.0)
    return float(np.min(np.linalg.norm(start + t[:, None] * along - point, axis=1)))


@pytest.mark.full
def test_the_followers_path_and_sightings_lie_on_the_painted_line(runs):
    frames = placed(runs, "follower")
    line = load_world(resolve_world_path("course")).centreline()
    line = np.vstack([line, line[:1]])  # closed
    for ns, kind in (("path", "LINE_STRIP"), ("sightings", "SPHERE_LIST")):
        points = [p[:2] for _, m in markers(frames, ns, kind) for p in m["points"]]
        assert len(points) > 100, ns
        worst = max(distance_to_polyline(np.array(p), line) for p in points)
        assert worst <= PATH_OFF_LINE_M, (ns, worst)


@pytest.mark.full
def test_the_beacon_chasers_ball_and_range_match_the_green_ball(runs):
    frames = placed(runs, "beacon_chaser")
    (ball,) = [o for o in load_world(resolve_world_path("green_red")).objects if o.name == "green"]
    spheres = markers(frames, "beacons", "SPHERE")
    assert len(spheres) > 100
    worst = max(np.linalg.norm(np.subtract(m["position"], ball.position)) for _, m in spheres)
    assert worst <= BALL_CENTRE_M
    errors = []
    for frame, text in markers(frames, "ranges", "TEXT_VIEW_FACING"):
        colour, range_m, unit = text["text"].split()
        assert (colour, unit) == ("green", "m")
        x, y, _ = frame["pose"]
        truth = math.hypot(ball.position[0] - x, ball.position[1] - y) - ball.radius
        errors.append(abs(float(range_m) - truth))
    assert len(errors) == len(spheres)
    assert max(errors) <= BALL_RANGE_M


@pytest.mark.full
def test_the_parkers_marker_and_goal_match_the_goal_tag(runs):
    frames = placed(runs, "parker")
    (tag,) = [o for o in load_world(resolve_world_path("parking")).objects if o.name == "goal_tag"]
    x, y, z, facing = tag.pose  # facing: the yaw of the tag's outward normal
    centres = markers(frames, "marker", "SPHERE")
    assert len(centres) > 100
    assert max(np.linalg.norm(np.subtract(m["position"], (x, y, z))) for _, m in centres) <= (
        TAG_CENTRE_M
    )
    for _, normal in markers(frames, "marker", "ARROW"):
        (x0, y0, _), (x1, y1, _) = normal["points"]
        off = math.remainder(math.atan2(y1 - y0, x1 - x0) - facing, math.tau)
        assert abs(math.degrees(off)) <= TAG_NORMAL_DEG
    goal = np.array([x + STANDOFF_M * math.cos(facing), y + STANDOFF_M * math.sin(facing)])
    goals = markers(frames, "goal", "ARROW")
    assert len(goals) == len(centres)
    assert max(np.linalg.norm(np.subtract(m["points"][0][:2], goal)) for _, m in goals) <= (
        PARKING_GOAL_M
    )
