"""The run plot renders a PNG with the floor map and the path."""

import math

import cv2
import numpy as np

from harness.plot import plot_run


def test_plot_run_writes_png(tmp_path, worlds):
    course = worlds["course"]
    path = course.centreline()[::20] + 0.02
    out = plot_run(tmp_path / "course.png", course, path, metrics={"rms": 0.02, "laps": 1})
    image = cv2.imread(str(out))
    assert image.shape == (800, 800, 3)
    # The yellow loop is visible in the background image.
    yellow = (image[..., 2] > 200) & (image[..., 1] > 180) & (image[..., 0] < 80)
    assert yellow.sum() > 500
    parking = worlds["parking"]
    poses = np.array([[0.0, 0.0, 0.0], [2.5, 0.0, 0.0]])
    out = plot_run(tmp_path / "p.png", parking, poses, goal=(2.5, 0.0, math.pi), title="park")
    assert out.stat().st_size > 10_000
    assert plot_run(tmp_path / "empty.png", parking, []).exists()
