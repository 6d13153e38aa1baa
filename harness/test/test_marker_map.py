"""Recorded markers land on the floor where the simulator's pose at their frame puts them."""

import math

import numpy as np
import pytest

from harness.marker_map import plot_markers, to_world


def marker(kind: str, position, points=()) -> dict:
    return {"ns": kind.lower(), "id": 0, "type": kind, "position": list(position),
            "points": [list(p) for p in points], "scale": [0.1, 0.1, 0.1],
            "colour": [1.0, 0.0, 0.0, 1.0], "text": "1.00 m"}  # fmt: skip


RUN = {
    "t": np.array([0.0, 0.1, 0.2]),
    "x": np.array([0.0, 1.0, 2.0]),
    "y": np.array([0.0, 2.0, 2.0]),
    "yaw": np.array([0.0, math.pi / 2, math.pi]),
}


def test_markers_are_placed_by_the_pose_of_their_frame():
    frames = [
        {"t": 0.1, "frame": "base_link", "markers": [
            marker("SPHERE", (1.0, 0.0, 0.2)),
            marker("LINE_STRIP", (0, 0, 0), [(0.0, 0.0, 0.0), (1.0, 1.0, 0.0)]),
        ]},
        {"t": 0.15, "frame": "base_link", "markers": []},  # no step at that time: left out
    ]  # fmt: skip
    (placed,) = to_world(frames, RUN)
    assert placed["pose"] == pytest.approx((1.0, 2.0, math.pi / 2))
    sphere, line = placed["markers"]
    # Facing +y: 1 m ahead is +y, 1 m to the left is -x; heights stay.
    assert sphere["position"] == pytest.approx([1.0, 3.0, 0.2])
    assert line["points"] == [pytest.approx([1.0, 2.0, 0.0]), pytest.approx([0.0, 3.0, 0.0])]


def test_the_marker_map_draws_every_kind(tmp_path, worlds):
    frames = [
        {"t": t, "frame": "base_link", "markers": [
            marker("SPHERE_LIST", (0, 0, 0), [(0.5, 0.0, 0.0)]),
            marker("ARROW", (0, 0, 0), [(0.0, 0.0, 0.0), (0.3, 0.0, 0.0)]),
            marker("TEXT_VIEW_FACING", (0.5, 0.0, 0.3)),
        ]}
        for t in RUN["t"]
    ]  # fmt: skip
    out = tmp_path / "markers.png"
    plot_markers(out, worlds["course"], RUN, frames, "test")
    assert out.stat().st_size > 0
