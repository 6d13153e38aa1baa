"""run_scenario tells the node under test where the world's camera is: every behaviour node has
the same default mounting, the worlds' cameras differ (course pitched 20 deg, the others level)."""

from dataclasses import replace
from pathlib import Path

from harness.run_scenario import description_command, mounting_args
from harness.world import load_world

WORLDS = Path(__file__).resolve().parents[2] / "worlds"


def test_course_camera_is_pitched_twenty_degrees():
    camera = load_world(WORLDS / "course.yaml").camera
    assert mounting_args(camera) == {
        "camera_height": 0.30,
        "camera_pitch_deg": 20.0,
        "camera_x_offset": 0.0,
    }


def test_parking_camera_is_level():
    camera = load_world(WORLDS / "parking.yaml").camera
    assert mounting_args(camera)["camera_pitch_deg"] == 0.0


def test_robot_description_gets_the_runs_mounting():
    camera = replace(load_world(WORLDS / "course.yaml").camera, height_m=0.5, pitch=0.0)
    assert description_command(camera)[-3:] == [
        "camera_height:=0.5",
        "camera_pitch_deg:=0.0",
        "camera_x_offset:=0.0",
    ]
