"""run_scenario gives the world's camera mounting to the robot description only: the node under
test finds its camera in tf, as on a robot, and is never told the mounting as ~params."""

from pathlib import Path

from harness.run_scenario import behaviour_command, description_command
from harness.scenario import load_scenarios

SCENARIOS = Path(__file__).resolve().parents[2] / "worlds" / "scenarios"


def test_the_node_gets_no_mounting_params():
    for path in sorted(SCENARIOS.glob("*.yaml")):
        for scenario in load_scenarios(path):
            command = " ".join(behaviour_command(scenario))
            for name in ("camera_height", "camera_pitch_deg", "camera_x_offset", "mounting"):
                assert name not in command, (scenario.name, command)


def test_the_description_carries_the_world():
    scenario = load_scenarios(SCENARIOS / "follower.yaml")[0]
    command = description_command(scenario)
    assert command[:4] == ["roslaunch", "--wait", "follow_bot", "robot_description.launch"]
    assert command[-1] == f"world:={scenario.world_path}"
