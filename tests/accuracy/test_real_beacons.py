"""The colour-beacon detector (follow_bot.core.ColourBlobDetector, the beacon chaser's defaults) on
real photographs from Debian's opencv-doc, against hand labels made by looking at them.

smarties.png (413 x 356): sweets on white paper, with specular spots, soft shadows, touching
neighbours and two cut by the frame's edge. Every red, green and blue sweet is found within a few
px of its label, an extra orange colour finds the orange sweets, and no red is reported at an
orange sweet (their shaded sides are as red as a red sweet's pixels). orange.jpg: an orange
filling the frame is not red.
"""

from pathlib import Path

import cv2
import numpy as np
import pytest

from follow_bot import core

DATA = Path("/usr/share/doc/opencv-doc/examples/data")

# Sweet centres (x, y) in px, by eye on the image; those cut by the frame's edge last.
SMARTIES = {
    "red": [(33, 228), (98, 259), (288, 213), (220, 306)],
    "orange": [(205, 211), (134, 327)],
    "green": [(268, 117), (386, 170), (12, 348)],
    "blue": [(376, 81), (347, 237), (294, 320)],
    "brown": [(152, 271), (77, 348)],
}
CUT_BY_THE_EDGE = {(12, 348), (77, 348)}
RADIUS_PX = 26  # by eye: the sweets are ~52 px across
CENTRE_TOLERANCE_PX = 5.0  # a whole sweet's circle centre from its label
EDGE_TOLERANCE_PX = 14.0  # a cut sweet's circle is fitted to its visible arc only


def photo(name: str) -> np.ndarray:
    path = DATA / name
    if not path.exists():
        pytest.fail(f"{path} is missing: install Debian's opencv-doc (tools/debian-packages.txt)")
    return cv2.imread(str(path))


def detector_with_orange() -> core.ColourBlobDetector:
    """The default red, green and blue, and orange: hues 0..20, blobs with a median of 5..20."""
    orange = core.ColourSpec(
        name="orange", hue_centre=10, sensitivity=10, s_min=100, v_min=20,
        median_hue_min=-5, median_hue_max=10,
    )  # fmt: skip
    colours = [core.parse_colour_name(name) for name in ("red", "green", "blue")]
    return core.ColourBlobDetector(core.ColourBlobConfig(colours=[*colours, orange]))


def nearest_label(circle, labels):
    distances = [float(np.hypot(circle[0] - x, circle[1] - y)) for x, y in labels]
    index = int(np.argmin(distances))
    return labels[index], distances[index]


@pytest.fixture(scope="module")
def smarties():
    result = detector_with_orange().detect(photo("smarties.png"))
    assert result.ok, result.error
    for blob in result.colours:  # shown with pytest -s
        print(blob.name, [tuple(round(float(v), 1) for v in c) for c in blob.circles])
    return result


@pytest.mark.parametrize("colour", ["red", "green", "blue", "orange"])
def test_every_sweet_of_a_colour_is_found_at_its_label(smarties, colour):
    circles = smarties.find(colour).circles
    for label in SMARTIES[colour]:
        tolerance = EDGE_TOLERANCE_PX if label in CUT_BY_THE_EDGE else CENTRE_TOLERANCE_PX
        error = min(float(np.hypot(c[0] - label[0], c[1] - label[1])) for c in circles)
        print(f"{colour} {label}: nearest circle {error:.1f} px")
        assert error <= tolerance, f"{colour} sweet at {label}: nearest circle {error:.1f} px"
    for circle in circles:
        if nearest_label(circle, SMARTIES[colour])[0] in CUT_BY_THE_EDGE:
            continue
        assert abs(circle[2] - RADIUS_PX) <= 4.0, f"{colour} circle {circle}: not a sweet's size"


def test_orange_sweets_are_never_red(smarties):
    """Red is reported only at red sweets and at the brown ones (dark red in HSV: hue 173-175)."""
    red_or_brown = SMARTIES["red"] + SMARTIES["brown"]
    for circle in smarties.find("red").circles:
        _, to_orange = nearest_label(circle, SMARTIES["orange"])
        assert to_orange > RADIUS_PX, f"red reported at an orange sweet: {circle}"
        label, error = nearest_label(circle, red_or_brown)
        tolerance = EDGE_TOLERANCE_PX if label in CUT_BY_THE_EDGE else CENTRE_TOLERANCE_PX
        assert error <= tolerance, f"red circle {circle} is at no red sweet"
    for circle in smarties.find("orange").circles:
        _, error = nearest_label(circle, SMARTIES["orange"])
        assert error <= CENTRE_TOLERANCE_PX, f"orange circle {circle} is at no orange sweet"
    # The brown sweet cut by the frame's edge is not judged (too little of its circle is in view).
    assert len(smarties.find("red").circles) == len(red_or_brown) - 1


def test_each_colour_reports_the_sweet_of_the_largest_circle(smarties):
    """The chosen blob is the first circle, the largest (nearest) of them."""
    for colour in ("red", "green", "blue", "orange"):
        blob = smarties.find(colour)
        assert blob.found
        radii = blob.circles[:, 2]
        assert radii[0] == radii.max()
        label, _ = nearest_label(blob.circles[0], SMARTIES[colour])
        tolerance = EDGE_TOLERANCE_PX if label in CUT_BY_THE_EDGE else CENTRE_TOLERANCE_PX
        assert np.hypot(blob.centroid[0] - label[0], blob.centroid[1] - label[1]) <= tolerance


def test_an_orange_is_not_red():
    result = core.ColourBlobDetector().detect(photo("orange.jpg"))
    assert not result.find("red").found, result.find("red").circles
