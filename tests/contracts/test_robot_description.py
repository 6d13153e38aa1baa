"""The robot description: a launch that runs a world publishes the URDF of that
world's camera mounting through robot_state_publisher, and the simulator publishes odom and
odom -> base_footprint as a base driver does. In a running course.launch the tf tree must give
base_footprint <- camera_rgb_optical_frame exactly as the world's camera is mounted (the pose the
renderer draws from), and base_link <- camera_rgb_optical_frame that minus base_link's height.

Each case starts a roscore and the launch, then reads tf from a child process (this file with
--client, tests/README.md), which prints what it saw as JSON.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

from harness.processes import launch_with_client
from harness.robot_description import BASE_LINK_HEIGHT, urdf
from harness.world_file import load_world, resolve_world_path

OPTICAL = "camera_rgb_optical_frame"


def client() -> None:
    import rospy
    import tf2_ros
    from nav_msgs.msg import Odometry

    rospy.init_node("description_probe")
    buffer = tf2_ros.Buffer()
    tf2_ros.TransformListener(buffer)
    seen = {}
    for parent in ("base_footprint", "base_link", "odom"):
        t = buffer.lookup_transform(parent, OPTICAL, rospy.Time(0), rospy.Duration(30.0)).transform
        seen[parent] = {
            "xyz": [t.translation.x, t.translation.y, t.translation.z],
            "xyzw": [t.rotation.x, t.rotation.y, t.rotation.z, t.rotation.w],
        }
    odom = rospy.wait_for_message("odom", Odometry, timeout=30.0)
    seen["odom_frames"] = [odom.header.frame_id, odom.child_frame_id]
    print(json.dumps(seen))


def rotation(xyzw) -> np.ndarray:
    x, y, z, w = xyzw
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])  # fmt: skip


def mounted_world(tmp_path: Path) -> Path:
    """The course with the camera 0.42 m up, 12 deg down and 6 cm ahead of the base centre."""
    data = yaml.safe_load(resolve_world_path("course").read_text())
    data["camera"] = {"height_m": 0.42, "pitch_deg": 12.0, "x_offset_m": 0.06}
    path = tmp_path / "mounted.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


@pytest.mark.parametrize("which", ["course", "mounted"])
def test_tf_from_the_launch_equals_the_worlds_camera(which, tmp_path):
    world_path = resolve_world_path("course") if which == "course" else mounted_world(tmp_path)
    camera = load_world(world_path).camera
    seen = launch_with_client(
        ["harness", "course.launch", f"world:={world_path}", "duration:=0"],
        [sys.executable, __file__, "--client"], timeout=90,
    )  # fmt: skip
    on_floor = seen["base_footprint"]
    expected = [camera.x_offset_m, 0.0, camera.height_m]
    assert on_floor["xyz"] == pytest.approx(expected, abs=1e-6)
    # Columns: the optical axes in the base frame, the renderer's own (harness.camera).
    assert rotation(on_floor["xyzw"]) == pytest.approx(camera.base_to_optical(), abs=1e-6)
    in_base_link = [expected[0], 0.0, expected[2] - BASE_LINK_HEIGHT]
    assert seen["base_link"]["xyz"] == pytest.approx(in_base_link, abs=1e-6)
    assert seen["odom_frames"] == ["odom", "base_footprint"]
    assert seen["odom"]["xyz"][2] == pytest.approx(camera.height_m, abs=1e-6)  # odom on the floor


def test_urdf_defaults_are_a_turtlebot2_kinect_and_bad_mountings_are_refused():
    text = urdf(0.297, 0.0, -0.087)
    assert '<origin xyz="-0.087 0 0.2868" rpy="0 0.0 0"/>' in text
    assert '<link name="camera_rgb_optical_frame"/>' in text
    for bad in [(0.0, 0.0, 0.0), (0.3, 89.0, 0.0), (math.nan, 0.0, 0.0)]:
        with pytest.raises(ValueError):
            urdf(*bad)
    refused = subprocess.run(
        [sys.executable, "-m", "harness.robot_description", "--camera-height", "-1"],
        capture_output=True, text=True,
    )  # fmt: skip
    assert refused.returncode == 2
    assert "camera_height must be above the floor (> 0 m), got -1.0" in refused.stderr


if __name__ == "__main__" and "--client" in sys.argv:
    client()
