"""Geometry helpers shared by the world loader, renderer and scoring (SI units, radians)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

# Rows of point-to-segment distances computed at once; bounds memory to ~50 MB per chunk.
_CHUNK_ELEMENTS = 2_000_000


def wrap_angle(angle: float | np.ndarray) -> float | np.ndarray:
    """Wrap an angle (or array of angles) to (-pi, pi] so headings compare without seams."""
    wrapped = math.pi - np.mod(math.pi - np.asarray(angle, dtype=float), 2.0 * math.pi)
    return float(wrapped) if np.ndim(wrapped) == 0 else wrapped


def rot_z(yaw: float) -> np.ndarray:
    """Rotation matrix about +z (counter-clockwise seen from above, REP-103)."""
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def rotation_angle_deg(a: np.ndarray, b: np.ndarray) -> float:
    """Angle of the rotation taking rotation matrix a to b, in degrees."""
    return math.degrees(math.acos(np.clip((np.trace(a.T @ b) - 1.0) / 2.0, -1.0, 1.0)))


def incidence_deg(marker_rotation: np.ndarray, marker_centre: np.ndarray) -> float:
    """Angle between the line of sight to a marker's centre and the marker's normal (its z axis),
    both in the camera frame, in degrees (0: seen face-on)."""
    cos = abs(marker_rotation[:, 2] @ marker_centre) / np.linalg.norm(marker_centre)
    return math.degrees(math.acos(min(1.0, cos)))


@dataclass(frozen=True)
class Straight:
    """Straight piece of a traced path, in metres."""

    length: float


@dataclass(frozen=True)
class Arc:
    """Circular piece of a traced path; positive angle turns left (counter-clockwise)."""

    radius: float
    angle: float


def trace_segments(
    start: tuple[float, float, float], segments: list[Straight | Arc], spacing: float
) -> tuple[np.ndarray, tuple[float, float, float]]:
    """Sample a straight/arc path at most `spacing` apart; return (points Nx2, end pose).

    Every sample is computed in closed form from its piece's start so that long paths
    accumulate no integration drift (the texture and the scoring centreline must agree).
    """
    x, y, yaw = start
    points = [np.array([[x, y]])]
    for seg in segments:
        if isinstance(seg, Straight):
            n = max(1, math.ceil(seg.length / spacing))
            s = np.linspace(0.0, seg.length, n + 1)[1:]
            pts = np.column_stack([x + s * math.cos(yaw), y + s * math.sin(yaw)])
            x, y = x + seg.length * math.cos(yaw), y + seg.length * math.sin(yaw)
        else:
            side = math.copysign(1.0, seg.angle)  # +1 centre on the left, -1 on the right
            cx = x - side * seg.radius * math.sin(yaw)
            cy = y + side * seg.radius * math.cos(yaw)
            n = max(1, math.ceil(seg.radius * abs(seg.angle) / spacing))
            headings = yaw + np.linspace(0.0, seg.angle, n + 1)[1:]
            r = side * seg.radius
            pts = np.column_stack([cx + r * np.sin(headings), cy - r * np.cos(headings)])
            yaw = yaw + seg.angle
            x = cx + side * seg.radius * math.sin(yaw)
            y = cy - side * seg.radius * math.cos(yaw)
        points.append(pts)
    return np.concatenate(points), (x, y, float(wrap_angle(yaw)))


def densify_polyline(points: np.ndarray, closed: bool, spacing: float) -> np.ndarray:
    """Insert evenly spaced points so that no segment is longer than `spacing`."""
    pts = np.asarray(points, dtype=float)
    ends = np.roll(pts, -1, axis=0) if closed else pts[1:]
    starts = pts if closed else pts[:-1]
    out = []
    for a, b in zip(starts, ends, strict=False):
        n = max(1, math.ceil(float(np.linalg.norm(b - a)) / spacing))
        t = np.arange(n)[:, None] / n
        out.append(a + t * (b - a))
    if not closed:
        out.append(pts[-1:])
    return np.concatenate(out)


def polyline_segments(polyline: np.ndarray, closed: bool) -> tuple[np.ndarray, np.ndarray]:
    """Return (segment starts, segment vectors) of a polyline, including the closing one."""
    pts = np.asarray(polyline, dtype=float)
    ends = np.roll(pts, -1, axis=0) if closed else pts[1:]
    starts = pts if closed else pts[:-1]
    return starts, ends - starts


def polyline_length(polyline: np.ndarray, closed: bool) -> float:
    """Total arc length of a polyline (including the closing segment when closed)."""
    _, vec = polyline_segments(polyline, closed)
    return float(np.hypot(vec[:, 0], vec[:, 1]).sum())


def project_onto_polyline(
    points: np.ndarray, polyline: np.ndarray, closed: bool
) -> tuple[np.ndarray, np.ndarray]:
    """Distance from each point to the polyline and arc length of its nearest projection.

    Returns (distance N, arc_length N); arc length is measured from polyline[0] along the
    point order. Vectorised in chunks so long runs against dense centrelines stay fast.
    """
    dist, arc, _, _ = nearest_on_polyline(points, polyline, closed)
    return dist, arc


def nearest_on_polyline(
    points: np.ndarray, polyline: np.ndarray, closed: bool
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """project_onto_polyline's (distance, arc length), plus the signed distance (positive left
    of the polyline's point order) and the unit direction (Nx2) of the nearest segment."""
    pts = np.asarray(points, dtype=float).reshape(-1, 2)
    starts, vec = polyline_segments(polyline, closed)
    seg_len2 = np.maximum((vec**2).sum(axis=1), 1e-300)
    seg_len = np.sqrt(seg_len2)
    cum = np.concatenate([[0.0], np.cumsum(seg_len)[:-1]])
    dist = np.empty(len(pts))
    arc = np.empty(len(pts))
    best_all = np.empty(len(pts), dtype=int)
    rows = max(1, _CHUNK_ELEMENTS // max(1, len(starts)))
    for i in range(0, len(pts), rows):
        p = pts[i : i + rows, None, :]
        rel = p - starts[None]
        t = np.clip((rel * vec[None]).sum(axis=2) / seg_len2[None], 0.0, 1.0)
        d2 = ((rel - t[..., None] * vec[None]) ** 2).sum(axis=2)
        best = np.argmin(d2, axis=1)
        idx = np.arange(len(best))
        dist[i : i + rows] = np.sqrt(d2[idx, best])
        arc[i : i + rows] = cum[best] + t[idx, best] * seg_len[best]
        best_all[i : i + rows] = best
    direction = vec[best_all] / seg_len[best_all, None]
    rel = pts - starts[best_all]
    left = direction[:, 0] * rel[:, 1] - direction[:, 1] * rel[:, 0]
    return dist, arc, np.where(left < 0.0, -dist, dist), direction


def clip_polygon_near(poly: np.ndarray, z_near: float) -> np.ndarray:
    """Clip a planar polygon in camera coordinates (Nx3) to z >= z_near (Sutherland-Hodgman).

    Needed because a homogeneous projection of vertices behind the camera flips them.
    """
    out = []
    n = len(poly)
    for i in range(n):
        a, b = poly[i], poly[(i + 1) % n]
        a_in, b_in = a[2] >= z_near, b[2] >= z_near
        if a_in:
            out.append(a)
        if a_in != b_in:
            t = (z_near - a[2]) / (b[2] - a[2])
            out.append(a + t * (b - a))
    return np.array(out).reshape(-1, 3)
