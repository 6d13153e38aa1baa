"""Camera model against numbers worked out by hand from fx, cx, height and pitch."""

import math

import numpy as np
import pytest

from follow_bot import core
from harness.camera import Camera
from harness.geometry import incidence_deg, rotation_angle_deg

FX = 320.0 / math.tan(math.radians(30.0))  # 554.2563 px for 640 px and 60 deg


def test_intrinsics_and_camera_info():
    cam = Camera()
    assert cam.fx == pytest.approx(554.2562584220407)
    assert (cam.cx, cam.cy) == (320.0, 240.0)
    info = cam.camera_info_dict()
    assert info["K"] == pytest.approx([FX, 0, 320, 0, FX, 240, 0, 0, 1])
    assert info["P"] == pytest.approx([FX, 0, 320, 0, 0, FX, 240, 0, 0, 0, 1, 0])
    assert info["D"] == [0.0] * 5
    assert info["distortion_model"] == "plumb_bob"
    assert (info["width"], info["height"]) == (640, 480)
    assert info["frame_id"] == "camera_rgb_optical_frame"


def test_default_mounting_is_the_behaviours():
    # One default: a world without a camera mounting is seen as the nodes assume it.
    nodes = core.CameraGeometry()
    camera = Camera()
    assert (camera.height_m, camera.pitch, camera.x_offset_m) == pytest.approx(
        (nodes.height_m, nodes.pitch_rad, nodes.x_offset_m), abs=1e-12)  # fmt: skip
    assert camera.pitch == pytest.approx(math.radians(20.0))


def test_level_camera_projects_hand_computed_pixels():
    cam = Camera(height_m=0.3, pitch=0.0)
    pts = np.array([[2.0, 0.0, 0.3], [2.0, 0.5, 0.3], [2.0, 0.0, 0.0], [4.0, -1.0, 1.3]])
    uv, depth = cam.project(pts, (0.0, 0.0, 0.0))
    expected = [
        (320.0, 240.0),  # straight ahead at lens height
        (320.0 - FX * 0.5 / 2.0, 240.0),  # 0.5 m to the left -> left of centre
        (320.0, 240.0 + FX * 0.3 / 2.0),  # on the floor -> below centre
        (320.0 + FX * 1.0 / 4.0, 240.0 - FX * 1.0 / 4.0),  # right and above
    ]
    np.testing.assert_allclose(uv, expected, atol=0.5)
    np.testing.assert_allclose(depth, [2.0, 2.0, 2.0, 4.0])


def test_pitched_offset_camera_on_rotated_robot():
    pitch, h, off = math.radians(20.0), 0.4, 0.1
    cam = Camera(height_m=h, pitch=pitch, x_offset_m=off)
    pose = (1.0, 2.0, math.pi / 2)  # facing +y: forward = +y, left = -x
    lens = (1.0, 2.0 + off)
    cases = [(1.5, 0.0, -h), (2.0, 0.3, -h), (3.0, -0.4, 0.5)]  # forward, left, up from lens
    pts, expected = [], []
    for fwd, left, up in cases:
        pts.append([lens[0] - left, lens[1] + fwd, h + up])
        x_opt = -left
        y_opt = -fwd * math.sin(pitch) - up * math.cos(pitch)
        z_opt = fwd * math.cos(pitch) - up * math.sin(pitch)
        expected.append((320.0 + FX * x_opt / z_opt, 240.0 + FX * y_opt / z_opt))
    uv, _ = cam.project(np.array(pts), pose)
    np.testing.assert_allclose(uv, expected, atol=0.5)
    # The first point is the floor 1.5 m ahead: 0.4 m below, so atan(0.4/1.5) below level.
    assert uv[0, 1] == pytest.approx(240.0 + FX * math.tan(math.atan2(h, 1.5) - pitch), abs=0.5)


def test_mounting_error_moves_and_turns_the_camera_on_the_base():
    # 5 mm to the left and turned 1 deg left: a point 2 m ahead of the described lens, at lens
    # height, lies 5 mm to the right and 1 deg to the right of the real optical axis.
    cam = Camera(height_m=0.3, pitch=0.0, y_offset_error_m=0.005, yaw_error=math.radians(1.0))
    uv, _ = cam.project(np.array([[2.0, 0.0, 0.3]]), (0.0, 0.0, 0.0))
    u, v = uv[0]
    bearing = math.atan2(0.005, 2.0) + math.radians(1.0)  # to the right of the axis
    assert u == pytest.approx(320.0 + FX * math.tan(bearing), abs=0.05)
    assert v == pytest.approx(240.0, abs=1e-6)
    # On a robot facing +y the error turns and moves with the base: 5 mm to -x.
    _, position = cam.camera_in_world((0.0, 0.0, math.pi / 2))
    np.testing.assert_allclose(position, [-0.005, 0.0, 0.3], atol=1e-12)


def test_horizon_row_for_pitched_camera():
    cam = Camera(pitch=math.radians(20.0))
    assert cam.horizon_row() == pytest.approx(240.0 - FX * math.tan(math.radians(20.0)))
    far, _ = cam.project(np.array([[1e6, 0.0, 0.0]]), (0.0, 0.0, 0.0))
    assert far[0, 1] == pytest.approx(cam.horizon_row(), abs=1e-3)
    assert Camera(pitch=math.radians(-10.0)).horizon_row() > 240.0


def test_ground_homography_round_trip():
    cam = Camera(pitch=math.radians(15.0), x_offset_m=0.05)
    pose = (0.3, -0.7, 0.4)
    floor = np.array([[1.5, 0.0], [2.0, -0.5], [3.0, 1.0]])
    uv, _ = cam.project(np.column_stack([floor, np.zeros(3)]), pose)
    h = cam.ground_homography(pose)
    hom = np.column_stack([floor, np.ones(3)]) @ h.T
    np.testing.assert_allclose(hom[:, :2] / hom[:, 2:], uv, atol=1e-9)
    np.testing.assert_allclose(cam.pixel_to_ground(uv, pose), floor, atol=1e-9)
    assert np.isnan(cam.pixel_to_ground([[320.0, 10.0]], pose)).all()  # above the horizon


def test_marker_pose_face_on_and_turned():
    cam = Camera(height_m=0.3, pitch=0.0)
    # Facing the robot 2 m ahead, 0.5 m to its left and 0.5 m above the lens: marker axes are
    # the optical axes (x right, y down, z away), centre at (-0.5, -0.5, 2).
    rot, centre = cam.marker_pose((0.0, 0.0, 0.0), (2.0, 0.5, 0.8, math.pi))
    np.testing.assert_allclose(rot, np.eye(3), atol=1e-12)
    np.testing.assert_allclose(centre, [-0.5, -0.5, 2.0], atol=1e-12)
    # Seen from 1 m further back.
    rot2, centre2 = cam.marker_pose((-1.0, 0.0, 0.0), (2.0, 0.5, 0.8, math.pi))
    np.testing.assert_allclose(centre2, [-0.5, -0.5, 3.0], atol=1e-12)
    # Turned 0.3 rad about the vertical, straight ahead: the rotation and the incidence are both
    # 0.3 rad.
    rot, centre = cam.marker_pose((0.0, 0.0, 0.0), (2.0, 0.0, 0.3, math.pi - 0.3))
    np.testing.assert_allclose(centre, [0.0, 0.0, 2.0], atol=1e-12)
    assert rotation_angle_deg(np.eye(3), rot) == pytest.approx(math.degrees(0.3))
    assert incidence_deg(rot, centre) == pytest.approx(math.degrees(0.3))
    assert rotation_angle_deg(rot, rot) == pytest.approx(0.0, abs=1e-6)


def test_lens_puts_a_3d_point_where_cv2_project_points_does(worlds):
    """A small ball seen through the turtlebot3 lens: its blob lands on cv2.projectPoints' pixel
    of its centre (the pinhole view is remapped by the inverse of the lens map)."""
    from dataclasses import replace

    import cv2

    from harness.camera import LENSES
    from harness.render import Renderer
    from harness.world import Sphere

    rgb = worlds["rgb"]
    rgb = replace(rgb, lighting=replace(rgb.lighting, ambient=1.0))  # unshaded: weight = coverage
    camera = replace(rgb.camera, distortion=LENSES["turtlebot3"])
    pose = (0.0, 0.0, 0.0)
    for position in ((1.5, 0.6, 0.55), (1.2, -0.5, 0.05), (2.0, 0.0, 0.3)):
        ball = Sphere("dot", (255, 0, 255), 0.01, position)
        world = replace(rgb, objects=(ball,))
        image = Renderer(world, camera).render(pose).astype(float)
        weight = np.clip((image[..., 0] - image[..., 1]) / 255.0, 0.0, 1.0)  # magenta: B - G
        rows, cols = np.indices(weight.shape)
        centroid = np.array([(weight * cols).sum(), (weight * rows).sum()]) / weight.sum()
        r, t = camera.world_to_camera(pose)
        expected, _ = cv2.projectPoints(
            np.array([position], float), cv2.Rodrigues(r)[0], t, camera.K,
            np.array(camera.distortion),
        )  # fmt: skip
        assert centroid == pytest.approx(expected.ravel(), abs=0.05)
        assert camera.distort_pixels(camera.project(np.array([position]), pose)[0])[
            0
        ] == pytest.approx(expected.ravel(), abs=1e-9)


def test_camera_info_carries_the_lens():
    from harness.camera import LENSES

    info = Camera(distortion=LENSES["turtlebot3"]).camera_info_dict()
    assert info["distortion_model"] == "plumb_bob"
    assert info["D"] == list(LENSES["turtlebot3"])
    assert info["P"][:3] == info["K"][:3] and info["P"][3] == 0.0
    assert info["R"] == [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
