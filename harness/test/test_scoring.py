"""Scoring functions on synthetic paths with known answers."""

import json
import math

import numpy as np
import pytest

from harness.scoring import (
    ROBOT_RADIUS_M,
    command_stats,
    cross_track,
    distance_to_object,
    lap_stats,
    parking_error,
    progress,
    stop_distance,
    time_to_stop,
)
from harness.world import AprilTagMarker, Box, Sphere


def circle(radius, n=4000, turns=1.0, start=0.0):
    a = start + np.linspace(0.0, 2 * math.pi * turns, n, endpoint=False)
    return np.column_stack([radius * np.cos(a), radius * np.sin(a)])


CENTRE = circle(1.0)


def test_cross_track_of_offset_circle():
    ct = cross_track(circle(1.02, 777), CENTRE)
    assert ct["rms"] == pytest.approx(0.02, abs=1e-5)
    assert ct["max"] == pytest.approx(0.02, abs=1e-5)
    inside = cross_track(circle(0.97, 500), CENTRE)
    assert inside["rms"] == pytest.approx(0.03, abs=1e-5)
    # Poses (N x 3) work too, and an open polyline has no closing segment.
    poses = np.column_stack([[0.5, 1.5], [0.1, -0.2], [0.0, 0.0]])
    open_ct = cross_track(poses, np.array([[0.0, 0.0], [1.0, 0.0]]), closed=False)
    assert open_ct["max"] == pytest.approx(math.hypot(0.5, 0.2))


def test_cross_track_mean_left_is_signed_by_the_heading():
    # A robot 2 cm outside the unit circle: driven anticlockwise (the centreline's order) the
    # line is on its left, so it is 2 cm to the right (-); driven clockwise, 2 cm left (+).
    path = circle(1.02, 777)
    ccw = np.arctan2(path[:, 1], path[:, 0]) + math.pi / 2
    right = cross_track(np.column_stack([path, ccw]), CENTRE)
    assert right["mean_left"] == pytest.approx(-0.02, abs=1e-5)
    left = cross_track(np.column_stack([path, ccw + math.pi]), CENTRE)
    assert left["mean_left"] == pytest.approx(0.02, abs=1e-5)
    # Without headings it is signed along the centreline's order; unsigned mean unchanged.
    no_heading = cross_track(circle(0.97, 500), CENTRE)
    assert no_heading["mean_left"] == pytest.approx(0.03, abs=1e-5)
    assert no_heading["mean"] == pytest.approx(0.03, abs=1e-5)


def test_full_lap_detected_with_time():
    path = circle(1.01, 1100, turns=1.1, start=0.3)  # starts away from the seam at angle 0
    t = np.arange(len(path)) * 0.01
    stats = lap_stats(t, path, CENTRE)
    length = 2 * math.pi  # the polyline is 1e-6 shorter than the circle
    assert stats["loop_length"] == pytest.approx(length, rel=1e-5)
    assert stats["laps"] == 1 and stats["direction"] == 1
    assert stats["progress"] == pytest.approx(1.1 * length * (1099 / 1100), rel=1e-3)
    assert stats["lap_time"] == pytest.approx(1000 * 0.01, abs=0.011)
    backwards = lap_stats(t, path[::-1], CENTRE)
    assert backwards["direction"] == -1 and backwards["laps"] == 1
    half = lap_stats(t[:500], path[:500], CENTRE)
    assert half["laps"] == 0 and half["lap_time"] is None


def test_max_reversal_is_the_length_driven_back():
    # A quarter turn anticlockwise, then an eighth back the way it came: pi/4 m back on the unit
    # circle; either way round the same.
    there = circle(1.0, 250, turns=0.25)
    back = there[::-1][: 125 + 1]
    path = np.concatenate([there, back])
    t = np.arange(len(path)) * 0.01
    assert lap_stats(t, path, CENTRE)["max_reversal"] == pytest.approx(math.pi / 4, rel=0.02)
    assert lap_stats(t, path[:, ::-1], CENTRE)["max_reversal"] == pytest.approx(
        math.pi / 4, rel=0.02
    )
    # Driven one way only: nothing back.
    assert lap_stats(t[:250], there, CENTRE)["max_reversal"] == 0.0
    # Swaying 0.2 m back and forth before setting off clockwise: the sway is before the direction
    # is chosen, yet counts as driven against it (0.2 m, as sampled).
    sway = circle(1.0, 41, turns=0.2 / (2 * math.pi))
    cw = circle(1.0, 250, turns=-0.25)
    path = np.concatenate([sway, sway[::-1], cw])
    t = np.arange(len(path)) * 0.01
    assert lap_stats(t, path, CENTRE)["max_reversal"] == pytest.approx(0.2 * 40 / 41, rel=1e-3)


def test_progress_ignores_jumps_and_far_samples():
    path = circle(1.0, 100, turns=0.5)
    far = path.copy()
    far[40:60] *= 3.0  # off the line for a while: no progress counted there
    full = progress(path, CENTRE)[-1]
    assert full == pytest.approx(math.pi * 99 / 100, rel=1e-4)
    assert progress(far, CENTRE)[-1] == pytest.approx(full - 21 * math.pi / 100, rel=1e-3)


def test_command_stats_find_nan_and_rates():
    t = np.array([0.0, 0.1, 0.2, 0.3, 0.4])
    v = np.array([0.0, 0.2, float("nan"), 0.5, 0.4])
    w = np.array([0.0, -1.0, 0.5, float("inf"), 0.0])
    s = command_stats(t, v, w, missed_replies=3)
    assert s["non_finite"] == 2 and s["missed_replies"] == 3 and s["count"] == 5
    assert s["max_abs_v"] == pytest.approx(0.5) and s["max_abs_w"] == pytest.approx(1.0)
    assert s["max_abs_dv_dt"] == pytest.approx(2.0)
    assert s["max_abs_dw_dt"] == pytest.approx(15.0)
    assert s["stops"] == 0  # it starts at zero, then never returns to it
    stopping = command_stats(t, np.array([0.2, 0.0, 0.0, 0.2, 0.0]), np.zeros(5))
    assert stopping["stops"] == 2
    with pytest.raises(ValueError, match="lengths differ"):
        command_stats(t, v[:3], w)


def test_time_to_stop():
    t = np.arange(10) * 0.1
    v = np.array([0.3, 0.3, 0.0, 0.3, 0.3, 0.2, 0.1, 0.0, 0.0, 0.0])
    w = np.array([0.1, 0.1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.05, 0.0, 0.0])
    s = time_to_stop(t, v, w, t_drop=0.35)
    assert s["t_stop"] == pytest.approx(0.8) and s["stop_delay"] == pytest.approx(0.45)
    assert time_to_stop(t, v, w, 0.35, tol=0.06)["t_stop"] == pytest.approx(0.7)
    assert time_to_stop(t, v + 1.0, w, 0.35) == {"t_stop": None, "stop_delay": None}


def test_distances_to_objects():
    ball = Sphere("b", (0, 0, 255), 0.2, (2.0, 0.0, 0.2))
    assert distance_to_object([1.5, 0.0], ball)[0] == pytest.approx(0.3)
    box = Box("d", (0, 90, 0), (1.8, 1.0, 1.2), (4.0, 0.0, math.pi / 2))
    # Long side (1.8 m) lies along y, so the near face is at x = 3.5.
    d = distance_to_object([[3.0, 0.0], [3.0, 1.4], [4.0, 0.0]], box)
    np.testing.assert_allclose(d, [0.5, math.hypot(0.5, 0.5), 0.0])
    tag = AprilTagMarker("t", "tag36h11", 0, 0.16, 0.04, (3.0, 0.0, 0.35, math.pi), True)
    d = distance_to_object([[2.0, 0.0], [3.0, 1.12]], tag)
    np.testing.assert_allclose(d, [1.0, 1.0])
    s = stop_distance(np.array([[0.0, 0.0], [1.0, 0.0], [1.6, 0.0], [1.5, 0.0]]), ball)
    assert s["final_distance"] == pytest.approx(0.3) and s["min_distance"] == pytest.approx(0.2)
    assert s["final_gap"] == pytest.approx(0.3 - ROBOT_RADIUS_M) and not s["collided"]


def test_parking_error():
    goal = (3.0, 0.0, math.pi)  # marker at x = 3 facing -x
    e = parking_error((2.45, -0.03, 0.05), goal, standoff=0.5)
    assert e["standoff"] == pytest.approx(0.55)
    assert e["standoff_error"] == pytest.approx(0.05)
    assert e["lateral"] == pytest.approx(0.03)  # right of the marker as seen facing it
    assert e["heading_error"] == pytest.approx(0.05)
    assert e["position_error"] == pytest.approx(math.hypot(0.05, 0.03))


def test_results_are_json_ready():
    t = np.arange(5) * 0.1
    path = circle(1.0, 5)
    results = [
        cross_track(path, CENTRE),
        lap_stats(t, path, CENTRE),
        command_stats(t, t, t),
        time_to_stop(t, t, t, 0.0),
        parking_error((0, 0, 0), (1, 0, math.pi), 0.5),
        stop_distance(path, Sphere("b", (0, 0, 0), 0.1, (3, 0, 0.1))),
    ]
    json.dumps(results, allow_nan=False)
