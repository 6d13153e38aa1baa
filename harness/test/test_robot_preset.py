"""A scenario's `robot`: the simulator plays the preset's camera and base limits (the figures
here are the TurtleBot3 Waffle Pi's published ones: its raspicam launch's 640x480 JPEG at 15 Hz
on raspicam_node/image, frame camera, 0.26 m/s and 1.82 rad/s), and the runner holds every
command to them; generic keeps the world's own camera."""

import math

import pytest

from harness.robot_preset import camera_topics, robot_world
from harness.scenario import ScenarioError
from harness.scenario_parse import parse_scenario, scenario_world
from harness.world_file import load_world, resolve_world_path

LAP = {"world": "course", "behaviour": {"launch": "follow_bot follower.launch"}, "duration": 2.0}


def test_the_waffle_pi_camera_and_limits_replace_the_worlds():
    scenario = parse_scenario({**LAP, "robot": "turtlebot3_waffle_pi"})
    world = scenario_world(scenario)
    camera = world.camera
    assert (camera.width, camera.height, camera.frame_id) == (640, 480, "camera")
    assert camera.pitch == 0.0 and camera.height_m == pytest.approx(0.102)
    assert world.camera_transport.name == "compressed"
    assert (world.robot.max_v, world.robot.max_w) == (0.26, 1.82)
    assert scenario.rate_hz == 15.0
    bounds = {c.metric: c.maximum for c in scenario.criteria}
    assert bounds["commands.max_abs_v"] == 0.26 and bounds["commands.max_abs_w"] == 1.82
    # turtlebot3_navigation's dwa_local_planner_params_waffle_pi.yaml
    assert bounds["commands.max_abs_dv_dt"] == pytest.approx(2.5, rel=1e-5)
    assert bounds["commands.max_abs_dw_dt"] == pytest.approx(3.2, rel=1e-5)
    assert camera_topics("turtlebot3_waffle_pi") == ("raspicam_node/image",
                                                     "raspicam_node/camera_info")  # fmt: skip


def test_generic_is_the_worlds_own_camera_on_the_lectures_topics():
    course = load_world(resolve_world_path("course"))
    assert robot_world(course, "generic") == course
    assert camera_topics(None) == ("camera/rgb/image_raw", "camera/rgb/camera_info")
    scenario = parse_scenario({**LAP, "robot": "generic"})
    assert scenario.rate_hz == 30.0 and scenario_world(scenario).camera.pitch == math.radians(20)


def test_a_scenario_mounting_moves_the_presets_camera():
    scenario = parse_scenario({**LAP, "robot": "turtlebot3_burger",
                               "camera_mounting": {"pitch_deg": 25.0}})  # fmt: skip
    camera = scenario_world(scenario).camera
    assert camera.pitch == pytest.approx(math.radians(25.0)) and camera.width == 320


def test_an_unknown_robot_is_refused_by_name():
    with pytest.raises(ScenarioError, match="robot: unknown robot 'turtlebot4': one of generic"):
        parse_scenario({**LAP, "robot": "turtlebot4"})
