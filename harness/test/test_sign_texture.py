"""The parking sign picture and world: reproducible, small, in view at the standoff, and rich
enough in SIFT features at 3 m for the sign detector."""

import math
from pathlib import Path

import cv2
import numpy as np
import pytest

from harness.render import Renderer
from harness.sign_texture import draw_sign

SIGN_PNG = Path(__file__).resolve().parents[2] / "follow_bot" / "assets" / "parking_sign.png"


def test_committed_sign_is_what_the_script_draws():
    committed = cv2.imread(str(SIGN_PNG), cv2.IMREAD_UNCHANGED)
    np.testing.assert_array_equal(committed, draw_sign())
    assert SIGN_PNG.stat().st_size < 100_000


@pytest.fixture(scope="module")
def sign_world(worlds):
    world = worlds["parking_sign"]
    (sign,) = world.objects
    return world, sign, Renderer(world)


def _facing(sign, distance, lateral=0.0):
    """Robot pose `distance` in front of the sign along its normal, `lateral` to its right (seen
    from the front), facing the sign."""
    x, y, _, yaw = sign.pose
    right = (-math.sin(yaw), math.cos(yaw))
    return (
        x + distance * math.cos(yaw) + lateral * right[0],
        y + distance * math.sin(yaw) + lateral * right[1],
        yaw + math.pi,
    )


@pytest.mark.parametrize("lateral", [-0.03, 0.0, 0.03])
def test_sign_whole_in_view_at_the_standoff(sign_world, lateral):
    world, sign, renderer = sign_world
    cam = world.camera
    x, y, yaw = _facing(sign, 0.5, lateral)
    for heading_error in (-math.radians(3), 0.0, math.radians(3)):
        (proj,) = renderer.object_projections((x, y, yaw + heading_error))
        corners = np.array(proj["corners_px"])
        assert (corners[:, 0] > 5).all() and (corners[:, 0] < cam.width - 6).all()
        assert (corners[:, 1] > 5).all() and (corners[:, 1] < cam.height - 6).all()


def test_plenty_of_well_spread_sift_features_at_3m(sign_world):
    world, sign, renderer = sign_world
    pose = _facing(sign, 3.0)
    gray = cv2.cvtColor(renderer.render(pose), cv2.COLOR_BGR2GRAY)
    (proj,) = renderer.object_projections(pose)
    quad = np.array(proj["corners_px"], np.float32)
    keypoints = cv2.SIFT_create().detect(gray)
    inside = [k.pt for k in keypoints if cv2.pointPolygonTest(quad, k.pt, False) >= 0]
    assert len(inside) >= 60, len(inside)
    centre = quad.mean(axis=0)
    pts = np.array(inside)
    quadrants = [
        int(np.sum((np.sign(pts[:, 0] - centre[0]) == sx) & (np.sign(pts[:, 1] - centre[1]) == sy)))
        for sx in (-1, 1)
        for sy in (-1, 1)
    ]
    assert min(quadrants) >= 8, quadrants
