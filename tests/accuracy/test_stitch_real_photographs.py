"""`rosrun image_converter stitch` on real photographs shipped by Debian's opencv-doc
(tools/debian-packages.txt): the Oxford "graffiti" viewpoint pair against its ground-truth
homography, and the cookie box found in a cluttered scene against points labelled by hand."""

from __future__ import annotations

import json
import subprocess
import xml.etree.ElementTree as ET
from pathlib import Path

import cv2
import numpy as np
import pytest

DATA = Path("/usr/share/doc/opencv-doc/examples/data")
GRAF1, GRAF3 = DATA / "graf1.png", DATA / "graf3.png"
BOX, BOX_IN_SCENE = DATA / "box.png", DATA / "box_in_scene.png"


def graf1_to_graf3() -> np.ndarray:
    """The dataset's ground truth H1to3p (cv2.FileStorage of OpenCV 4.10 cannot read this file)."""
    data = ET.parse(DATA / "H1to3p.xml").getroot().find("H13/data")
    return np.array(data.text.split(), float).reshape(3, 3)


def apply(h: np.ndarray, points: np.ndarray) -> np.ndarray:
    mapped = np.c_[points, np.ones(len(points))] @ h.T
    return mapped[:, :2] / mapped[:, 2:]


@pytest.fixture(scope="module")
def stitched(tmp_path_factory) -> tuple[subprocess.CompletedProcess, Path]:
    if not GRAF1.exists():
        pytest.fail(f"no {GRAF1}: install opencv-doc (tools/debian-packages.txt)")
    out = tmp_path_factory.mktemp("graffiti") / "pano.png"
    done = subprocess.run(
        ["rosrun", "image_converter", "stitch", str(GRAF1), str(GRAF3), "-o", str(out),
         "--detector", "sift", "--json", "--verbose"],
        capture_output=True, text=True, timeout=180,
    )  # fmt: skip
    return done, out


def test_graffiti_pair_stitches_within_three_pixels_of_the_truth(stitched):
    done, out = stitched
    assert done.returncode == 0, done.stderr
    report = json.loads(done.stdout)
    assert report["method"] == "homography" and report["detector"] == "sift"
    (pair,) = report["pairs"]
    graf3_to_graf1 = np.array(pair["homography"]).reshape(3, 3)

    # The panorama's misregistration at each graf1 pixel p that graf3 sees: |H(H_true p) - p|,
    # over a 4 px grid reaching graf1's borders. Measured: median 0.38 px, max 2.41 px (the
    # core's gtest has the same figures; ECC always gave max 3.38 px); the goal is 3 px.
    height, width = cv2.imread(str(GRAF1)).shape[:2]
    xs = np.r_[np.arange(0, width - 1, 4), width - 1]
    ys = np.r_[np.arange(0, height - 1, 4), height - 1]
    grid = np.array([(x, y) for y in ys for x in xs], float)
    in_graf3 = apply(graf1_to_graf3(), grid)
    inside = np.all((in_graf3 >= 0) & (in_graf3 <= [width - 1, height - 1]), axis=1)
    errors = np.linalg.norm(apply(graf3_to_graf1, in_graf3[inside]) - grid[inside], axis=1)
    assert inside.sum() > 30000
    assert errors.max() <= 3.0 and np.median(errors) <= 0.5, (errors.max(), np.median(errors))

    # The ECC refinement fitted the held-out matches worse, so RANSAC's homography was kept.
    assert pair["refined"] is False
    assert pair["held_out_matches"] >= 50
    assert pair["held_out_median_refined_px"] > pair["held_out_median_ransac_px"]
    assert pair["inliers"] >= 25 and pair["reprojection_error_px"] < 3.0

    # The panorama is the bounding box of graf1 and graf3 warped by the reported homography.
    corners = np.array([[0, 0], [width, 0], [width, height], [0, height]], float)
    box = np.r_[corners, apply(graf3_to_graf1, corners)]
    low = np.floor(np.minimum(box.min(axis=0), 0))
    expected = np.ceil(np.maximum(box.max(axis=0), 0) - low).astype(int)
    assert [report["width"], report["height"]] == list(expected)
    assert cv2.imread(str(out)).shape[:2] == (report["height"], report["width"])


def test_verbose_says_which_homography_was_kept(stitched):
    done, _ = stitched
    pair = json.loads(done.stdout)["pairs"][0]
    assert done.stderr == (
        f"stitch: {GRAF1} + {GRAF3}: {pair['inliers']} inliers of {pair['matches']} matches; "
        "RANSAC kept, ECC refinement rejected: held-out median error "
        f"{pair['held_out_median_refined_px']:.3f} px refined, "
        f"{pair['held_out_median_ransac_px']:.3f} px RANSAC "
        f"({pair['held_out_matches']} held-out matches)\n"
    )


# Four points of the cookie box, read off both images at 10-12x zoom (pixel centres): the corner of
# the printed border (the two thin lines' centres) and three corners of the cookie photograph
# (the edges of its dark frame). The box's other corners are hidden by the rice box beside it.
BOX_POINTS = np.array([(22.0, 10.0), (139.5, 18.5), (138.5, 202.4), (279.5, 203.0)])
SCENE_POINTS = np.array([(126.5, 166.0), (185.3, 176.5), (165.8, 271.6), (243.7, 282.0)])


# Measured: largest error over the four points 1.29 px with SIFT, 3.38 px with ORB (the labels
# are good to about a pixel); AKAZE finds 24 ratio-tested matches, under the 25 needed.
@pytest.mark.parametrize("detector, bound_px", [("sift", 2.5), ("orb", 5.0)])
def test_the_box_is_found_in_the_scene_where_it_was_labelled(tmp_path, detector, bound_px):
    if not BOX.exists():
        pytest.fail(f"no {BOX}: install opencv-doc (tools/debian-packages.txt)")
    done = subprocess.run(
        ["rosrun", "image_converter", "stitch", str(BOX_IN_SCENE), str(BOX),
         "-o", str(tmp_path / "pano.png"), "--detector", detector, "--json"],
        capture_output=True, text=True, timeout=180,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    (pair,) = json.loads(done.stdout)["pairs"]
    box_to_scene = np.array(pair["homography"]).reshape(3, 3)
    errors = np.linalg.norm(apply(box_to_scene, BOX_POINTS) - SCENE_POINTS, axis=1)
    assert errors.max() <= bound_px, errors
