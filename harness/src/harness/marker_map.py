"""A behaviour's recorded `~markers` (harness.marker_record) placed on the floor by the simulator's
true pose at each frame, and drawn top-down over the world: what rviz would show, checkable
against the world's truth."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
from matplotlib.patches import Circle

from harness.plot import floor_map
from harness.world import World

MAP_MARGIN_M = 0.4  # around the driven path and every marker drawn
MAX_ASPECT = 1.5  # the map's longer side at most this times the shorter (a straight run is flat)
SHOWN_FRAMES = 6  # frames drawn, evenly spaced over the run (the last one among them)


def load_frames(path: Path | str) -> list[dict]:
    return json.loads(Path(path).read_text())


def to_world(frames: list[dict], run: dict) -> list[dict]:
    """`frames` with every position and point moved from the robot's base frame into the world
    (x, y; z stays the height above the floor) by the pose `run` (record.npz) logs at the
    frame's step; frames whose step is not in the record are left out."""
    placed = []
    for frame in frames:
        step = np.flatnonzero(np.isclose(run["t"], frame["t"], atol=1e-4))
        if not len(step):
            continue
        x, y, yaw = (float(run[k][step[0]]) for k in ("x", "y", "yaw"))
        c, s = math.cos(yaw), math.sin(yaw)

        def place(p, x=x, y=y, c=c, s=s):
            return [x + c * p[0] - s * p[1], y + s * p[0] + c * p[1], p[2]]

        markers = [
            {**m, "position": place(m["position"]), "points": [place(p) for p in m["points"]]}
            for m in frame["markers"]
        ]
        placed.append({**frame, "pose": (x, y, yaw), "markers": markers})
    return placed


def _draw(ax, marker: dict, alpha: float, last: bool) -> list[np.ndarray]:
    """Draws one world-placed marker (text only in the `last` frame drawn); the points it
    covers."""
    colour = tuple(marker["colour"][:3])
    position = np.array(marker["position"][:2])
    points = np.array(marker["points"], dtype=float).reshape(-1, 3)[:, :2]
    kind = marker["type"]
    if kind == "SPHERE_LIST":
        ax.plot(points[:, 0], points[:, 1], "o", color=colour, ms=4, alpha=alpha)
        return [points]
    if kind == "LINE_STRIP":
        ax.plot(points[:, 0], points[:, 1], "-", color=colour, lw=2, alpha=alpha)
        return [points]
    if kind == "SPHERE":
        radius = marker["scale"][0] / 2.0
        ax.add_patch(Circle(position, radius, fc=colour, ec="k", ls="--", alpha=0.5 * alpha))
        return [position[None]]
    if kind == "ARROW":
        (x0, y0), (x1, y1) = points
        arrow = {"arrowstyle": "-|>", "color": colour, "alpha": alpha, "lw": 2}
        ax.annotate("", (x1, y1), (x0, y0), arrowprops=arrow)
        return [points]
    if kind == "TEXT_VIEW_FACING" and last:
        ax.text(*position, marker["text"], color="k", fontsize="small", alpha=alpha)
        return [position[None]]
    return []


def plot_markers(out_path: Path | str, world: World, run: dict, frames: list[dict], title: str):
    """A PNG of the world, the driven path and the markers of SHOWN_FRAMES frames with markers
    (earlier ones fainter), zoomed on what is drawn."""
    placed = [f for f in to_world(frames, run) if f["markers"]]
    fig, ax, _ = floor_map(world, (5, 5))
    path = np.column_stack([run["x"], run["y"]])
    ax.plot(path[:, 0], path[:, 1], color="tab:blue", lw=1, label="true path")
    covered = [path]
    named: set[str] = set()  # namespaces in the legend
    shown = np.unique(np.linspace(0, len(placed) - 1, SHOWN_FRAMES).round().astype(int))
    for rank, index in enumerate(shown if placed else []):
        frame = placed[index]
        alpha = 0.3 + 0.7 * (rank + 1) / len(shown)
        x, y, yaw = frame["pose"]
        robot = {"arrowstyle": "->", "color": "tab:blue", "alpha": alpha}
        ax.annotate("", (x + 0.15 * math.cos(yaw), y + 0.15 * math.sin(yaw)), (x, y),
                    arrowprops=robot)  # fmt: skip
        for marker in frame["markers"]:
            covered += _draw(ax, marker, alpha, rank == len(shown) - 1)
            if marker["ns"] not in named:
                named.add(marker["ns"])
                ax.plot([], [], color=tuple(marker["colour"][:3]), lw=2, label=marker["ns"])
    corners = np.vstack(covered)
    low, high = corners.min(axis=0) - MAP_MARGIN_M, corners.max(axis=0) + MAP_MARGIN_M
    size = high - low
    grow = np.maximum(0.0, size.max() / MAX_ASPECT - size)
    low, high = low - grow / 2.0, high + grow / 2.0
    ax.set_xlim(low[0], high[0])
    ax.set_ylim(low[1], high[1])
    ax.legend(loc="upper right", fontsize="small")
    ax.set_title(title, fontsize="medium")
    fig.tight_layout()
    fig.savefig(out_path)
