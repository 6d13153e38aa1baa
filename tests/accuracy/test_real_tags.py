"""The parker's AprilTag detector (follow_bot.core.TagDetector, default config) on real photos.

- Multi-tag Duckiebot frames (realdata `apriltag_multiple`: rectified 640x480, tag36h11 0.065 m,
  small and foreshortened tags on signs): each tag labelled by hand, by looking at the frames;
  its id read by comparing its cells, rectified and enlarged, with the family's code. The two
  signs seen edge-on at the left of frame 05 show no legible tag and are not counted. A detector
  configured with each id of the set must find it in >= 95 % of the frames that show it (the
  decimated search alone found 17 of the 27), where the labels put it, and never in a frame
  that does not show it.
- ViSP's real photo (visp-images-data AprilTag.pgm, twelve 0.053 m tags at 0.37-0.56 m, the
  intrinsics of ViSP's testAprilTag) against its ground_truth_pose.txt, ViSP's own regression
  reference: ViSP 3.5 reads libapriltag's corners, whose pixel centres sit at +0.5, as
  integer-centred pixels; our corners are shifted to integer centres, so the reference is
  compared in its convention (principal point moved by half a pixel), where the pose may differ
  by 0.5 mm per tag. In ours the half pixel alone moves the tags 0.4-0.6 mm, as measured.
"""

from pathlib import Path

import cv2
import numpy as np
import pytest

from follow_bot import core

MULTIPLE = "apriltag_multiple"
MULTIPLE_TAG_SIZE = 0.065  # m, realdata README
MULTIPLE_CAMERA = dict(fx=338.5633, fy=338.9393, cx=336.4550, cy=230.4870)  # rectified, D = 0
# Per frame: tag id -> where the tag's centre is (pixels, column and row, within a few pixels).
HAND_LABELS = {
    "test_image_multiple_01.png": {
        22: (291, 252),
        24: (250, 218),
        58: (465, 243),
        85: (306, 206),
        144: (188, 320),
        198: (378, 218),
    },
    "test_image_multiple_02.png": {
        22: (299, 207),
        24: (314, 147),
        85: (376, 155),
        144: (152, 212),
        198: (493, 237),
    },
    "test_image_multiple_03.png": {
        22: (303, 231),
        24: (239, 192),
        58: (546, 177),
        85: (307, 163),
        144: (197, 349),
        198: (403, 161),
    },
    "test_image_multiple_04.png": {
        22: (332, 175),
        24: (377, 137),
        58: (269, 231),
        85: (311, 196),
        144: (219, 296),
        198: (355, 153),
    },
    "test_image_multiple_05.png": {22: (357, 187), 24: (521, 193), 85: (282, 182), 198: (436, 187)},
}
MIN_RECALL = 0.95
CENTRE_TOLERANCE_PX = 5.0

VISP_TAGS = "/usr/share/visp-images-data/ViSP-images/AprilTag/"
VISP_TAG_SIZE = 0.053  # m, ViSP's testAprilTag
VISP_CAMERA = dict(fx=615.1674805, fy=615.1675415, cx=312.1889954, cy=243.4373779)
MAX_TRANSLATION_ERROR_MM = 0.5
MAX_ROTATION_ERROR_DEG = 0.2
# ViSP's tag frame (x right, y up, z out of the tag) in ours (x right, y down, z into the tag).
VISP_TAG_FRAME = np.diag([1.0, -1.0, -1.0])


def test_hand_labelled_tags_found_without_false_ids_on_real_frames(realdata, record_property):
    camera = core.CameraGeometry(**MULTIPLE_CAMERA)
    ids = sorted({tag for labels in HAND_LABELS.values() for tag in labels})
    found, false_ids, misplaced = 0, [], []
    for name, labels in HAND_LABELS.items():
        grey = cv2.imread(str(realdata / MULTIPLE / name), cv2.IMREAD_GRAYSCALE)
        assert grey is not None, name
        for tag in ids:
            detector = core.TagDetector(core.TagDetectorConfig(id=tag, size_m=MULTIPLE_TAG_SIZE))
            seen = detector.detect(grey, camera)
            if seen is None:
                continue
            if tag not in labels:
                false_ids.append((name, tag))
                continue
            found += 1
            centre = seen.corners.mean(axis=0)
            if np.linalg.norm(centre - labels[tag]) > CENTRE_TOLERANCE_PX:
                misplaced.append((name, tag, centre.round(1).tolist()))
    total = sum(len(labels) for labels in HAND_LABELS.values())
    record_property("summary", f"real multi-tag frames: {found}/{total} hand-labelled tags found")
    assert not false_ids
    assert not misplaced
    assert found >= MIN_RECALL * total, f"{found}/{total}"


def visp_reference():
    """ground_truth_pose.txt: per tag '36h11_id:_N' then tx ty tz (m) and theta-u (rad)."""
    path = Path(VISP_TAGS) / "ground_truth_pose.txt"
    try:
        tokens = path.read_text().split()
    except FileNotFoundError:
        pytest.fail(f"no {path}: install Debian's visp-images-data (tools/debian-packages.txt)")
    return {
        int(tokens[i].rsplit("_", 1)[1]): np.array(tokens[i + 1 : i + 7], dtype=float)
        for i in range(0, len(tokens), 7)
    }


def test_pose_on_visp_real_photo_within_half_a_millimetre_of_its_reference(record_property):
    reference = visp_reference()
    grey = cv2.imread(VISP_TAGS + "AprilTag.pgm", cv2.IMREAD_GRAYSCALE)
    assert grey.shape == (480, 640)
    # The reference's pixel convention: libapriltag's corners read as integer-centred.
    half_pixel = dict(VISP_CAMERA, cx=VISP_CAMERA["cx"] - 0.5, cy=VISP_CAMERA["cy"] - 0.5)
    errors = {}
    for tag, pose in sorted(reference.items()):
        detector = core.TagDetector(core.TagDetectorConfig(id=tag, size_m=VISP_TAG_SIZE))
        seen = detector.detect(grey, core.CameraGeometry(**half_pixel))
        assert seen is not None, tag
        rotation, _ = cv2.Rodrigues(pose[3:])
        difference = seen.rotation.T @ rotation @ VISP_TAG_FRAME
        angle = np.degrees(np.arccos(np.clip((np.trace(difference) - 1.0) / 2.0, -1.0, 1.0)))
        errors[tag] = (1000.0 * np.linalg.norm(seen.translation - pose[:3]), angle)
    table = ", ".join(f"{tag}: {mm:.2f} mm {deg:.2f} deg" for tag, (mm, deg) in errors.items())
    record_property("summary", f"ViSP AprilTag.pgm pose vs reference: {table}")
    assert max(mm for mm, _ in errors.values()) < MAX_TRANSLATION_ERROR_MM, table
    assert max(deg for _, deg in errors.values()) < MAX_ROTATION_ERROR_DEG, table
