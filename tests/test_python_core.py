"""follow_bot.core, the pybind11 bindings of the C++ cores: the same results as the C++ library.

Detectors, bit for bit on the same frames (rendered by the harness, written as PNG): the C++
results come from `core_reference` (LineDetector, ColourBlobDetector) and `marker_probe`
(TagDetector), which print every field exactly. Controllers: the values the gtests assert
(follow_bot/test/*_test.cpp, image_converter/test/velocity_limiter_test.cpp), within 1e-9.
Bad configs raise ValueError with the C++ validate() message; bad arrays raise TypeError or
ValueError, never crash; frames are read in place, row-strided crops included.
"""

import json
import math
import re
import subprocess
from pathlib import Path

import cv2
import numpy as np
import pytest

from follow_bot import core
from harness.render import Renderer
from harness.world import WORLDS_DIR, load_world

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
# Tag views (distance m, incidence deg, bearing deg), as tests/test_tag_pose_accuracy.py.
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
    "confidence", "row_begin", "row_end",
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
    detector = core.ColourBlobDetector()
    expected = run_json("rosrun", "follow_bot", "core_reference", "--blobs", *files)
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


def test_tag_detector_equals_cpp_over_a_sequence(tmp_path):
    world = load_world(WORLDS_DIR / "parking.yaml")
    tag = world.objects[0]
    x, y, _, yaw = tag.pose
    poses = []
    for distance, incidence, bearing in TAG_VIEWS:
        a = yaw + math.radians(incidence)
        rx, ry = x + distance * math.cos(a), y + distance * math.sin(a)
        poses.append((rx, ry, math.atan2(y - ry, x - rx) - math.radians(bearing)))
    renderer = Renderer(world)
    greys, files = [], []
    for i, pose in enumerate(poses):
        greys.append(cv2.cvtColor(renderer.render(pose, frame=i), cv2.COLOR_BGR2GRAY))
        files.append(str(tmp_path / f"tag{i:02d}.png"))
        assert cv2.imwrite(files[-1], greys[-1])
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


# ---- controllers: the gtests' values -----------------------------------------------------------


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
    assert controller.state == core.BeaconState.SEARCHING
    assert (twist.linear, twist.angular) == (0.0, config.search_rate)
    twist = controller.update(blobs(absent[0], blob("green", 480.0, 2000.0), absent[2]), 0.1)
    assert controller.state == core.BeaconState.APPROACHING
    assert twist.linear == config.approach_speed
    assert twist.angular == pytest.approx(-config.turn_gain * 0.5, abs=1e-9)
    twist = controller.update(blobs(absent[0], blob("green", 160.0, 2000.0), absent[2]), 0.2)
    assert twist.angular == pytest.approx(config.turn_gain * 0.5, abs=1e-9)
    close = blobs(absent[0], blob("green", 330.0, config.close_area), absent[2])
    twist = controller.update(close, 0.3)
    assert controller.state == core.BeaconState.HOLDING and twist.linear == 0.0
    red = blobs(blob("red", 500.0, 800.0), blob("green", 400.0, 2000.0), absent[2])
    twist = controller.update(red, 0.4)
    assert controller.state == core.BeaconState.STOPPED_BY_RED
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
        ["/usr/bin/python3", "-c", "from follow_bot import core; print(core.LineDetectorConfig())"],
        capture_output=True, text=True, check=True, timeout=60,
    )  # fmt: skip
    assert out.stdout.startswith("LineDetectorConfig(lower=HsvColor(h=20, s=100, v=100)")


def test_the_readme_example_runs_with_debians_python():
    readme = (Path(__file__).resolve().parents[1] / "follow_bot" / "README.md").read_text()
    example = re.search(r"## From Python.*?```python\n(.*?)```", readme, re.S).group(1)
    assert len(example.splitlines()) == 10
    out = subprocess.run(
        ["/usr/bin/python3", "-c", example], capture_output=True, text=True, check=True, timeout=60
    )
    assert out.stdout == "True 505.0 0.578125\n0.10 -0.60\n"
