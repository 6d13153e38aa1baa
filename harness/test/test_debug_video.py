"""The demo video's frame: the exact camera view on the left, the behaviour's overlay on the
right with its state and command written on it."""

import numpy as np

from harness.debug_video import side_by_side


def test_raw_view_is_kept_exactly_and_the_overlay_is_beside_it():
    rng = np.random.default_rng(1)
    raw = rng.integers(0, 256, (480, 640, 3), dtype=np.uint8)
    debug = np.zeros_like(raw)
    debug[360:380, :] = (0, 255, 255)  # a band, as the follower draws it
    frame = side_by_side(raw, debug, ["state: tracking", "v = +0.30 m/s", "w = -0.10 rad/s"])
    assert frame.shape == (480, 1280, 3)
    assert np.array_equal(frame[:, :640], raw)
    assert np.array_equal(frame[360:380, 640:], debug[360:380])  # text stays above the band
    text = frame[:80, 640:]
    assert (text == 255).all(axis=2).sum() > 300  # three white lines of text


def test_a_grey_panel_until_the_first_overlay_arrives():
    raw = np.zeros((480, 640, 3), dtype=np.uint8)
    frame = side_by_side(raw, None, [])
    assert frame.shape == (480, 1280, 3)
    assert (frame[:, 640:] == 64).all()
