"""run_scenario gives the world's camera mounting to the robot description only: the node under
test finds its camera in tf, as on a robot, and is never told the mounting as ~params."""

from dataclasses import replace
from pathlib import Path

from harness.run_scenario import behaviour_command, description_command
from harness.scenario import load_scenarios
from harness.world import load_world

WORLDS = Path(__file__).resolve().parents[2] / "worlds"
SCENARIOS = WORLDS / "scenarios"


def test_the_node_gets_no_mounting_params():
    for path in sorted(SCENARIOS.glob("*.yaml")):
        for scenario in load_scenarios(path):
            command = " ".join(behaviour_command(scenario))
            for name in ("camera_height", "camera_pitch_deg", "camera_x_offset", "mounting"):
                assert name not in command, (scenario.name, command)


def test_the_description_carries_the_runs_camera():
    course = load_world(WORLDS / "course.yaml").camera
    command = description_command(course)
    assert command[:4] == ["roslaunch", "--wait", "follow_bot", "robot_description.launch"]
    assert command[4:] == ["camera_height:=0.3", "camera_pitch_deg:=20.0", "camera_x_offset:=0.0"]
    assert description_command(load_world(WORLDS / "parking.yaml").camera)[5] == (
        "camera_pitch_deg:=0.0"
    )
    moved = replace(course, height_m=0.5, pitch=0.0)
    assert description_command(moved)[4:6] == ["camera_height:=0.5", "camera_pitch_deg:=0.0"]
