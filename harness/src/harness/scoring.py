"""Scoring of a simulated run: pure functions over arrays, returning JSON-ready dicts.

Positions are robot base-frame origins in world metres, angles in radians, times in s.
"""

from __future__ import annotations

import math

import numpy as np

from harness.geometry import (
    nearest_on_polyline,
    polyline_length,
    project_onto_polyline,
    wrap_angle,
)
from harness.world import AprilTagMarker, Box, Sphere, TextureMarker, WorldObject

# TurtleBot 2 (Kobuki) base radius: the gap to an obstacle is measured from the bumper.
ROBOT_RADIUS_M = 0.177
# Lap progress counts while the base is within this of the line (m), unless told a bound.
LAP_MAX_OFFSET = 0.25


def _xy(path) -> np.ndarray:
    a = np.asarray(path, dtype=float)
    if a.ndim != 2 or a.shape[1] < 2:
        raise ValueError(f"path must be an N x 2 (or N x 3 pose) array, got shape {a.shape}")
    return a[:, :2]


def cross_track(path, centreline: np.ndarray, closed: bool = True) -> dict:
    """Distance from each path point to the nearest centreline segment: RMS, max, mean, and the
    mean of the signed distance (`mean_left`: positive left of the line seen along the robot's
    heading, or along the centreline's point order for a path without headings), which shows a
    bias that the unsigned figures fold away."""
    dist, _, left, direction = nearest_on_polyline(_xy(path), centreline, closed)
    if len(dist) == 0:
        return {"rms": 0.0, "max": 0.0, "mean": 0.0, "mean_left": 0.0, "samples": 0}
    along = np.ones(len(dist))
    if np.asarray(path).shape[1] >= 3:
        yaw = np.asarray(path, dtype=float)[:, 2]
        along = direction[:, 0] * np.cos(yaw) + direction[:, 1] * np.sin(yaw)
    return {
        "rms": float(np.sqrt(np.mean(dist**2))),
        "max": float(dist.max()),
        "mean": float(dist.mean()),
        "mean_left": float(np.mean(np.where(along < 0.0, -left, left))),
        "samples": int(len(dist)),
    }


def progress(
    path,
    centreline: np.ndarray,
    closed: bool = True,
    *,
    max_offset: float = LAP_MAX_OFFSET,
    max_step: float = 1.0,
) -> np.ndarray:
    """Signed distance travelled along the line since the first sample (one per sample).

    Arc length of each projection is unwrapped across the loop seam. A step only counts
    while both samples are within `max_offset` of the line and move less than `max_step`
    along it, so a robot far off the line cannot score by jumping between branches.
    Positive means along the centreline's point order.
    """
    dist, arc = project_onto_polyline(_xy(path), centreline, closed)
    if len(arc) == 0:
        return arc
    step = np.diff(arc)
    if closed:
        length = polyline_length(centreline, closed)
        step = (step + length / 2.0) % length - length / 2.0
    near = (dist[:-1] <= max_offset) & (dist[1:] <= max_offset)
    step = np.where(near & (np.abs(step) < max_step), step, 0.0)
    return np.concatenate([[0.0], np.cumsum(step)])


# Progress before the direction of travel counts as chosen (m): a search may sway both ways.
TRAVEL_DIRECTION_AFTER = 0.5


def reversal(prog: np.ndarray) -> dict:
    """How far progress ran back against the direction of travel (m): the largest drop below its
    best so far. The direction is the sign of the progress when it first reaches
    TRAVEL_DIRECTION_AFTER either way (else the final progress's), so a robot that turns round and
    drives the course the wrong way scores the length it drove back."""
    prog = np.asarray(prog, dtype=float)
    if len(prog) == 0:
        return {"max_reversal": 0.0}
    chosen = np.nonzero(np.abs(prog) >= TRAVEL_DIRECTION_AFTER)[0]
    direction = math.copysign(1.0, prog[chosen[0]] if len(chosen) else prog[-1])
    along = direction * prog
    return {"max_reversal": float(np.max(np.maximum.accumulate(along) - along))}


def lap_stats(t, path, centreline: np.ndarray, *, max_offset: float = LAP_MAX_OFFSET) -> dict:
    """Loop progress, completed laps, the time of the first full lap (None if none) and how far
    progress ran back against the direction of travel (`max_reversal`, m).

    A lap is complete when |progress| reaches the loop length, in either direction.
    """
    times = np.asarray(t, dtype=float)
    prog = progress(path, centreline, True, max_offset=max_offset)
    if len(times) != len(prog):
        raise ValueError(f"t has {len(times)} samples but path has {len(prog)}")
    length = polyline_length(centreline, True)
    reach = np.abs(prog)
    done = np.nonzero(reach >= length)[0]
    final = float(prog[-1]) if len(prog) else 0.0
    return {
        **reversal(prog),
        "loop_length": length,
        "progress": final,
        "direction": int(math.copysign(1, final)) if final else 0,
        "laps": int(reach.max() // length) if len(reach) else 0,
        "lap_time": float(times[done[0]] - times[0]) if len(done) else None,
    }


def distance_to_object(xy, obj: WorldObject) -> np.ndarray:
    """Horizontal distance from points to an object's footprint (0 inside it).

    Footprints: sphere = circle of its radius, box = its rectangle, marker = its board
    segment (the post is ignored).
    """
    p = np.atleast_2d(np.asarray(xy, dtype=float))[:, :2]
    if isinstance(obj, Sphere):
        d = np.hypot(*(p - obj.position[:2]).T) - obj.radius
    elif isinstance(obj, Box):
        x, y, yaw = obj.pose
        c, s = math.cos(yaw), math.sin(yaw)
        rel = p - (x, y)
        along = np.abs(rel @ (c, s)) - obj.size[0] / 2.0
        across = np.abs(rel @ (-s, c)) - obj.size[1] / 2.0
        d = np.hypot(np.maximum(along, 0.0), np.maximum(across, 0.0))
    elif isinstance(obj, AprilTagMarker | TextureMarker):
        x, y, _, yaw = obj.pose
        half = obj.board_size[0] / 2.0
        right = np.array([-math.sin(yaw), math.cos(yaw)])
        board = np.array([(x, y) - half * right, (x, y) + half * right])
        d, _ = project_onto_polyline(p, board, closed=False)
    else:
        raise TypeError(f"no footprint for object type {type(obj).__name__}")
    return np.maximum(d, 0.0)


def stop_distance(path, obj: WorldObject, robot_radius: float = ROBOT_RADIUS_M) -> dict:
    """Final and closest approach to an object, from the base centre and from the bumper.

    `*_distance` is base centre to the object's footprint; `*_gap` subtracts the robot
    radius (negative gap = the bumper overlaps the object, i.e. a collision).
    """
    d = distance_to_object(_xy(path), obj)
    return {
        "final_distance": float(d[-1]),
        "min_distance": float(d.min()),
        "final_gap": float(d[-1] - robot_radius),
        "min_gap": float(d.min() - robot_radius),
        "collided": bool(d.min() < robot_radius),
    }


def parking_error(pose, goal: tuple[float, float, float], standoff: float) -> dict:
    """Final pose against a goal facing it: goal = (x, y, yaw) of a marker's outward normal.

    The ideal pose is `standoff` metres in front of the goal along its normal, facing it.
    `lateral` is positive to the right of the goal as seen when facing it; the heading error
    is zero when the robot faces the goal squarely.
    """
    x, y, yaw = (float(v) for v in pose[:3])
    gx, gy, gyaw = goal
    rel = np.array([x - gx, y - gy])
    along = float(rel @ (math.cos(gyaw), math.sin(gyaw)))
    lateral = float(rel @ (-math.sin(gyaw), math.cos(gyaw)))
    return {
        "standoff": along,
        "standoff_error": along - standoff,
        "lateral": lateral,
        "position_error": math.hypot(along - standoff, lateral),
        "heading_error": float(wrap_angle(yaw - gyaw - math.pi)),
    }


def still_since(t, v, w) -> float | None:
    """The time from which every command to the end of the run is zero (the robot stopped for
    good), or None if the last command moves it."""
    t, v, w = (np.asarray(a, dtype=float) for a in (t, v, w))
    moving = np.nonzero((v != 0.0) | (w != 0.0))[0]
    if len(t) == 0 or (len(moving) and moving[-1] == len(t) - 1):
        return None
    return float(t[moving[-1] + 1]) if len(moving) else float(t[0])


def _max_abs(a: np.ndarray) -> float:
    finite = a[np.isfinite(a)]
    return float(np.abs(finite).max()) if len(finite) else 0.0


def _max_rate(t: np.ndarray, a: np.ndarray) -> float:
    dt = np.diff(t)
    ok = np.isfinite(a[1:]) & np.isfinite(a[:-1]) & (dt > 0.0)
    return float(np.max(np.abs(np.diff(a)[ok]) / dt[ok])) if ok.any() else 0.0


def command_stats(t, v, w, missed_replies: int = 0) -> dict:
    """Extremes of the commanded (v, w) and their rates; non-finite samples are counted,
    not used. `stops`: how often the command fell from moving to zero (a behaviour halting, a
    frame watchdog's stop). `missed_replies` (frames without a status reply) is passed through
    for the report.
    """
    times, lin, ang = (np.asarray(a, dtype=float) for a in (t, v, w))
    if not len(times) == len(lin) == len(ang):
        raise ValueError(f"t, v, w lengths differ: {len(times)}, {len(lin)}, {len(ang)}")
    moving = (lin != 0.0) | (ang != 0.0)  # NaN included
    return {
        "count": int(len(times)),
        "max_abs_v": _max_abs(lin),
        "max_abs_w": _max_abs(ang),
        "max_abs_dv_dt": _max_rate(times, lin),
        "max_abs_dw_dt": _max_rate(times, ang),
        "non_finite": int(np.count_nonzero(~(np.isfinite(lin) & np.isfinite(ang)))),
        "stops": int(np.count_nonzero(moving[:-1] & ~moving[1:])),
        "missed_replies": int(missed_replies),
    }


def time_to_stop(t, v, w, t_drop: float, tol: float = 0.0) -> dict:
    """First time at or after t_drop (when frames stopped) with |v| and |w| <= tol.

    `t_stop` and `stop_delay` (t_stop - t_drop) are None if the robot never stopped.
    """
    times, lin, ang = (np.asarray(a, dtype=float) for a in (t, v, w))
    stopped = (times >= t_drop) & (np.abs(lin) <= tol) & (np.abs(ang) <= tol)
    idx = np.nonzero(stopped)[0]
    if not len(idx):
        return {"t_stop": None, "stop_delay": None}
    return {"t_stop": float(times[idx[0]]), "stop_delay": float(times[idx[0]] - t_drop)}
