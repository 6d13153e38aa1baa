"""Distractors a realism adds to a world before it is rendered: a white lane line beside line 0,
yellow tape pieces and a yellow box off the course, coloured clutter, posters beside markers.
Drawn from RNGs keyed by the run's seed (harness.realism.rng_for), so a run repeats exactly.
"""

from __future__ import annotations

import math
from dataclasses import replace

import cv2
import numpy as np

from harness.geometry import densify_polyline
from harness.realism import Realism, rng_for
from harness.world import Box, Line, Sphere, TextureMarker

TAPE_COLOUR = (0, 220, 255)  # the course line's yellow
LANE_COLOUR = (235, 235, 235)
YELLOW_BOX_COLOUR = (20, 200, 235)
# Clutter colours: none is the pure red, green or blue of the beacon worlds' balls.
CLUTTER_COLOURS = (
    (0, 140, 255),  # orange
    (150, 40, 130),  # purple
    (200, 190, 40),  # teal
    (180, 120, 250),  # pink
    (40, 70, 120),  # brown
    (230, 230, 230),  # white
)


def poster_texture(seed: int, index: int, size_px: tuple[int, int] = (240, 320)) -> np.ndarray:
    """A made-up poster: coloured background, shapes, stripes and a few words."""
    rng = rng_for(seed, 4, index)
    rows, cols = size_px
    image = np.empty((rows, cols, 3), np.uint8)
    image[:] = rng.integers(60, 255, 3)
    for _ in range(6):
        col = tuple(int(c) for c in rng.integers(0, 255, 3))
        kind = rng.integers(3)
        if kind == 0:
            centre = (int(rng.uniform(0, cols)), int(rng.uniform(0, rows)))
            cv2.circle(image, centre, int(rng.uniform(10, 60)), col, -1, cv2.LINE_AA)
        elif kind == 1:
            p0 = (int(rng.uniform(0, cols)), int(rng.uniform(0, rows)))
            p1 = (int(rng.uniform(0, cols)), int(rng.uniform(0, rows)))
            cv2.rectangle(image, p0, p1, col, -1)
        else:
            y = int(rng.uniform(0, rows))
            cv2.line(image, (0, y), (cols, y + int(rng.uniform(-40, 40))), col, 6, cv2.LINE_AA)
    words = ("EXIT", "LAB 3", "NO FOOD", "ROBOTS", "CAUTION", "AREA B")
    text = words[int(rng.integers(len(words)))]
    cv2.putText(image, text, (12, rows - 24), cv2.FONT_HERSHEY_DUPLEX, 1.4, (20, 20, 20), 3,
                cv2.LINE_AA)  # fmt: skip
    return image


def _segment_distance(points: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    d = b - a
    t = np.clip(((points - a) @ d) / max(float(d @ d), 1e-12), 0.0, 1.0)
    return np.hypot(*(points - a - t[:, None] * d).T)


def offset_polyline(points: np.ndarray, closed: bool, offset: float) -> np.ndarray:
    """`points` moved `offset` metres to their right (seen travelling along them)."""
    if closed:
        tangent = np.roll(points, -1, axis=0) - np.roll(points, 1, axis=0)
    else:
        tangent = np.gradient(points, axis=0)
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    return points + offset * np.column_stack([tangent[:, 1], -tangent[:, 0]])


class _Placer:
    """Random floor spots at least some distance from the robot's ways and from each other."""

    def __init__(self, world, rng: np.random.Generator, starts: list[tuple[float, float]]):
        g = world.ground
        self.low = np.array(g.origin) + 0.5
        self.high = np.array(g.origin) + np.array(g.size) - 0.5
        self.rng = rng
        self.line = world.ground.lines[0].points if world.ground.lines else None
        targets = [tuple(getattr(o, "position", None) or o.pose)[:2] for o in world.objects]
        self.segments = [(np.array(s), np.array(t)) for s in starts for t in targets]
        self.points = [np.array(p) for p in [*starts, *targets]]

    def line_distance(self, p: np.ndarray) -> float:
        if self.line is None:
            return math.inf
        return float(np.min(np.hypot(*(self.line - p).T)))

    def spot(self, clear: float, near_line: tuple[float, float] | None = None) -> np.ndarray | None:
        """A spot `clear` m from every start, object, start-object segment and placed spot, and
        (with `near_line`) between those distances from line 0; None after 500 tries."""
        for _ in range(500):
            p = self.rng.uniform(self.low, self.high)
            if near_line is not None and self.line is not None:
                k = int(self.rng.integers(len(self.line)))
                side = self.rng.choice([-1.0, 1.0]) * self.rng.uniform(*near_line)
                p = offset_polyline(self.line, True, side)[k]
            if any(np.hypot(*(p - q)) < clear for q in self.points):
                continue
            if any(_segment_distance(p[None], a, b)[0] < clear for a, b in self.segments):
                continue
            if near_line is not None and self.line is not None:
                if self.line_distance(p) < near_line[0] - 1e-6:
                    continue
            elif self.line_distance(p) < clear:
                continue
            self.points.append(p)
            return p
        return None


def with_distractors(world, realism: Realism, seed: int, starts: list[tuple[float, float]]):
    """The world with the realism's lane line, tape, yellow box, clutter and posters added.
    Line 0 and every existing object stay as they are (scoring uses them)."""

    rng = rng_for(seed, 5)
    lines = list(world.ground.lines)
    objects = list(world.objects)
    placer = _Placer(world, rng, starts)
    if realism.lane_line and lines:
        first = lines[0]
        points = offset_polyline(first.points, first.closed, realism.lane_line)
        lines.append(Line(points, 0.05, LANE_COLOUR, first.closed))
    for _ in range(realism.tape):
        p = placer.spot(0.3, near_line=(0.3, 1.0))
        if p is None:
            break
        angle = rng.uniform(0.0, math.pi)
        half = 0.5 * rng.uniform(0.1, 0.35) * np.array([math.cos(angle), math.sin(angle)])
        ends = np.array([p - half, p + half])
        lines.append(Line(densify_polyline(ends, False, 0.01), 0.05, TAPE_COLOUR, False))
    if realism.yellow_box:
        p = placer.spot(0.6, near_line=(0.6, 1.2))
        if p is not None:
            yaw = rng.uniform(-math.pi, math.pi)
            objects.append(Box("yellow_box", YELLOW_BOX_COLOUR, (0.3, 0.3, 0.25), (*p, yaw)))
    for i in range(realism.clutter):
        p = placer.spot(1.0)
        if p is None:
            break
        colour = CLUTTER_COLOURS[int(rng.integers(len(CLUTTER_COLOURS)))]
        if rng.uniform() < 0.5:
            radius = rng.uniform(0.1, 0.25)
            objects.append(Sphere(f"clutter{i}", colour, radius, (*p, radius)))
        else:
            size = tuple(rng.uniform([0.2, 0.2, 0.2], [0.6, 0.6, 0.8]))
            objects.append(Box(f"clutter{i}", colour, size, (*p, rng.uniform(-math.pi, math.pi))))
    markers = [o for o in world.objects if hasattr(o, "board_size")]
    for m_index, marker in enumerate(markers):
        x, y, z, yaw = marker.pose
        right = np.array([-math.sin(yaw), math.cos(yaw)])  # the marker's right, seen from front
        for k in range(realism.posters):
            side = 1.0 if k % 2 == 0 else -1.0
            lateral = side * (0.75 + 0.6 * (k // 2) + rng.uniform(0.0, 0.2))
            cx, cy = np.array([x, y]) + lateral * right
            image = poster_texture(seed, m_index * 100 + k)
            width = rng.uniform(0.3, 0.45)
            height = width * image.shape[0] / image.shape[1]
            cz = max(height / 2.0 + 0.02, z + rng.uniform(-0.1, 0.15))
            pose = (float(cx), float(cy), float(cz), yaw + rng.uniform(-0.2, 0.2))
            objects.append(TextureMarker(f"poster{m_index}_{k}", None, image, width, pose, True))
    ground = replace(world.ground, lines=tuple(lines))
    return replace(world, ground=ground, objects=tuple(objects))
