"""The parker's tag pose on frames the harness renders of the parking world, at known poses.

Frames come from harness.render.Renderer (the simulator's own renderer), the pose from the
parker's TagDetector through the `marker_probe` tool (AprilTag mode), the truth from the world
file.

- Position within 1 cm at 0.5-3 m, every view; also on raw frames through a barrel lens (the
  harness's turtlebot3 lens, the detector rectifying the corners).
- At the parker's standoff (0.5-0.8 m, where the tag spans half the frame and a barrel lens bows
  its edges most) the range within 1 mm, on raw frames through the lens as on pinhole ones: the
  parking bound is 6 mm. (Fitting the quad on the raw frame's bowed edges put it 9 mm near.)
- Orientation within 1 deg wherever it is observable: up to 1.5 m, or at >= 15 deg incidence.
  Seen face-on from further away, tilting the 0.30 m tag by 1 deg moves its corners by only
  0.02-0.05 px, below what corner refinement resolves, so there the bound is what the corner
  accuracy allows (5 deg).
- No flips: the planar pose ambiguity's two solutions are mirror tilts about the line of sight,
  nearly equal in residual far out. Over a sweep of views stepping out from 0.5 m to 3 m, one
  detector sees them as a sequence and must never jump to the mirror branch: face-on the tilt
  stays within the bound above in every frame, and at 12 deg incidence (mirror 24 deg away)
  within 3 deg in every frame.
"""

import json
import math
import subprocess
from dataclasses import replace

import cv2
import numpy as np
import pytest

from harness.camera import LENSES
from harness.geometry import rotation_angle_deg
from harness.render import Renderer
from harness.testing import REPO
from harness.world_file import load_world

WORLDS = REPO / "worlds"


@pytest.fixture(scope="module")
def parking():
    world = load_world(WORLDS / "parking.yaml")
    return world, Renderer(world), world.objects[0]


@pytest.fixture(scope="module")
def parking_through_lens():
    world = load_world(WORLDS / "parking.yaml")
    camera = replace(world.camera, distortion=LENSES["turtlebot3"])
    return world, Renderer(world, camera), world.objects[0]


def probe(renderer, robots, tmp_path, tag):
    cam = renderer.camera
    files = []
    for i, robot in enumerate(robots):
        path = tmp_path / f"frame{i:03d}.png"
        cv2.imwrite(str(path), cv2.cvtColor(renderer.render(robot), cv2.COLOR_BGR2GRAY))
        files.append(str(path))
    args = ["--tag-size", str(tag.size), "--tag-id", str(tag.tag_id), "--tag-family", tag.family]
    for flag, value in (("--fx", cam.fx), ("--fy", cam.fy), ("--cx", cam.cx), ("--cy", cam.cy)):
        args += [flag, str(value)]
    if cam.distorted:
        args += ["--distortion", ",".join(str(d) for d in cam.distortion)]
    out = subprocess.run(
        ["rosrun", "follow_bot", "marker_probe", *args, *files],
        capture_output=True, text=True, check=True, timeout=120,
    ).stdout.splitlines()  # fmt: skip
    poses = []
    for line in out:
        seen = json.loads(line)
        assert seen["found"], f"tag not detected in {seen['frame']}"
        poses.append((np.array(seen["rotation"]), np.array(seen["translation"])))
    assert len(poses) == len(files)
    return poses


def tilt_deg(rotation):
    """Tilt about the tag's vertical axis (the one the ambiguity mirrors), in the camera's x-z."""
    return math.degrees(math.atan2(rotation[0, 2], rotation[2, 2]))


def view(tag, distance, incidence_deg, bearing_deg):
    """Robot pose `distance` from the tag centre, `incidence_deg` off its normal, with the tag
    at `bearing_deg` from the heading (positive: to the left)."""
    x, y, _, yaw = tag.pose
    a = yaw + math.radians(incidence_deg)
    rx, ry = x + distance * math.cos(a), y + distance * math.sin(a)
    return (rx, ry, math.atan2(y - ry, x - rx) - math.radians(bearing_deg))


# (distance m, incidence deg, bearing deg)
VIEWS = [
    (0.5, 0, 0), (0.6, 20, 5), (0.8, -30, -8), (1.0, 0, 10), (1.0, 45, -5), (1.5, -15, 0),
    (1.5, 25, 12), (2.0, 0, 0), (2.0, 30, -10), (2.5, -40, 5), (3.0, 0, 0), (3.0, 20, 15),
    (3.0, -50, -10), (2.7, 10, 20),
]  # fmt: skip


@pytest.mark.parametrize("frames", ["parking", "parking_through_lens"])
def test_pose_within_1cm_and_1deg_where_observable(frames, request, tmp_path):
    world, renderer, tag = request.getfixturevalue(frames)
    robots = [view(tag, *v) for v in VIEWS]
    failures = []
    poses = probe(renderer, robots, tmp_path, tag)
    for v, robot, (r, t) in zip(VIEWS, robots, poses, strict=True):
        r_true, t_true = renderer.camera.marker_pose(robot, tag.pose)
        position = float(np.linalg.norm(t - t_true))
        angle = rotation_angle_deg(r, r_true)
        observable = v[0] <= 1.5 or abs(v[1]) >= 15
        if position > 0.01 or angle > (1.0 if observable else 5.0):
            failures.append(f"{v}: position {position * 100:.2f} cm, rotation {angle:.2f} deg")
    assert not failures, "; ".join(failures)


# (distance m, incidence deg, bearing deg) around the parker's 0.5 m standoff
STANDOFF_VIEWS = [(0.5, 0, 0), (0.5, 5, 3), (0.5, -10, -5), (0.55, 0, 0), (0.6, 0, 0), (0.8, 10, 5)]


@pytest.mark.parametrize("frames", ["parking", "parking_through_lens"])
def test_range_within_1mm_at_the_parking_standoff(frames, request, tmp_path):
    world, renderer, tag = request.getfixturevalue(frames)
    robots = [view(tag, *v) for v in STANDOFF_VIEWS]
    poses = probe(renderer, robots, tmp_path, tag)
    errors_mm = {
        v: round(1000 * float(t[2] - renderer.camera.marker_pose(robot, tag.pose)[1][2]), 2)
        for v, robot, (_, t) in zip(STANDOFF_VIEWS, robots, poses, strict=True)
    }
    assert all(abs(e) <= 1.0 for e in errors_mm.values()), errors_mm


@pytest.mark.parametrize("incidence_deg, far_bound_deg", [(0.0, 5.0), (12.0, 3.0)])
def test_sweep_out_to_3m_never_flips(parking, tmp_path, incidence_deg, far_bound_deg):
    world, renderer, tag = parking
    distances = np.arange(0.5, 3.001, 0.1)
    robots = [view(tag, d, incidence_deg, 0.0) for d in distances]
    errors = []
    for robot, (r, _) in zip(robots, probe(renderer, robots, tmp_path, tag), strict=True):
        r_true, _ = renderer.camera.marker_pose(robot, tag.pose)
        errors.append(tilt_deg(r) - tilt_deg(r_true))
    errors = np.array(errors)
    near = distances <= 1.5
    assert np.all(np.abs(errors[near]) <= 1.0), errors
    assert np.all(np.abs(errors[~near]) <= far_bound_deg), errors
