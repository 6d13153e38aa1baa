"""`rosrun image_converter stitch` on generated images: panoramas, --json, and clear failures."""

from __future__ import annotations

import json
import math
import subprocess
from pathlib import Path

import cv2
import numpy as np
import pytest

from harness.testing import textured_scene

F = 320.0 / math.tan(math.radians(30.0))  # 640 px wide views with a 60 deg field of view


def cylinder_view(cylinder: np.ndarray, yaw: float, size=(640, 480)) -> np.ndarray:
    """A pinhole camera at the centre of the unrolled `cylinder` (radius F), turned left by yaw."""
    u, v = np.meshgrid(np.arange(size[0], dtype=np.float64), np.arange(size[1], dtype=np.float64))
    x, y = (u - size[0] / 2) / F, (v - size[1] / 2) / F
    wx, wz = math.cos(yaw) * x - math.sin(yaw), math.sin(yaw) * x + math.cos(yaw)
    map_x = (F * np.arctan2(wx, wz) + cylinder.shape[1] / 2).astype(np.float32)
    map_y = (F * y / np.hypot(wx, wz) + cylinder.shape[0] / 2).astype(np.float32)
    return cv2.remap(cylinder, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)


def stitch(*args: str | Path) -> subprocess.CompletedProcess:
    return subprocess.run(
        ["rosrun", "image_converter", "stitch", *map(str, args)],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip


@pytest.fixture(scope="module")
def images(tmp_path_factory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("stitch_cli")
    scene = textured_scene(900, 400, 1)
    cylinder = textured_scene(1500, 700, 2)
    pictures = {
        "left": scene[:, :500],
        "right": scene[:, 300:800],  # overlaps "left" by 200 px, shifted by 300 px
        "far": scene[:, 600:900],
        "blank": np.full((400, 500, 3), 90, np.uint8),
    }
    for i, yaw_deg in enumerate((20, 0, -20)):
        pictures[f"turn{i}"] = cylinder_view(cylinder, math.radians(yaw_deg))
    paths = {}
    for name, picture in pictures.items():
        paths[name] = folder / f"{name}.png"
        cv2.imwrite(str(paths[name]), picture)
    return paths


def test_two_images_json_homography_maps_b_into_a(images, tmp_path):
    out = tmp_path / "pano.png"
    done = stitch(images["left"], images["right"], "-o", out, "--json")
    assert done.returncode == 0, done.stderr
    report = json.loads(done.stdout)
    assert report["method"] == "homography" and report["detector"] == "orb"
    (pair,) = report["pairs"]
    assert pair["inliers"] >= 25 and pair["reprojection_error_px"] < 3.0
    h = np.array(pair["homography"]).reshape(3, 3)
    corners = np.array([[0, 0, 1], [500, 0, 1], [500, 400, 1], [0, 400, 1]], float)
    mapped = corners @ h.T
    mapped = mapped[:, :2] / mapped[:, 2:]
    np.testing.assert_allclose(mapped, corners[:, :2] + [300, 0], atol=1.0)
    # 800 x 400 up to the sub-pixel error of H, rounded outwards at both ends.
    height, width = cv2.imread(str(out)).shape[:2]
    assert abs(width - 800) <= 2 and abs(height - 400) <= 2


def test_sift_detector_is_accepted(images, tmp_path):
    done = stitch(images["left"], images["right"], "-o", tmp_path / "p.png", "--detector", "sift")
    assert done.returncode == 0, done.stderr


def test_three_turned_views_stitch_to_the_expected_width(images, tmp_path):
    out = tmp_path / "pano.png"
    done = stitch(images["turn0"], images["turn1"], images["turn2"], "-o", out, "--json")
    assert done.returncode == 0, done.stderr
    report = json.loads(done.stdout)
    assert report["method"] == "cv::Stitcher" and len(report["pairs"]) == 2
    expected = F * (math.radians(40) + math.radians(60))
    assert abs(cv2.imread(str(out)).shape[1] - expected) < 0.05 * expected


@pytest.mark.parametrize(
    ("inputs", "words"),
    [
        (("left", "far"), "overlap"),
        (("left", "blank"), "image B is blank"),
        (("turn0", "turn1", "blank"), "image 3 is blank"),
    ],
)
def test_unstitchable_images_fail_with_a_message(images, tmp_path, inputs, words):
    out = tmp_path / "pano.png"
    done = stitch(*(images[name] for name in inputs), "-o", out)
    assert done.returncode == 1
    assert "cannot stitch" in done.stderr and words in done.stderr, done.stderr
    assert not out.exists()


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (("left",), "need at least two input images, got 1"),
        (("left", "right", "--detector", "surf"), "unknown detector 'surf'"),
        (("left", "right", "--bogus"), "unrecognised option '--bogus'"),
    ],
)
def test_bad_command_lines_exit_2_with_usage(images, tmp_path, args, words):
    resolved = [str(images.get(a, a)) for a in args]
    done = stitch(*resolved, "-o", tmp_path / "pano.png")
    assert done.returncode == 2
    assert words in done.stderr and "usage:" in done.stderr


def test_missing_input_and_output_are_errors(images, tmp_path):
    done = stitch(images["left"], tmp_path / "missing.png", "-o", tmp_path / "pano.png")
    assert done.returncode == 1 and "cannot read image" in done.stderr
    done = stitch(images["left"], images["right"])
    assert done.returncode == 2 and "no output file" in done.stderr
