"""The parking sign picture (follow_bot/assets/parking_sign.png), drawn deterministically.

A blue sign with a big white "P", the word PARKING and a white border, plus the distinctive,
non-repeating detail a SIFT matcher needs: a border of dashes of varying length, corner glyphs
that differ from each other, and a panel of fixed shapes (a car, an arrow, a clock, rings,
triangles, digits). Everything is drawn with OpenCV primitives and Hershey fonts from fixed
coordinates, so the same image comes out on every machine.

    python3 -m harness.sign_texture follow_bot/assets/parking_sign.png
"""

from __future__ import annotations

import argparse
import itertools
from pathlib import Path

import cv2
import numpy as np

WIDTH_PX, HEIGHT_PX = 480, 400
BLUE = (170, 80, 10)  # BGR
WHITE = (255, 255, 255)
YELLOW = (40, 210, 250)
RED = (40, 40, 210)
BLACK = (20, 20, 20)
LINE = cv2.LINE_AA


def _border(img: np.ndarray) -> None:
    """White frame with a ring of dashes whose lengths follow a fixed, non-periodic sequence."""
    h, w = img.shape[:2]
    cv2.rectangle(img, (6, 6), (w - 7, h - 7), WHITE, 6, LINE)
    lengths = [14, 6, 22, 9, 17, 5, 27, 11, 8, 19, 13, 7, 24, 10]
    # Walk the perimeter 20 px inside the edge and lay dashes of the listed lengths.
    path = [(20, 20), (w - 21, 20), (w - 21, h - 21), (20, h - 21), (20, 20)]
    k = 0
    for (x0, y0), (x1, y1) in itertools.pairwise(path):
        side = max(abs(x1 - x0), abs(y1 - y0))
        dx, dy = np.sign(x1 - x0), np.sign(y1 - y0)
        s = 6
        while s < side - 6:
            n = min(lengths[k % len(lengths)], side - 6 - s)
            colour = YELLOW if k % 5 == 2 else WHITE
            a = (int(x0 + dx * s), int(y0 + dy * s))
            b = (int(x0 + dx * (s + n)), int(y0 + dy * (s + n)))
            cv2.line(img, a, b, colour, 5, LINE)
            s += n + 4 + (k * 7) % 9
            k += 1


def _big_p(img: np.ndarray) -> None:
    """A bold white P (stem plus bowl) on the left half, drawn from shapes, not a font."""
    cv2.rectangle(img, (50, 50), (100, 300), WHITE, -1, LINE)
    cv2.ellipse(img, (130, 118), (75, 50), 0, -90, 90, WHITE, 36, LINE)
    cv2.rectangle(img, (100, 50), (130, 86), WHITE, -1, LINE)
    cv2.rectangle(img, (100, 150), (130, 186), WHITE, -1, LINE)


def _panel(img: np.ndarray) -> None:
    """Right-hand panel of distinct shapes and characters."""
    cv2.rectangle(img, (268, 48), (448, 298), WHITE, 3, LINE)
    # A car: body, cabin, wheels.
    cv2.rectangle(img, (285, 90), (385, 120), WHITE, -1, LINE)
    cv2.fillConvexPoly(img, np.array([[305, 90], [318, 68], [355, 68], [370, 90]]), WHITE, LINE)
    cv2.fillConvexPoly(img, np.array([[322, 88], [330, 74], [342, 74], [342, 88]]), BLUE, LINE)
    for cx in (305, 365):
        cv2.circle(img, (cx, 122), 12, BLACK, -1, LINE)
        cv2.circle(img, (cx, 122), 5, WHITE, -1, LINE)
    # An arrow pointing right, then a clock.
    cv2.arrowedLine(img, (290, 160), (380, 160), YELLOW, 9, LINE, tipLength=0.35)
    cv2.circle(img, (415, 95), 24, WHITE, 4, LINE)
    cv2.line(img, (415, 95), (415, 78), WHITE, 4, LINE)
    cv2.line(img, (415, 95), (429, 103), WHITE, 3, LINE)
    cv2.putText(img, "2h", (396, 175), cv2.FONT_HERSHEY_DUPLEX, 1.1, WHITE, 2, LINE)
    # Shapes of different kinds and sizes, none repeated at the same scale.
    cv2.fillConvexPoly(img, np.array([[285, 250], [310, 205], [335, 250]]), YELLOW, LINE)
    cv2.circle(img, (370, 228), 20, RED, -1, LINE)
    cv2.circle(img, (370, 228), 9, WHITE, -1, LINE)
    cv2.rectangle(img, (402, 206), (436, 240), WHITE, 3, LINE)
    cv2.line(img, (402, 206), (436, 240), WHITE, 3, LINE)
    cv2.putText(img, "7:00-19:00", (280, 285), cv2.FONT_HERSHEY_SIMPLEX, 0.62, WHITE, 2, LINE)


def _corners(img: np.ndarray) -> None:
    """A different glyph at each corner so the sign has no rotational symmetry."""
    h, w = img.shape[:2]
    cv2.circle(img, (44, 44), 8, YELLOW, -1, LINE)
    cv2.fillConvexPoly(img, np.array([[w - 54, 36], [w - 36, 36], [w - 45, 54]]), WHITE, LINE)
    cv2.rectangle(img, (w - 54, h - 54), (w - 38, h - 38), RED, -1, LINE)
    cv2.drawMarker(img, (44, h - 46), WHITE, cv2.MARKER_CROSS, 18, 4, LINE)


def draw_sign() -> np.ndarray:
    """The sign as a WIDTH_PX x HEIGHT_PX BGR image."""
    img = np.empty((HEIGHT_PX, WIDTH_PX, 3), np.uint8)
    img[:] = BLUE
    _border(img)
    _big_p(img)
    _panel(img)
    _corners(img)
    cv2.putText(img, "PARKING", (60, 362), cv2.FONT_HERSHEY_TRIPLEX, 1.9, WHITE, 4, LINE)
    cv2.putText(img, "ZONE", (122, 240), cv2.FONT_HERSHEY_PLAIN, 2.2, YELLOW, 2, LINE)
    cv2.putText(img, "B-14", (122, 288), cv2.FONT_HERSHEY_COMPLEX, 1.3, WHITE, 2, LINE)
    return img


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("output", type=Path, help="PNG file to write")
    args = parser.parse_args(argv)
    args.output.parent.mkdir(parents=True, exist_ok=True)
    if not cv2.imwrite(str(args.output), draw_sign(), [cv2.IMWRITE_PNG_COMPRESSION, 9]):
        raise SystemExit(f"could not write {args.output}")


if __name__ == "__main__":
    main()
