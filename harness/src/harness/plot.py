"""Top-down PNG of a run: floor texture, objects, driven path, start/end/goal, key metrics."""

from __future__ import annotations

import math
import textwrap
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.patches import Circle, Polygon

from harness.ground import ground_texture
from harness.world import AprilTagMarker, Box, Sphere, TextureMarker, World

MAX_BACKGROUND_PX = 1000  # the floor image is decimated to at most this many pixels a side


def _rgb(bgr) -> tuple[float, float, float]:
    return bgr[2] / 255.0, bgr[1] / 255.0, bgr[0] / 255.0


def _format_metrics(metrics: dict) -> str:
    parts = [f"{k}={v:.3g}" if isinstance(v, float) else f"{k}={v}" for k, v in metrics.items()]
    return textwrap.fill(", ".join(parts), width=90)


def floor_map(world: World, size_in: tuple[float, float]):
    """A figure of `size_in` inches with the world's floor and objects drawn top-down; the
    figure, its axes and the floor's extent (x0, x1, y0, y1)."""
    fig = Figure(figsize=size_in, dpi=100)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    tex, tex_to_world = ground_texture(world)
    step = max(1, math.ceil(max(tex.shape[:2]) / MAX_BACKGROUND_PX))
    rows, cols = tex.shape[:2]
    m = tex_to_world[0, 0]
    x0, y_top = tex_to_world[0, 2] - 0.5 * m, tex_to_world[1, 2] + 0.5 * m
    extent = (x0, x0 + cols * m, y_top - rows * m, y_top)
    ax.imshow(tex[::step, ::step, ::-1], extent=extent, origin="upper", interpolation="bilinear")
    for obj in world.objects:
        if isinstance(obj, Sphere):
            ax.add_patch(Circle(obj.position[:2], obj.radius, color=_rgb(obj.colour), ec="k"))
        elif isinstance(obj, Box):
            x, y, yaw = obj.pose
            c, s = math.cos(yaw), math.sin(yaw)
            half = np.array([[1, 1], [-1, 1], [-1, -1], [1, -1]]) * np.array(obj.size[:2]) / 2.0
            corners = half @ np.array([[c, s], [-s, c]]) + (x, y)
            ax.add_patch(Polygon(corners, closed=True, color=_rgb(obj.colour), ec="k"))
        elif isinstance(obj, AprilTagMarker | TextureMarker):
            x, y, _, yaw = obj.pose
            half = obj.board_size[0] / 2.0
            dx, dy = -math.sin(yaw) * half, math.cos(yaw) * half
            ax.plot([x - dx, x + dx], [y - dy, y + dy], color="k", lw=3)
            ax.arrow(x, y, 0.3 * math.cos(yaw), 0.3 * math.sin(yaw), width=0.02, color="k")
        ax.annotate(obj.name, obj.pose[:2] if not isinstance(obj, Sphere) else obj.position[:2])
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    return fig, ax, extent


def plot_run(
    out_path: Path | str,
    world: World,
    path,
    *,
    goal: tuple[float, float, float] | None = None,
    metrics: dict | None = None,
    title: str | None = None,
) -> Path:
    """Write a PNG map of the run; `path` is N x 2 (or N x 3 poses), goal is (x, y, yaw)."""
    pts = np.asarray(path, dtype=float)
    pts = pts.reshape(0, 2) if pts.size == 0 else pts
    fig, ax, extent = floor_map(world, (8, 8))
    if len(pts):
        ax.plot(pts[:, 0], pts[:, 1], color="tab:blue", lw=1.5, label="path")
        ax.plot(*pts[0, :2], "o", color="tab:green", ms=8, label="start")
        ax.plot(*pts[-1, :2], "X", color="tab:red", ms=9, label="end")
    if goal is not None:
        ax.plot(goal[0], goal[1], "*", color="tab:orange", ms=14, label="goal")
        ax.arrow(goal[0], goal[1], 0.3 * math.cos(goal[2]), 0.3 * math.sin(goal[2]), width=0.01)
    ax.set_xlim(extent[0], extent[1])
    ax.set_ylim(extent[2], extent[3])
    ax.legend(loc="upper right", fontsize="small")
    heading = title or world.name
    if metrics:
        heading += "\n" + _format_metrics(metrics)
    ax.set_title(heading, fontsize="medium")
    out = Path(out_path)
    fig.savefig(out)
    return out
