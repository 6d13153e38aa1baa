"""The contact sheet: written, the size it says, frames in reading order."""

import cv2
import numpy as np
import pytest

from harness.contact_sheet import sheet_size, write_contact_sheet


@pytest.fixture
def video(tmp_path):
    path = tmp_path / "camera.mp4"
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), 30.0, (320, 120))
    for k in range(60):
        writer.write(np.full((120, 320, 3), 4 * k, np.uint8))  # brightness tells the frame
    writer.release()
    return path


def test_sheet_is_written_with_the_grid_size(video, tmp_path):
    out = tmp_path / "sheet" / "contact_sheet.png"
    shape = write_contact_sheet(video, out, rate_hz=30.0, count=5, columns=2, width=400)
    assert shape == sheet_size((120, 320), 5, 2, 400) == (3 * 75, 400)
    sheet = cv2.imread(str(out))
    assert sheet.shape == (225, 400, 3)
    # First tile is frame 0 (dark), the last filled one frame 59 (bright), the sixth slot empty.
    assert sheet[5:40, 5:195].mean() < 10
    assert sheet[155:185, 5:195].mean() == pytest.approx(4 * 59, abs=8)
    assert (sheet[150:, 200:] == 0).all()


def test_an_empty_video_is_an_error(tmp_path):
    with pytest.raises(ValueError, match="no frames"):
        write_contact_sheet(tmp_path / "missing.mp4", tmp_path / "s.png", rate_hz=30.0)
