"""Rendered pixels against geometry computed by hand, plus determinism and speed helpers."""

import math

import cv2
import numpy as np
import pytest

from harness.render import Renderer, bench_render
from harness.world_file import parse_world

FX = 320.0 / math.tan(math.radians(30.0))


@pytest.fixture(scope="module")
def renderers(worlds):
    return {name: Renderer(w) for name, w in worlds.items()}


@pytest.mark.parametrize(
    ("pose", "x_right"),
    [
        ((-2.0, -3.47, 0.0), 0.03),  # 3 cm left of the first straight -> line 3 cm to the right
        ((0.0, 2.16, math.pi), 0.04),  # on the top straight driving -x, line 4 cm to the right
        ((-1.0, -3.52, 0.0), -0.02),
    ],
)
def test_line_lands_where_the_geometry_says(worlds, renderers, pose, x_right):
    w = worlds["course"]
    cam = w.camera
    assert cam.pitch == pytest.approx(math.radians(20.0)) and cam.height_m == pytest.approx(0.3)
    row = 360  # 3/4 of the image height
    below = cam.pitch + math.atan((row - 240.0) / FX)  # ray angle below horizontal
    forward = 0.3 / math.tan(below)  # floor distance ahead of the lens
    depth = forward * math.cos(cam.pitch) + 0.3 * math.sin(cam.pitch)  # optical z
    expected_u = 320.0 + FX * x_right / depth
    expected_width = FX * 0.05 / depth
    image = renderers["course"].render(pose)
    blue = image[row, :, 0].astype(float)
    cover = np.clip((120.0 - blue) / 120.0, 0.0, 1.0)  # floor B = 120, paint B = 0
    centre = (cover * np.arange(640)).sum() / cover.sum()
    assert centre == pytest.approx(expected_u, abs=1.0)
    assert cover.sum() == pytest.approx(expected_width, abs=1.0)


def test_sky_above_horizon_floor_below(worlds, renderers):
    image = renderers["rgb"].render((0.0, 0.0, math.pi))  # balls behind: empty floor
    horizon = worlds["rgb"].camera.horizon_row()
    assert horizon == pytest.approx(240.0)
    assert (image[:240] == 200).all()
    assert (image[245:] == 120).all()


COLOUR_AXIS = {"red": 2, "green": 1, "blue": 0}


@pytest.mark.parametrize("pose", [(0.0, 0.0, 0.0), (0.5, 0.3, 0.1), (0.3, -0.2, -0.08)])
def test_sphere_blob_centroid_matches_reported_projection(renderers, pose):
    renderer = renderers["rgb"]
    image = renderer.render(pose).astype(int)
    checked = 0
    for entry in renderer.object_projections(pose):
        axis = COLOUR_AXIS[entry["name"]]
        others = np.delete(image, axis, axis=2).max(axis=2)
        mask = (image[..., axis] - others) > 60
        rows, cols = np.nonzero(mask)
        touches_edge = len(rows) == 0 or rows.min() == 0 or cols.min() == 0 or cols.max() == 639
        if not entry["in_view"] or touches_edge:
            continue
        centroid = np.array([cols.mean(), rows.mean()])
        assert np.linalg.norm(centroid - entry["blob_centre_px"]) < 1.0, entry["name"]
        # The projected 3-D centre is close too, but not equal (perspective).
        assert np.linalg.norm(centroid - entry["centre_px"]) < 3.0
        checked += 1
    assert checked >= 2


def test_box_front_face_colour_and_extent(worlds, renderers):
    w = worlds["dumpster"]
    (box,) = w.objects
    image = renderers["dumpster"].render((0.0, 0.0, 0.0))
    lit = w.lighting
    normal = np.array([-1.0, 0.0, 0.0])  # the long side faces the robot at the origin
    shade = lit.ambient + (1 - lit.ambient) * max(0.0, normal @ lit.direction)
    np.testing.assert_allclose(image[240, 320], np.array(box.colour) * shade, atol=1.0)
    # Face spans y in [-0.9, 0.9] at x = 3.5 m: columns 320 -/+ FX * 0.9 / 3.5.
    face = np.nonzero(np.abs(image[240].astype(int) - image[240, 320]).sum(axis=1) < 3)[0]
    assert face.min() == pytest.approx(320 - FX * 0.9 / 3.5, abs=1.0)
    assert face.max() == pytest.approx(320 + FX * 0.9 / 3.5, abs=1.0)


def test_texture_marker_shows_its_picture(tmp_path):
    picture = np.zeros((100, 200, 3), np.uint8)
    picture[:, :100] = (255, 0, 0)  # left half blue, right half red, as printed
    picture[:, 100:] = (0, 0, 255)
    cv2.imwrite(str(tmp_path / "p.png"), picture)
    world = parse_world(
        {
            "name": "pic",
            "ground": {"size": [6, 6], "metres_per_pixel": 0.02},
            "lighting": {"ambient": 1.0},
            "camera": {"pitch_deg": 0.0},
            "objects": [
                {
                    "kind": "texture",
                    "image": "p.png",
                    "width": 1.0,
                    "pose": [2.0, 0.0, 0.4, math.pi],
                }
            ],
        },
        tmp_path,
    )
    image = Renderer(world).render((0.0, 0.0, 0.0))
    left, right = image[240 - 20, 320 - 40], image[240 - 20, 320 + 40]
    np.testing.assert_array_equal(left, [255, 0, 0])
    np.testing.assert_array_equal(right, [0, 0, 255])
    # Seen from behind: plain grey back, no picture.
    back = Renderer(world).render((4.0, 0.0, math.pi))
    assert abs(int(back[220, 320, 0]) - int(back[220, 320, 2])) < 3


def test_noise_is_seeded_and_deterministic(worlds):
    w = worlds["rgb"]
    pose = (0.2, 0.1, 0.05)
    a = Renderer(w, noise_sigma=5.0, seed=3)
    b = Renderer(w, noise_sigma=5.0, seed=3)
    first = a.render(pose)
    np.testing.assert_array_equal(first, b.render(pose))
    np.testing.assert_array_equal(a.render(pose, frame=7), b.render(pose, frame=7))
    assert not np.array_equal(first, a.render(pose))  # next frame, fresh noise
    assert not np.array_equal(first, Renderer(w, noise_sigma=5.0, seed=4).render(pose))
    clean = Renderer(w).render(pose).astype(float)
    assert np.std(first.astype(float)[:200] - clean[:200]) == pytest.approx(5.0, rel=0.05)
    np.testing.assert_array_equal(clean, Renderer(w).render(pose))


def test_gain_scales_the_image(worlds):
    dim = Renderer(worlds["rgb"], gain=0.5).render((-5.0, -5.0, 0.0))
    assert dim[100, 100].tolist() == [100, 100, 100] and dim[400, 100].tolist() == [60, 60, 60]


def test_camera_can_be_anywhere(worlds, renderers):
    # Inside the box, right against the tag, below-horizon-only views: no crash, right shape.
    for name, pose in [
        ("dumpster", (4.0, 0.0, 0.3)),
        ("parking", (2.99, 0.0, 0.0)),
        ("rgb", (3.0, 1.0, 0.0)),
        ("parking", (3.2, 0.0, math.pi)),
    ]:
        image = renderers[name].render(pose)
        assert image.shape == (480, 640, 3) and image.dtype == np.uint8


def test_bench_render_reports_fps(worlds):
    assert bench_render(worlds["rgb"], 5) > 0.0
