"""run_scenario's command lines for the node under test. It gives the world's camera mounting to
the robot description only: the node finds its camera in tf, as on a robot, and is never told the
mounting as ~params. In lockstep it tells the node the simulator's per-step wall tolerance."""

from dataclasses import replace
from pathlib import Path

from harness.runs import behaviour_command, description_command
from harness.scenario_file import load_scenarios
from harness.world_file import load_world

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
    assert command[4:] == [
        "camera_height:=0.3", "camera_pitch_deg:=20.0", "camera_x_offset:=0.0",
        "camera_frame:=camera_rgb_optical_frame",
    ]  # fmt: skip
    assert description_command(load_world(WORLDS / "parking.yaml").camera)[5] == (
        "camera_pitch_deg:=0.0"
    )
    moved = replace(course, height_m=0.5, pitch=0.0)
    assert description_command(moved)[4:6] == ["camera_height:=0.5", "camera_pitch_deg:=0.0"]


def test_lockstep_gives_the_c_plus_plus_behaviours_the_reply_timeout_as_wall_watchdog():
    by_name = {s.name: s for path in SCENARIOS.glob("*.yaml") for s in load_scenarios(path)}
    for name in ("follower/lap_default", "parker_tag/d2_off20_b60", "beacons_red_stop/plain"):
        scenario = by_name[name]
        assert scenario.lockstep and scenario.reply_timeout == 10.0, name
        assert "wall_watchdog_timeout:=10.0" in behaviour_command(scenario), name
        realtime = replace(scenario, lockstep=False)
        assert not any("wall_watchdog" in a for a in behaviour_command(realtime)), name
    # The Python lab nodes have no wall-clock watchdog, and their launch no such arg.
    lab = by_name["lab_red_stop/plain"]
    assert lab.behaviour.launch_file == "lab.launch"
    assert not any("wall_watchdog" in a for a in behaviour_command(lab)), lab.name
