"""A contact sheet: a PNG grid of frames picked evenly from a run's camera video, so a person can
see what the camera saw (with the behaviour's debug overlay beside it, as the video has it)."""

from __future__ import annotations

import math
from pathlib import Path

import cv2
import numpy as np

DEFAULT_FRAMES = 12
DEFAULT_COLUMNS = 3
DEFAULT_WIDTH = 1920  # px, the whole sheet


def sheet_size(
    frame_shape: tuple[int, int], count: int, columns: int, width: int
) -> tuple[int, int]:
    """(height, width) of the sheet for frames of `frame_shape` (rows, cols)."""
    tile_w = width // columns
    tile_h = round(frame_shape[0] * tile_w / frame_shape[1])
    return math.ceil(count / columns) * tile_h, columns * tile_w


def write_contact_sheet(
    video: Path,
    out: Path,
    rate_hz: float,
    count: int = DEFAULT_FRAMES,
    columns: int = DEFAULT_COLUMNS,
    width: int = DEFAULT_WIDTH,
) -> tuple[int, int]:
    """Writes `out` from `count` frames spread evenly over `video` (first to last), each labelled
    with its time; returns the sheet's (height, width). Raises ValueError on an unreadable video."""
    capture = cv2.VideoCapture(str(video))
    total = int(capture.get(cv2.CAP_PROP_FRAME_COUNT))
    wanted = set(np.rint(np.linspace(0, max(total - 1, 0), count)).astype(int).tolist())
    frames: dict[int, np.ndarray] = {}
    index = 0
    while capture.grab():  # sequential: seeking in an MP4 is not frame-exact
        if index in wanted or total <= 0:
            ok, frame = capture.retrieve()
            if ok:
                frames[index] = frame
        index += 1
    capture.release()
    if not frames:
        raise ValueError(f"{video}: no frames to put on a contact sheet")
    if total <= 0 or index != total:  # the container's count was missing or wrong: pick again
        kept = sorted(frames)
        chosen = {kept[i] for i in np.rint(np.linspace(0, len(kept) - 1, count)).astype(int)}
        frames = {i: frames[i] for i in kept if i in chosen}
    picks = sorted(frames)
    first = frames[picks[0]]
    height, sheet_w = sheet_size((first.shape[0], first.shape[1]), count, columns, width)
    tile_w = sheet_w // columns
    tile_h = height // math.ceil(count / columns)
    sheet = np.zeros((height, sheet_w, 3), np.uint8)
    for slot, index in enumerate(picks):
        tile = cv2.resize(frames[index], (tile_w, tile_h), interpolation=cv2.INTER_AREA)
        label = f"t = {index / rate_hz:.1f} s"
        for colour, thickness in (((0, 0, 0), 3), ((255, 255, 255), 1)):
            cv2.putText(tile, label, (8, tile_h - 10), cv2.FONT_HERSHEY_SIMPLEX, 0.6, colour,
                        thickness, cv2.LINE_AA)  # fmt: skip
        row, col = divmod(slot, columns)
        sheet[row * tile_h : (row + 1) * tile_h, col * tile_w : (col + 1) * tile_w] = tile
    out.parent.mkdir(parents=True, exist_ok=True)
    if not cv2.imwrite(str(out), sheet):
        raise ValueError(f"{out}: cannot write the contact sheet")
    return sheet.shape[0], sheet.shape[1]
