"""follow_bot.core and image_converter.core, the pybind11 bindings of the C++ cores: the same
results as the C++ library.

Detectors, bit for bit on the same frames (rendered by the harness or generated, written as PNG):
the C++ results come from follow_bot's `core_reference` (LineDetector, ColourBlobDetector),
`marker_probe` (TagDetector, SignDetector) and image_converter's `core_reference` (overlay,
matching, stitching), which print every field exactly and write images as PNG. Controllers:
the steering laws and the parking servo against `core_reference` driving them on the same
frames, the others against the values the gtests assert (follow_bot/test/*_test.cpp,
image_converter/test/velocity_limiter_test.cpp), within 1e-9.
Bad configs raise ValueError with the C++ validate() message; bad arrays raise TypeError or
ValueError, never crash; frames are read in place, row-strided crops included.
"""

import json
import math
import re
import subprocess

import cv2
import numpy as np
import pytest

from follow_bot import core
from harness.render import Renderer
from harness.testing import REPO, textured_scene
from harness.world import WORLDS_DIR
from harness.world_file import load_world
from image_converter import core as ic_core

# Robot poses (x, y, yaw): on the course's first straight, off to either side, across a curve,
# facing away from every line.
COURSE_POSES = [
    (-2.5, -3.5, 0.0), (-2.0, -3.45, 0.1), (-1.0, -3.6, -0.2), (1.6, -3.2, 0.9),
    (2.5, -2.0, 1.6), (-2.5, -3.5, 3.14), (0.0, 0.0, 0.5),
]  # fmt: skip
RGB_POSES = [
    (0.0, 0.0, 0.0), (0.5, 0.3, 0.1), (1.0, -0.5, -0.2), (2.0, 0.4, 0.45), (0.0, 0.0, 3.14),
]  # fmt: skip
DUMPSTER_POSES = [(0.0, 0.0, 0.0), (1.0, 1.0, -0.3), (2.0, -1.0, 0.4)]
# Tag views (distance m, incidence deg, bearing deg), as tests/accuracy/test_tag_pose_accuracy.py.
TAG_VIEWS = [(0.5, 0, 0), (1.0, 45, -5), (1.5, 25, 12), (2.0, 0, 0), (3.0, -50, -10), (6.0, 0, 0)]


def render(world_name, poses, tmp_path, **variant):
    """The harness's BGR frames of a world at `poses`, and the PNG files holding them."""
    renderer = Renderer(load_world(WORLDS_DIR / f"{world_name}.yaml"), **variant)
    frames, files = [], []
    for i, pose in enumerate(poses):
        frames.append(renderer.render(pose, frame=i))
        files.append(str(tmp_path / f"{world_name}{i:02d}.png"))
        assert cv2.imwrite(files[-1], frames[-1])
    return renderer, frames, files


def run_json(*command):
    out = subprocess.run(command, capture_output=True, text=True, check=True, timeout=120)
    return [json.loads(line) for line in out.stdout.splitlines()]


def band_fields(band):
    return {name: getattr(band, name) for name in BAND_FIELDS}


BAND_FIELDS = (
    "found", "pixel_count", "centroid_x", "centroid_y", "error_px", "error_normalised",
    "confidence", "row_begin", "row_end", "centre_pixel_count", "centre_found", "centre_x",
    "centre_y",
)  # fmt: skip


# ---- detectors: bit for bit against the C++ library --------------------------------------------


def test_line_detector_equals_cpp_on_course_frames(tmp_path):
    _, frames, files = render("course", COURSE_POSES, tmp_path, noise_sigma=4.0)
    detector = core.LineDetector()
    expected = run_json("rosrun", "follow_bot", "core_reference", "--line", *files)
    found = 0
    for frame, cpp in zip(frames, expected, strict=True):
        m = detector.detect(frame)
        assert m.ok and (m.image_width, m.image_height) == (cpp["image_width"], cpp["image_height"])
        assert band_fields(m.band) == cpp["band"], cpp["frame"]
        assert band_fields(m.look_ahead) == cpp["look_ahead"], cpp["frame"]
        found += m.band.found
    assert 3 <= found < len(frames)  # the poses see the line and miss it


def test_line_detector_reads_crops_in_place_and_matches_a_copy():
    # The lecture's stripe (line_detector_test.cpp: FindsAStripeAtItsColumn) inside a larger
    # array, passed as a row-strided view.
    canvas = np.full((600, 800, 3), (110, 115, 120), np.uint8)
    canvas[50:530, 580:591] = (0, 220, 230)
    view = canvas[50:530, 80:720]
    assert not view.flags.c_contiguous
    band = core.LineDetector().detect(view).band
    assert band_fields(band) == band_fields(
        core.LineDetector().detect(np.ascontiguousarray(view)).band
    )
    assert (band.found, band.pixel_count, band.centroid_x, band.centroid_y) == (
        True, 220, 505.0, 369.5,
    )  # fmt: skip
    assert (band.error_px, band.confidence, band.row_begin, band.row_end) == (185.0, 1.0, 360, 380)


def test_line_detector_keeps_the_blob_of_the_previous_sighting():
    # line_detector_test.cpp: KeepsTheBlobNearestThePreviousSighting.
    grey, yellow = (110, 115, 120), (0, 220, 230)
    line_only = np.full((480, 640, 3), grey, np.uint8)
    line_only[:, 300:311] = yellow
    with_tape = line_only.copy()
    with_tape[365:, 500:540] = yellow
    detector = core.LineDetector()
    previous = detector.detect(line_only)
    assert detector.detect(with_tape).band.pixel_count == 11 * 20 + 40 * 15
    band = detector.detect(with_tape, previous).band
    assert (band.found, band.pixel_count, band.centroid_x, band.centroid_y) == (
        True, 220, 305.0, 369.5,
    )  # fmt: skip
    assert band_fields(detector.detect(line_only, previous).band) == band_fields(previous.band)


def test_line_detector_debug_mask_and_drawing():
    frame = np.full((480, 640, 3), (110, 115, 120), np.uint8)
    frame[:, 100:110] = (0, 220, 230)
    detector = core.LineDetector()
    mask = detector.debug_mask(frame)
    assert mask.shape == (480, 640) and mask.dtype == np.uint8
    assert np.count_nonzero(mask) == 200 and np.all(mask[360:380, 100:110] == 255)
    drawn = frame.copy()
    assert detector.draw_debug(drawn, detector.detect(frame))
    assert tuple(drawn[370, 104]) == (0, 0, 255)  # the lecture's red dot at the centroid
    with pytest.raises(ValueError, match="read-only"):
        frame.flags.writeable = False
        detector.draw_debug(frame, detector.detect(frame))


def blob_fields(blob):
    return {
        "name": blob.name, "found": blob.found, "blob_count": blob.blob_count,
        "area": blob.area, "centroid": list(blob.centroid),
        "bounding_box": list(blob.bounding_box), "contour": blob.contour.tolist(),
    }  # fmt: skip


@pytest.mark.parametrize(
    "world_name, poses, variant",
    [
        ("rgb", RGB_POSES, {}),
        ("rgb", RGB_POSES, {"gain": 0.5, "noise_sigma": 8.0}),
        ("dumpster", DUMPSTER_POSES, {}),
    ],
    ids=["rgb", "rgb_dark_noisy", "dumpster"],
)
def test_colour_blob_detector_equals_cpp(tmp_path, world_name, poses, variant):
    _, frames, files = render(world_name, poses, tmp_path, **variant)
    # The dumpster is a box: detected without the roundness gate, as the approach mode does.
    box = world_name == "dumpster"
    config = core.ColourBlobConfig(roundness_tolerance=0.0) if box else core.ColourBlobConfig()
    detector = core.ColourBlobDetector(config)
    mode = "--blobs-any-shape" if box else "--blobs"
    expected = run_json("rosrun", "follow_bot", "core_reference", mode, *files)
    found = 0
    for frame, cpp in zip(frames, expected, strict=True):
        result = detector.detect(frame)
        assert result.ok and result.image_width == cpp["image_width"]
        assert len(result.colours) == len(cpp["colours"])
        for blob, want in zip(result.colours, cpp["colours"], strict=True):
            # float fields: the C++ floats, printed to 9 digits (exact for a float)
            assert np.float32(blob.circle_radius) == np.float32(want.pop("circle_radius"))
            assert np.all(np.float32(blob.circle_centre) == np.float32(want.pop("circle_centre")))
            assert blob_fields(blob) == want, cpp["frame"]
            assert result.find(blob.name).area == blob.area
            found += blob.found
    assert found >= len(frames)  # most frames hold a blob or more
    assert detector.mask(frames[0], "green").shape == frames[0].shape[:2]
    assert result.find("purple") is None


def tag_frames(tmp_path):
    """The parking world's tag at TAG_VIEWS: the tag, renderer, grey frames and their files."""
    world = load_world(WORLDS_DIR / "parking.yaml")
    tag = world.objects[0]
    renderer = Renderer(world)
    greys, files = [], []
    for i, pose in enumerate(views_of(tag.pose, TAG_VIEWS)):
        greys.append(cv2.cvtColor(renderer.render(pose, frame=i), cv2.COLOR_BGR2GRAY))
        files.append(str(tmp_path / f"tag{i:02d}.png"))
        assert cv2.imwrite(files[-1], greys[-1])
    return tag, renderer, greys, files


def views_of(marker_pose, views):
    """Robot poses seeing a marker at (distance m, incidence deg, bearing deg)."""
    x, y, _, yaw = marker_pose
    poses = []
    for distance, incidence, bearing in views:
        a = yaw + math.radians(incidence)
        rx, ry = x + distance * math.cos(a), y + distance * math.sin(a)
        poses.append((rx, ry, math.atan2(y - ry, x - rx) - math.radians(bearing)))
    return poses


def test_tag_detector_equals_cpp_over_a_sequence(tmp_path):
    tag, renderer, greys, files = tag_frames(tmp_path)
    cam = renderer.camera
    camera = core.CameraGeometry(fx=cam.fx, fy=cam.fy, cx=cam.cx, cy=cam.cy)
    args = ["--tag-size", str(tag.size), "--tag-id", str(tag.tag_id), "--tag-family", tag.family]
    for flag, value in (("--fx", cam.fx), ("--fy", cam.fy), ("--cx", cam.cx), ("--cy", cam.cy)):
        args += [flag, repr(value)]
    expected = run_json("rosrun", "follow_bot", "marker_probe", *args, *files)
    # One detector over the sequence, as the probe: the previous pose settles the ambiguity.
    detector = core.TagDetector(
        core.TagDetectorConfig(family=tag.family, id=tag.tag_id, size_m=tag.size)
    )
    for grey, cpp in zip(greys, expected, strict=True):
        seen = detector.detect(grey, camera)
        assert (seen is not None) == cpp["found"], cpp["frame"]
        if seen is None:
            continue
        assert seen.id == tag.tag_id
        assert seen.corners.tolist() == cpp["corners"]
        assert seen.rotation.tolist() == cpp["rotation"]
        assert seen.translation.tolist() == cpp["translation"]
        assert seen.quality == cpp["quality"]
        assert seen.reprojection_error_px == cpp["reprojection_error_px"]
    assert sum(c["found"] for c in expected) >= len(TAG_VIEWS) - 1
    assert detector.detect(np.zeros((480, 640), np.uint8), camera) is None


SIGN_VIEWS = [(1.0, 0, 0), (1.2, 20, -5), (1.5, -25, 8), (2.0, 0, 0), (2.5, 35, 0)]


def test_sign_detector_equals_cpp_over_a_sequence(tmp_path):
    world = load_world(WORLDS_DIR / "parking_sign.yaml")
    (sign,) = world.objects
    renderer = Renderer(world, noise_sigma=2.0, seed=1)
    greys, files = [], []
    for i, pose in enumerate(views_of(sign.pose, SIGN_VIEWS)):
        greys.append(cv2.cvtColor(renderer.render(pose, frame=i), cv2.COLOR_BGR2GRAY))
        files.append(str(tmp_path / f"sign{i:02d}.png"))
        assert cv2.imwrite(files[-1], greys[-1])
    expected = run_json(
        "rosrun", "follow_bot", "marker_probe", "--sign", str(sign.path), "--width",
        repr(sign.width), *files,
    )  # fmt: skip
    # One detector over the sequence, as the probe: it tracks the sign from frame to frame.
    detector = core.SignDetector(core.SignDetectorConfig(image_path=str(sign.path),
                                                         width_m=sign.width))  # fmt: skip
    assert detector.reference_features >= 50
    tracked = 0
    for grey, cpp in zip(greys, expected, strict=True):
        seen = detector.detect(grey, core.CameraGeometry())
        assert (seen is not None) == cpp["found"], cpp["frame"]
        if seen is None:
            continue
        assert seen.id == 0
        assert seen.corners.tolist() == cpp["corners"]
        assert seen.rotation.tolist() == cpp["rotation"]
        assert seen.translation.tolist() == cpp["translation"]
        assert (seen.quality, seen.reprojection_error_px) == (
            cpp["quality"], cpp["reprojection_error_px"],
        )  # fmt: skip
        tracked += detector.last_tracked
    assert sum(c["found"] for c in expected) >= len(SIGN_VIEWS) - 1
    detector.reset()
    assert detector.detect(np.zeros((480, 640), np.uint8)) is None and not detector.last_tracked


# ---- controllers: the C++ driving them on the same frames, and the gtests' values -------------


def twist_fields(twist):
    return (twist.linear, twist.angular)


def assert_twist_close(twist, cpp, frame):
    assert twist.linear == pytest.approx(cpp["linear"], abs=1e-9), frame
    assert twist.angular == pytest.approx(cpp["angular"], abs=1e-9), frame


# The robot drives along the course's first straight and off it, then looks away (line lost).
STEER_POSES = [(-2.5 + 0.02 * i, -3.5 + 0.004 * i, 0.05 * math.sin(i / 3)) for i in range(12)] + [
    (0.0, 0.0, 0.5 + 0.01 * i) for i in range(6)
]


@pytest.mark.parametrize("mode", ["lecture", "pd", "path"])
def test_steering_laws_equal_cpp_on_course_frames(tmp_path, mode):
    _, frames, files = render("course", STEER_POSES, tmp_path, noise_sigma=4.0)
    expected = run_json("rosrun", "follow_bot", "core_reference", "--steer", mode, *files)
    detector = core.LineDetector()
    law = core.make_steering_law(core.SteeringConfig(mode=mode), core.CameraGeometry())
    assert law.mode == core.SteeringMode(mode)
    applied = core.Twist2D()
    states = set()
    for i, (frame, cpp) in enumerate(zip(frames, expected, strict=True)):
        applied = law.step(detector.detect(frame), i / 30.0, applied, applied)
        assert_twist_close(applied, cpp, cpp["frame"])
        assert law.state.name == cpp["state"], cpp["frame"]
        states.add(cpp["state"])
    # The sequence sees the line, then loses it (path still steers on its memory of the line).
    assert states == ({"following"} if mode == "path" else {"following", "lost"})


def test_mounting_from_transform_reads_tf_as_the_nodes_do():
    # A URDF optical frame (rpy -90, 0, -90 deg: z forward, x right, y down) 0.10 m ahead and
    # 0.28 m above a base_link 0.02 m above the floor: a level camera 0.30 m up.
    level = (-0.5, 0.5, -0.5, 0.5)
    intrinsics = core.CameraGeometry(fx=400.0, fy=400.0, cx=160.0, cy=120.0)
    camera, warning = core.mounting_from_transform((0.10, 0.0, 0.28), level, 0.02, intrinsics)
    mounting = (camera.height_m, camera.pitch_rad, camera.x_offset_m)
    assert mounting == pytest.approx((0.30, 0.0, 0.10))
    assert (camera.fx, camera.cx) == (400.0, 160.0) and warning == ""
    assert core.same_intrinsics(camera, intrinsics) and not core.same_mounting(camera, intrinsics)
    assert core.describe_mounting(camera) == "height 0.300 m, pitch 0.0 deg down, x offset 0.100 m"
    _, warning = core.mounting_from_transform((0.10, 0.05, 0.28), level, 0.02, intrinsics)
    assert "0.05 m to the side" in warning  # an offset the model leaves out
    upside_down = (0.5, 0.5, 0.5, 0.5)  # the optical y axis points up: rolled 180 deg
    with pytest.raises(ValueError, match="roll"):
        core.mounting_from_transform((0.10, 0.0, 0.28), upside_down, 0.02, intrinsics)
    assert core.WAITING_FOR_MOUNTING == "waiting for camera mounting"


def test_path_law_without_a_camera_is_pd_and_exposes_its_memory():
    config = core.SteeringConfig(mode="path")
    assert isinstance(core.make_steering_law(config), core.PdLaw)
    law = core.make_steering_law(config, core.CameraGeometry())
    assert isinstance(law, core.PathLaw) and law.path_points().shape == (0, 2)
    band = core.BandMeasurement(found=True, pixel_count=200, centroid_x=320.0, centroid_y=370.0,
                                centre_pixel_count=200, centre_found=True, centre_x=320.0,
                                centre_y=370.0, confidence=1.0, row_begin=360, row_end=380,
                                spans=[core.RowSpan(row=370, left=315.0, right=325.0)])  # fmt: skip
    law.step(core.LineObservation(measurement=core.LineMeasurement(
        image_width=640, image_height=480, band=band), stamp=0.0))  # fmt: skip
    assert law.path_points().shape == (1, 2) and law.path_state.points == 1
    assert law.path_points()[0, 1] == pytest.approx(0.0, abs=1e-12)  # straight ahead


def test_floor_centre_of_row_spans():
    camera = core.CameraGeometry()
    band = core.BandMeasurement(spans=[core.RowSpan(row=float(row), left=310.0, right=330.0)
                                       for row in range(360, 380)])  # fmt: skip
    x, y = core.floor_centre(band, camera)
    assert 0.3 < x < 0.6 and y == pytest.approx(0.0, abs=1e-12)  # straight ahead, in the band
    assert core.floor_centre(core.BandMeasurement(), camera) is None


def seen_at_error(e):
    """A found band at normalised error e (line_controller_test.cpp's seenAtError)."""
    centroid_x = 320.0 * (1.0 + e)
    band = core.BandMeasurement(found=True, pixel_count=200, centroid_x=centroid_x,
                                centroid_y=370.0, error_px=centroid_x - 320.0,
                                error_normalised=(centroid_x - 320.0) / 320.0,
                                confidence=1.0)  # fmt: skip
    return core.LineMeasurement(image_width=640, image_height=480, band=band)


def test_pd_law_and_line_search_as_the_gtests():
    # line_controller_test.cpp: PdLaw.LostThenSearchingThenGivesUpThenResumes
    law = core.PdLaw()
    unseen = core.LineMeasurement(image_width=640, image_height=480)
    law.step(seen_at_error(0.6), 0.0)
    assert twist_fields(law.step(unseen, 0.5)) == pytest.approx((0.05, -0.4), abs=1e-9)
    assert law.state == core.LineState.lost
    law.step(unseen, 1.0)
    assert twist_fields(law.step(unseen, 1.01)) == pytest.approx((0.0, -0.6), abs=1e-9)
    assert law.state == core.LineState.searching
    assert twist_fields(law.step(unseen, 13.01)) == (0.0, 0.0)
    assert law.state == core.LineState.gave_up
    assert law.step(seen_at_error(-0.2), 501.0).angular > 0.0
    assert law.state == core.LineState.following
    # The same state machine alone.
    search = core.LineSearch()
    search.seen(0.0, 0.6)
    assert twist_fields(search.unseen(0.5)) == pytest.approx((0.05, -0.4), abs=1e-9)
    assert twist_fields(search.unseen(1.01)) == pytest.approx((0.0, -0.6), abs=1e-9)
    assert search.state == core.LineState.searching
    search.reset()
    assert search.state == core.LineState.lost
    # The lecture: linear 0.2, angular -error_px / 100 whenever a pixel is seen.
    lecture = core.LectureLaw().step(seen_at_error(0.25), 0.0)
    assert twist_fields(lecture) == pytest.approx((0.2, -0.8), abs=1e-9)


def test_parking_servo_equals_cpp_over_a_tag_sequence(tmp_path):
    tag, _, greys, files = tag_frames(tmp_path)
    expected = run_json(
        "rosrun", "follow_bot", "core_reference", "--park", repr(tag.size), str(tag.tag_id),
        tag.family, *files,
    )  # fmt: skip
    detector = core.TagDetector(
        core.TagDetectorConfig(family=tag.family, id=tag.tag_id, size_m=tag.size)
    )
    servo = core.ParkingServo(core.ParkingServoConfig())
    camera = core.CameraGeometry()
    for i, (grey, cpp) in enumerate(zip(greys, expected, strict=True)):
        marker = detector.detect(grey, camera)
        assert_twist_close(servo.update(marker, i / 30.0), cpp, cpp["frame"])
        assert servo.state.name == cpp["state"], cpp["frame"]
        error = servo.last_error
        assert (error is None) == (cpp["error"] is None)
        if error is not None:
            for name, value in cpp["error"].items():
                assert getattr(error, name) == pytest.approx(value, abs=1e-9), (cpp["frame"], name)
    assert servo.state != core.ParkingState.searching


def test_parking_error_of_a_marker_made_in_python():
    # A marker 1 m straight ahead of a level camera, facing it (its z, into the marker, is the
    # camera's z: the identity rotation): 1 m along its normal, square and centred.
    camera = core.CameraGeometry(pitch_rad=0.0)
    marker = core.MarkerObservation(id=0, rotation=np.eye(3), translation=(0.0, 0.0, 1.0))
    error = core.parking_error(marker, camera)
    assert (error.along, error.lateral, error.heading, error.bearing) == pytest.approx(
        (1.0, 0.0, 0.0, 0.0), abs=1e-9
    )
    with pytest.raises(ValueError, match="rotation must be 3x3"):
        marker.rotation = np.eye(2)


def test_velocity_limiter_as_the_gtests():
    limiter = core.VelocityLimiter()  # 0.7 m/s, pi rad/s, 1 m/s^2, 6 rad/s^2
    out = limiter.limit(core.Twist2D(linear=5.0, angular=-10.0), 100.0)
    assert (out.linear, out.angular) == (0.7, -math.pi)
    limiter.reset()
    for step in (1, 2):  # RateLimitsBothWays
        out = limiter.limit(core.Twist2D(linear=0.7, angular=3.0), 0.1)
        assert out.linear == pytest.approx(0.1 * step, abs=1e-9)
        assert out.angular == pytest.approx(0.6 * step, abs=1e-9)
    out = limiter.limit(core.Twist2D(linear=0.0, angular=-3.0), 0.05)
    assert out.linear == pytest.approx(0.15, abs=1e-9)
    assert out.angular == pytest.approx(0.9, abs=1e-9)
    assert limiter.last_output.linear == out.linear
    stopped = limiter.stop()
    assert (stopped.linear, stopped.angular) == (0.0, 0.0)
    out = limiter.limit(core.Twist2D(linear=math.nan, angular=math.inf), 10.0)
    assert (out.linear, out.angular) == (0.0, 0.0)
    reversing = core.VelocityLimiter(core.VelocityLimiterConfig(allow_reverse=True))
    assert reversing.limit(core.Twist2D(linear=-5.0), 100.0).linear == -0.7
    assert core.VelocityLimiter().limit(core.Twist2D(linear=-0.5), 100.0).linear == 0.0


def test_frame_watchdog_as_the_gtests():
    watchdog = core.FrameWatchdog(0.5)
    assert watchdog.expired(10.0) and not watchdog.should_send_stop(10.0)
    watchdog.frame_arrived(2.0)
    assert not watchdog.expired(2.5) and watchdog.expired(2.5001)
    assert not watchdog.should_send_stop(2.5)
    assert watchdog.should_send_stop(2.6) and not watchdog.should_send_stop(2.7)
    assert watchdog.last_frame == 2.0 and watchdog.timeout == 0.5
    watchdog.reset()
    assert watchdog.expired(2.1)
    for bad in (0.0, -1.0, math.nan, math.inf):
        with pytest.raises(ValueError, match="timeout must be finite and > 0"):
            core.FrameWatchdog(bad)
    # A 5 Hz camera: 3 frame periods, its expected one until measured.
    slow = core.FrameWatchdog(core.WATCHDOG_TIMEOUT, expected_period_s=0.2)
    assert slow.timeout == pytest.approx(0.6) and slow.min_timeout == core.WATCHDOG_TIMEOUT
    for t in (1.0, 1.2, 1.4):
        slow.frame_arrived(t)
    assert slow.frame_interval == pytest.approx(0.2) and not slow.expired(1.95)
    assert slow.expired(2.05) and core.EXPECTED_FRAME_RATE == 0.0


def blob(name, centroid_x, area):
    """A found blob as beacon_controller_test.cpp makes them."""
    radius = math.sqrt(area / math.pi)
    return core.ColourBlob(
        name=name, found=True, blob_count=1, area=area, centroid=(centroid_x, 240.0),
        circle_centre=(centroid_x, 240.0), circle_radius=radius,
        bounding_box=(round(centroid_x - radius), round(240 - radius), round(2 * radius) + 1,
                      round(2 * radius) + 1),
    )  # fmt: skip


def blobs(*colours):
    return core.BlobResult(image_width=640, image_height=480, colours=list(colours))


def test_beacon_controller_follow_mode_as_the_gtests():
    absent = [core.ColourBlob(name=n) for n in ("red", "green", "blue")]
    nothing = blobs(*absent)
    controller = core.BeaconController()
    config = controller.config
    twist = controller.update(nothing, 0.0)
    assert controller.state == core.BeaconState.searching
    assert (twist.linear, twist.angular) == (0.0, config.search_rate)
    twist = controller.update(blobs(absent[0], blob("green", 480.0, 2000.0), absent[2]), 0.1)
    assert controller.state == core.BeaconState.approaching
    assert twist.linear == config.approach_speed
    assert twist.angular == pytest.approx(-config.turn_gain * 0.5, abs=1e-9)
    twist = controller.update(blobs(absent[0], blob("green", 160.0, 2000.0), absent[2]), 0.2)
    assert twist.angular == pytest.approx(config.turn_gain * 0.5, abs=1e-9)
    close = blobs(absent[0], blob("green", 330.0, config.close_area), absent[2])
    twist = controller.update(close, 0.3)
    assert controller.state == core.BeaconState.holding and twist.linear == 0.0
    red = blobs(blob("red", 500.0, 800.0), blob("green", 400.0, 2000.0), absent[2])
    twist = controller.update(red, 0.4)
    assert controller.state == core.BeaconState.stopped_by_red
    assert (twist.linear, twist.angular) == (0.0, 0.0)
    controller.reset()
    assert controller.update(nothing, 0.0).angular == config.search_rate


def test_beacon_controller_approach_mode_range_from_the_cpp():
    ball = core.BeaconObject(shape="sphere", size_m=0.2)
    config = core.BeaconControllerConfig(mode="approach", target=ball)
    assert config.mode == core.BeaconMode.approach
    controller = core.BeaconController(config)
    sphere = blob("green", 320.0, math.pi * 40.0**2)
    twist = controller.update(blobs(core.ColourBlob(name="red"), sphere), 0.0)
    estimate = core.estimate_range(sphere, 640, 480, config.camera, config.target)
    assert controller.last_range == estimate.best() == estimate.from_size
    assert controller.last_bearing == pytest.approx(0.0, abs=1e-9)
    want = min(config.max_linear, config.k_range * (estimate.from_size - config.stop_distance))
    assert twist.linear == pytest.approx(want, abs=1e-9)


# ---- image_converter.core: bit for bit against the C++ library ---------------------------------


def run_ic_reference(*args):
    return run_json("rosrun", "image_converter", "core_reference", *map(str, args))[0]


def pair_fields(pair):
    return {
        "error": pair.error, "homography": pair.homography.ravel().tolist(),
        "keypoints_a": pair.keypoints_a, "keypoints_b": pair.keypoints_b,
        "matches": pair.matches, "inliers": pair.inliers,
        "reprojection_error_px": pair.reprojection_error_px, "refined": pair.refined,
        "held_out_matches": pair.held_out_matches,
        "held_out_median_ransac_px": pair.held_out_median_ransac_px,
        "held_out_median_refined_px": pair.held_out_median_refined_px,
    }  # fmt: skip


def test_overlay_equals_cpp_and_draws_in_place(tmp_path):
    frame = textured_scene(640, 480, 3)
    assert cv2.imwrite(str(tmp_path / "in.png"), frame)
    assert run_ic_reference("--overlay", tmp_path / "in.png", tmp_path / "out.png")["drawn"]
    view = np.full((500, 700, 3), 7, np.uint8)
    view[10:490, 30:670] = frame
    crop = view[10:490, 30:670]  # drawn through a row-strided view, in place
    assert ic_core.draw_overlay(crop)
    assert np.array_equal(crop, cv2.imread(str(tmp_path / "out.png")))
    assert tuple(crop[240, 320 + 25]) == (0, 0, 255) and np.all(view[:10] == 7)
    small = np.zeros((50, 60, 3), np.uint8)
    assert not ic_core.draw_overlay(small) and not small.any()


@pytest.fixture(scope="module")
def overlapping_views(tmp_path_factory):
    folder = tmp_path_factory.mktemp("ic_core")
    scene = textured_scene(900, 400, 1)
    views = {"left": scene[:, :500], "right": scene[:, 300:800]}  # 200 px overlap
    for name, view in views.items():
        assert cv2.imwrite(str(folder / f"{name}.png"), view)
    return folder, views


def test_match_pair_equals_cpp(overlapping_views):
    folder, views = overlapping_views
    cpp = run_ic_reference("--match", folder / "left.png", folder / "right.png")
    pair = ic_core.match_pair(views["left"], views["right"])
    assert pair.ok and pair.inliers >= 25
    assert pair_fields(pair) == cpp
    # B's pixel (0, 0) lies 300 px right of A's
    x, y = ic_core.apply_homography(pair.homography, (0.0, 0.0))
    assert (x, y) == pytest.approx((300.0, 0.0), abs=0.5)
    grey = ic_core.match_pair(cv2.cvtColor(views["left"], cv2.COLOR_BGR2GRAY), views["right"])
    assert grey.ok
    blank = ic_core.match_pair(views["left"], np.full((400, 500, 3), 90, np.uint8))
    assert not blank.ok and "blank" in blank.error


def test_stitch_pair_equals_cpp(overlapping_views, tmp_path):
    folder, views = overlapping_views
    panorama = tmp_path / "p.png"
    cpp = run_ic_reference("--stitch", folder / "left.png", folder / "right.png", panorama)
    result = ic_core.stitch_pair(views["left"], views["right"])
    assert result.ok and list(result.origin_of_first) == cpp["origin_of_first"]
    assert [pair_fields(p) for p in result.pairs] == cpp["pairs"]
    assert np.array_equal(result.panorama, cv2.imread(str(panorama)))
    assert result.panorama.shape[1] == pytest.approx(800, abs=2)


def test_stitch_by_rotation_equals_cpp(tmp_path):
    cylinder = textured_scene(1500, 700, 2)
    f = 320.0 / math.tan(math.radians(30.0))
    u, v = np.meshgrid(np.arange(640, dtype=np.float64), np.arange(480, dtype=np.float64))
    x, y = (u - 320.0) / f, (v - 240.0) / f
    images, args = [], []
    for i, yaw in enumerate((0.3, 0.0, -0.3)):
        wx, wz = math.cos(yaw) * x - math.sin(yaw), math.sin(yaw) * x + math.cos(yaw)
        map_x = (f * np.arctan2(wx, wz) + 750.0).astype(np.float32)
        map_y = (f * y / np.hypot(wx, wz) + 350.0).astype(np.float32)
        images.append(cv2.remap(cylinder, map_x, map_y, cv2.INTER_LINEAR))
        assert cv2.imwrite(str(tmp_path / f"turn{i}.png"), images[-1])
        args += [repr(yaw), tmp_path / f"turn{i}.png"]
    camera = ic_core.TurningCamera(fx=f, fy=f, cx=320.0, cy=240.0)
    cpp = run_ic_reference("--rotation", f, f, 320.0, 240.0, 0.0, tmp_path / "p.png", *args)
    result = ic_core.stitch_by_rotation(images, [0.3, 0.0, -0.3], camera)
    assert result.ok and cpp["error"] == ""
    assert list(result.origin_of_first) == cpp["origin_of_first"]
    assert np.array_equal(result.panorama, cv2.imread(str(tmp_path / "p.png")))


# ---- configs and bad input ---------------------------------------------------------------------


def bad_camera():
    camera = core.CameraGeometry()
    camera.fx = -1.0  # attributes are not checked on assignment, configs on construction
    return camera


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda: core.ColourBlobConfig(colours=[core.parse_colour_name("red"),
                                                core.ColourSpec(name="green", hue_centre=60,
                                                                sensitivity=95)]),
         "colours[1] (green): sensitivity must be in [0, 90], got 95"),
        (lambda: core.ColourBlobConfig(open_kernel=4),
         "open_kernel must be 0 (off) or an odd size, got 4"),
        (lambda: core.BeaconControllerConfig(stop_distance=0.0),
         "stop_distance must be > 0, got 0"),
        (lambda: core.BeaconControllerConfig(stop_colour="green"),
         "follow_colour and stop_colour must differ, both are 'green'"),
        (lambda: core.CameraGeometry(fx=-1.0), "fx must be > 0, got -1"),
        (lambda: core.BeaconControllerConfig(camera=bad_camera()), "camera.fx must be > 0, got -1"),
        (lambda: core.LineDetectorConfig(min_pixels=0), "min_pixels must be >= 1, got 0"),
        (lambda: core.VelocityLimiterConfig(max_linear=0.0), "max_linear must be > 0, got 0"),
        (lambda: core.SteeringConfig(pd=core.PdConfig(kp=-1.0)), "kp must be >= 0, got -1"),
        (lambda: core.SteeringConfig(mode="path", min_linear=0.5),
         "min_linear (0.5) must be <= max_linear (0.3)"),
        (lambda: core.SignDetectorConfig(image_path="sign.png", width_m=0.0),
         "width_m must be > 0, got 0"),
        (lambda: core.ParkingServoConfig(gain=-1.0), "gain must be > 0, got -1"),
        (lambda: ic_core.OverlayConfig(radius_px=0), "radius_px must be > 0, got 0"),
        (lambda: ic_core.MatchOptions(ratio=1.5), "ratio must be in (0, 1], got 1.5"),
        (lambda: ic_core.TurningCamera(fx=0.0), "fx must be > 0"),
    ],
)  # fmt: skip
def test_bad_configs_raise_value_error_with_the_cpp_message(make, message):
    with pytest.raises(ValueError) as raised:
        make()
    assert str(raised.value) == message


def test_detectors_validate_configs_changed_after_construction():
    config = core.LineDetectorConfig()
    config.band.rows = 0
    assert config.validate() == "band.rows must be in [1, 65536], got 0"
    with pytest.raises(ValueError, match=r"^LineDetector: band.rows must be in \[1, 65536\]"):
        core.LineDetector(config)
    tag = core.TagDetectorConfig(family="tag36h11", id=600)
    with pytest.raises(ValueError, match="id must be < 587 for tag36h11, got 600"):
        core.TagDetector(tag)
    with pytest.raises(TypeError, match="unexpected keyword argument 'min_pixel'"):
        core.LineDetectorConfig(min_pixel=3)
    with pytest.raises(ValueError, match="mode: unknown value 'follow'"):
        core.BeaconControllerConfig(mode="follow")
    with pytest.raises(ValueError, match="mode: unknown value 'lectures'"):
        core.SteeringConfig(mode="lectures")
    with pytest.raises(ValueError, match="cannot read the sign image '/nonexistent.png'"):
        core.SignDetector(core.SignDetectorConfig(image_path="/nonexistent.png", width_m=0.4))
    overlay = ic_core.OverlayConfig()
    overlay.thickness_px = 0
    with pytest.raises(ValueError, match="thickness_px must be > 0, got 0"):
        ic_core.draw_overlay(np.zeros((100, 100, 3), np.uint8), overlay)


@pytest.mark.parametrize(
    "frame, error",
    [
        (np.zeros((480, 640, 3), np.float32), TypeError),
        (np.zeros((480, 640, 3), np.int8), TypeError),
        (np.zeros((480, 640), np.uint8), ValueError),
        (np.zeros((480, 640, 4), np.uint8), ValueError),
        (np.zeros((2, 480, 640, 3), np.uint8), ValueError),
        (np.zeros((480, 640, 3), np.uint8)[:, ::2], ValueError),  # columns strided
        (np.zeros((480, 640, 3), np.uint8)[::-1], ValueError),  # rows reversed
        (np.zeros((3, 480, 640), np.uint8).transpose(1, 2, 0), ValueError),  # planar
        ([[1, 2, 3]], TypeError),
    ],
    ids=["float32", "int8", "grey", "bgra", "4d", "col_strided", "flipped", "planar", "list"],
)  # fmt: skip
def test_bad_colour_frames_raise(frame, error):
    for detect in (core.LineDetector().detect, core.ColourBlobDetector().detect):
        with pytest.raises(error):
            detect(frame)


def test_bad_grey_frames_raise_and_empty_frames_are_reported():
    detector = core.TagDetector(core.TagDetectorConfig())
    with pytest.raises(ValueError, match="HxW uint8 grey"):
        detector.detect(np.zeros((480, 640, 3), np.uint8))
    with pytest.raises(TypeError, match="dtype"):
        detector.detect(np.zeros((480, 640), np.uint16))
    assert detector.detect(np.zeros((0, 0), np.uint8)) is None
    empty = core.LineDetector().detect(np.zeros((0, 640, 3), np.uint8))
    assert not empty.ok and empty.error and not empty.band.found


def test_imports_with_debians_python():
    out = subprocess.run(
        ["/usr/bin/python3", "-c", "from follow_bot import core; from image_converter import "
         "core as ic; print(core.LineDetectorConfig(), ic.OverlayConfig())"],
        capture_output=True, text=True, check=True, timeout=60,
    )  # fmt: skip
    assert out.stdout.startswith("LineDetectorConfig(lower=HsvColor(h=20, s=100, v=40)")
    overlay = "OverlayConfig(radius_px=25, thickness_px=2, min_image_size=50)"
    assert out.stdout.rstrip().endswith(overlay)


def test_the_readme_example_runs_with_debians_python():
    manual = (REPO / "follow_bot" / "doc" / "python.md").read_text()
    example = re.search(r"^# From Python.*?```python\n(.*?)```", manual, re.S).group(1)
    assert len(example.splitlines()) == 10
    out = subprocess.run(
        ["/usr/bin/python3", "-c", example], capture_output=True, text=True, check=True, timeout=60
    )
    assert out.stdout == "True 505.0 0.578125\n0.10 -0.60\n"
