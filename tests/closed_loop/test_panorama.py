"""The panorama scenario: on the rgb world the panorama node turns in place, grabs frames,
stitches them, and the red, green and blue spheres all appear in it, in their true left-to-right
order and near the columns their bearings predict.

The ROS client runs in a child process (this file with --client, tests/README.md).
"""

from __future__ import annotations

import json
import math
import sys
import time

import cv2
import numpy as np
import pytest

from harness.processes import launch_with_client
from harness.testing import REPO
from harness.world import Sphere
from harness.world_file import load_world

WORLD = REPO / "worlds" / "rgb.yaml"
# OpenCV HSV (H 0-179) bands of the rgb world's sphere colours, shading included.
HUE_BANDS = {"red": [(0, 8), (172, 179)], "green": [(50, 70)], "blue": [(110, 130)]}


def client(out_png: str) -> None:
    import rospy
    from nav_msgs.msg import Odometry
    from sensor_msgs.msg import Image
    from std_srvs.srv import Trigger

    from follow_bot_msgs.ros_image import msg_to_bgr

    rospy.init_node("panorama_test_client")
    rospy.wait_for_service("/panorama/capture", timeout=60)
    rospy.wait_for_message("/sim/pose", Odometry, timeout=60)
    # The node refuses ("cannot capture: ...") until it has a pose, intrinsics and frames.
    deadline = time.monotonic() + 10.0
    while True:
        reply = rospy.ServiceProxy("/panorama/capture", Trigger)()
        if not reply.message.startswith("cannot capture") or time.monotonic() > deadline:
            break
        time.sleep(0.2)
    result = {"success": reply.success, "message": reply.message}
    if reply.success:
        msg = rospy.wait_for_message("/panorama/panorama", Image, timeout=10)
        cv2.imwrite(out_png, msg_to_bgr(msg))
    print(json.dumps(result))


@pytest.fixture(scope="module")
def capture(tmp_path_factory) -> tuple[dict, np.ndarray | None]:
    out_png = tmp_path_factory.mktemp("panorama") / "panorama.png"
    result = launch_with_client(
        ["harness", "panorama.launch"], [sys.executable, __file__, "--client", str(out_png)],
        timeout=120, roscore=True,
    )  # fmt: skip
    return result, cv2.imread(str(out_png)) if result["success"] else None


def blob_columns(panorama: np.ndarray) -> dict[str, float]:
    """Centroid column of the largest blob of each sphere colour (absent colours left out)."""
    hsv = cv2.cvtColor(panorama, cv2.COLOR_BGR2HSV)
    columns = {}
    for name, bands in HUE_BANDS.items():
        mask = np.zeros(hsv.shape[:2], np.uint8)
        for low, high in bands:
            mask |= cv2.inRange(hsv, (low, 120, 60), (high, 255, 255))
        count, _, stats, centroids = cv2.connectedComponentsWithStats(mask)
        if count > 1:
            largest = 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))
            if stats[largest, cv2.CC_STAT_AREA] >= 100:
                columns[name] = float(centroids[largest][0])
    return columns


def expected_columns(width: int) -> dict[str, float]:
    """Columns on the cylindrical panorama centred on the start heading: f per radian of
    bearing, left (counter-clockwise) first."""
    world = load_world(WORLD)
    x0, y0, yaw0 = world.robot.start
    camera = world.camera
    columns = {}
    for sphere in world.objects:
        assert isinstance(sphere, Sphere)
        x, y, _ = sphere.position
        bearing = math.atan2(y - y0, x - x0) - yaw0
        columns[sphere.name] = width / 2.0 - camera.fx * bearing
    return columns


def test_capture_succeeds(capture):
    result, panorama = capture
    assert result["success"], result["message"]
    assert panorama is not None and panorama.shape[1] > panorama.shape[0]


def test_all_three_spheres_appear_in_their_left_to_right_order(capture):
    result, panorama = capture
    assert result["success"], result["message"]
    found = blob_columns(panorama)
    assert set(found) == {"red", "green", "blue"}, f"found {found}"
    expected = expected_columns(panorama.shape[1])
    assert sorted(found, key=found.get) == sorted(expected, key=expected.get)
    # Frames are grabbed within the node's 0.5 deg yaw tolerance (4.8 px at f = 554 px): twice
    # that bounds the blob centroids, shading and shadow included.
    for name, column in found.items():
        assert abs(column - expected[name]) < 10.0, (name, found, expected)


if __name__ == "__main__" and sys.argv[1:2] == ["--client"]:
    client(sys.argv[2])
