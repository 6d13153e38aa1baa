"""make bench: a follow_bot.core call from Python against the same C++ call, on the same frames.

LineDetector.detect on 640x480 course frames, TagDetector.detect and SignDetector.detect on
640x480 parking-world views, all rendered by the harness: the Python call (numpy frame in,
result object out) may cost at most 10 % more than the C++ call timed by `core_call_timer` over
the same PNG files. The pd steering law's step on those course frames' measurements is timed
too, for information only: a sub-microsecond C++ call, so its ratio is the binding's fixed
cost per call.
The baseline is the worksheet's pure-OpenCV Python colour step on the line frames (full-frame
cvtColor + inRange + findContours, then the largest contour's moments). Each figure is the mean
per call (process CPU time) of the fastest of several rounds, one thread; exits 1 when a ratio
is above 1.10.
"""

import json
import math
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np

from follow_bot import core
from harness.render import Renderer
from harness.world import WORLDS_DIR
from harness.world_file import load_world

MAX_RATIO = 1.10
ROUNDS = 5
CALLS = {"line": 20, "tag": 2, "sign": 1, "steer": 2000}  # calls per frame per round
GATED = {"line", "tag", "sign"}  # the detectors; steer is reported only
LECTURE_LOWER, LECTURE_UPPER = np.array([20, 100, 100]), np.array([30, 255, 255])


def course_frames() -> list[np.ndarray]:
    """Views along and across the course's first straight and its first curve, with noise."""
    renderer = Renderer(load_world(WORLDS_DIR / "course.yaml"), noise_sigma=4.0)
    poses = [(-2.8 + 0.15 * i, -3.5 + 0.04 * math.sin(i), 0.3 * math.sin(i / 2)) for i in range(30)]
    return [renderer.render(pose, frame=i) for i, pose in enumerate(poses)]


def facing_views(renderer: Renderer, target, distances, off_deg: float) -> list[np.ndarray]:
    """Grey frames of `target` (a world object) looked at from `distances` (m), up to `off_deg`
    off its normal."""
    x, y, _, yaw = target.pose
    frames = []
    for i, distance in enumerate(distances):
        a = yaw + math.radians(off_deg * math.sin(i))
        rx, ry = x + distance * math.cos(a), y + distance * math.sin(a)
        bgr = renderer.render((rx, ry, math.atan2(y - ry, x - rx)), frame=i)
        frames.append(cv2.cvtColor(bgr, cv2.COLOR_BGR2GRAY))
    return frames


def tag_frames() -> list[np.ndarray]:
    """The parking tag from 0.6 to 3 m, up to 30 deg off its normal (the default config's tag)."""
    world = load_world(WORLDS_DIR / "parking.yaml")
    return facing_views(Renderer(world), world.objects[0], np.linspace(0.6, 3.0, 10), 30.0)


def sign_frames():
    """The parking sign from 0.8 to 2.5 m, up to 25 deg off its normal; the sign's world."""
    world = load_world(WORLDS_DIR / "parking_sign.yaml")
    renderer = Renderer(world, noise_sigma=2.0, seed=1)
    sign = world.objects[0]
    return sign, facing_views(renderer, sign, np.linspace(0.8, 2.5, 6), 25.0)


def time_calls(call, frames, calls: int) -> float:
    """Mean process CPU microseconds per call over the fastest of ROUNDS rounds (as
    core_call_timer): time the scheduler gives other processes does not count."""
    for frame in frames:
        call(frame)
    fastest = math.inf
    for _ in range(ROUNDS):
        start = time.process_time()
        for frame in frames:
            for _ in range(calls):
                call(frame)
        fastest = min(fastest, (time.process_time() - start) / (len(frames) * calls))
    return fastest * 1e6


def time_cpp(mode: str, frames, folder: Path, args=()) -> float:
    files = []
    for i, frame in enumerate(frames):
        files.append(str(folder / f"{mode}{i:02d}.png"))
        cv2.imwrite(files[-1], frame)
    out = subprocess.run(
        ["rosrun", "follow_bot", "core_call_timer", f"--{mode}", *args, "--rounds", str(ROUNDS),
         "--calls", str(CALLS[mode]), *files],
        capture_output=True, text=True, check=True, timeout=600,
    )  # fmt: skip
    return json.loads(out.stdout)["us_per_call"]


def worksheet_colour_step(bgr: np.ndarray):
    hsv = cv2.cvtColor(bgr, cv2.COLOR_BGR2HSV)
    mask = cv2.inRange(hsv, LECTURE_LOWER, LECTURE_UPPER)
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    return cv2.moments(max(contours, key=cv2.contourArea)) if contours else None


def main() -> int:
    cv2.setNumThreads(1)  # as the C++ side: one thread
    line_detector = core.LineDetector()
    tag_detector = core.TagDetector(core.TagDetectorConfig())
    camera = core.CameraGeometry()
    sign, signs = sign_frames()
    sign_detector = core.SignDetector(
        core.SignDetectorConfig(image_path=str(sign.path), width_m=sign.width)
    )
    course = course_frames()
    measurements = {id(frame): line_detector.detect(frame) for frame in course}
    law, stamp = core.make_steering_law(), [0.0]

    def steer(frame):
        stamp[0] += 1.0 / 30.0
        return law.step(measurements[id(frame)], stamp[0])

    checks = {
        "line": (course, line_detector.detect, ()),
        "tag": (tag_frames(), lambda grey: tag_detector.detect(grey, camera), ()),
        "sign": (signs, lambda grey: sign_detector.detect(grey, camera),
                 (str(sign.path), repr(sign.width))),
        "steer": (course, steer, ()),
    }  # fmt: skip
    failed = False
    with tempfile.TemporaryDirectory() as folder:
        for mode, (frames, call, args) in checks.items():
            # Alternating twice, keeping each side's best, evens out load from other processes.
            cpp_us = py_us = math.inf
            for _ in range(2):
                cpp_us = min(cpp_us, time_cpp(mode, frames, Path(folder), args))
                py_us = min(py_us, time_calls(call, frames, CALLS[mode]))
            ratio = py_us / cpp_us
            failed |= mode in GATED and ratio > MAX_RATIO
            verdict = "ok" if ratio <= MAX_RATIO else f"ABOVE {MAX_RATIO:.2f}"
            verdict = verdict if mode in GATED else "information"
            what = "pd law step" if mode == "steer" else f"{mode} detect"
            print(f"{what}, {len(frames)} frames 640x480: C++ {cpp_us:9.3f} us, "
                  f"Python {py_us:9.3f} us, Python/C++ {ratio:.3f} ({verdict})")  # fmt: skip
            if mode == "line":
                sheet_us = time_calls(worksheet_colour_step, frames, CALLS[mode])
                print(f"  worksheet's pure-OpenCV Python colour step on the same frames: "
                      f"{sheet_us:9.1f} us, {sheet_us / cpp_us:.1f}x the C++ detector")  # fmt: skip
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
