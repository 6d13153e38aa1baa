"""The follower's line detector on real robot-camera frames (../shared/realdata, not ours to ship:
the tests skip, saying so once, where it is absent).

Truth: hand labels. Each case is a frame and a 20-row band of it; the label is the column of the
yellow paint's centre in that band, read off the frame by eye at 2x zoom with a pixel ruler, or
None where the band holds no yellow paint (dash gaps, red stop lines, white lines, the robot's own
bumper, dark floor). Bands where a dash starts or ends inside the rows are left out: there the
truth is ambiguous. The frames cover every lighting condition of the set (Duckietown noon,
night, night with coordination lights, a closed room, an ice rink under green-cast light, the
anti-instagram inputs) and the four colour-cast photos (resized from 1080x810 to 640x480).

The detector runs with its defaults (cfg/Follower.cfg), the band placed on the rows by ground
distance for the set's nominal camera (README there: K; mounting ~0.1 m high, ~17 deg down).
Through that unmeasured mounting the paint is 1-4 cm wide on the floor, inside the width gate
of the default line_width (our course's 5 cm) on every band.
"""

import math

import cv2
import numpy as np

from follow_bot import core

# (file, first band row) -> the paint's centre column in the band, or None.
LABELS = {
    ("226noon_0004.jpg", 370): 50,
    ("226noon_0013.jpg", 370): None,
    ("226noon_0032.jpg", 370): 592,
    ("226noon_0038.jpg", 370): 524,
    ("226noon_0046.jpg", 370): None,
    ("226night_0004.jpg", 370): 105,
    ("226night_0010.jpg", 370): 110,
    ("226night_0039.jpg", 370): None,
    ("226night_0050.jpg", 370): 69,
    ("226night_0056.jpg", 370): 220,
    ("226night_0064.jpg", 370): 122,
    ("316closed_0031.jpg", 370): None,
    ("316closed_0043.jpg", 370): None,
    ("316closed_0061.jpg", 370): 159,
    ("316closed_0087.jpg", 370): 326,
    ("316closed_0102.jpg", 370): None,
    ("icerink_0002.jpg", 370): None,
    ("icerink_0012.jpg", 370): 215,
    ("icerink_0018.jpg", 370): None,
    ("icerink_0026.jpg", 370): None,
    ("icerink_0031.jpg", 370): 131,
    ("icerink_0036.jpg", 370): 357,
    ("226nightCoordination_0016.jpg", 370): None,
    ("226nightCoordination_0019.jpg", 370): 247,
    ("anti_instagram_inputimage0.jpg", 370): 97,
    ("anti_instagram_inputimage1.jpg", 370): 89,
    ("pic1_smaller.jpg", 300): 75,
    ("pic1_smaller.jpg", 450): 5,
    ("pic2_smaller.jpg", 300): 100,
    ("pic2_smaller.jpg", 340): 72,
    ("pic2_smaller.jpg", 370): 64,
    ("pic4_smaller.jpg", 300): 78,
    ("pic4_smaller.jpg", 340): 40,
    ("pic4_smaller.jpg", 370): 38,
    ("pic4_smaller.jpg", 450): None,
    ("pic5_smaller.jpg", 300): None,
    ("pic5_smaller.jpg", 370): None,
    ("pic5_smaller.jpg", 450): None,
}
TOLERANCE_PX = 25
BAND_ROWS = 20  # cfg/Follower.cfg's band_rows, as the labels' bands


def nominal_camera():
    return core.CameraGeometry(
        fx=305.5719, fy=308.8339, cx=303.0797, cy=231.8845, height_m=0.1,
        pitch_rad=math.radians(17.0), x_offset_m=0.0,
    )  # fmt: skip


def band_distance(camera, first_row):
    """The floor distance whose band starts at first_row (ground_to_row falls with distance)."""
    centre = first_row + (BAND_ROWS - 1) / 2
    near, far = 0.05, 10.0
    for _ in range(60):
        middle = (near + far) / 2
        near, far = (middle, far) if core.ground_to_row(camera, middle) > centre else (near, middle)
    return (near + far) / 2


def load(realdata, name):
    folder = "line_colour_cast" if name.startswith("pic") else "line_lighting"
    frame = cv2.imread(str(realdata / folder / name))
    assert frame is not None, name
    if frame.shape[:2] != (480, 640):
        frame = cv2.resize(frame, (640, 480), interpolation=cv2.INTER_AREA)
    return frame


SKY_SHADOW_TINT = (1.1, 1.0, 0.95)  # BGR gains of a sky-lit shadow: blue up, red down
BLUER_SHADOW_TINT = (1.3, 1.0, 0.85)  # a shadow lit by clear sky alone


def in_shadow(frame, brightness, tint=SKY_SHADOW_TINT):
    gains = np.array(tint, np.float32) * brightness
    return np.clip(np.rint(frame.astype(np.float32) * gains), 0, 255).astype(np.uint8)


def in_shadow_over(frame, columns, brightness, tint=BLUER_SHADOW_TINT):
    """The frame with a shadow over `columns` (a slice) alone."""
    shaded = frame.copy()
    shaded[:, columns] = in_shadow(frame[:, columns], brightness, tint)
    return shaded


def in_stripe_of_shadow(frame, centre, brightness, tint=BLUER_SHADOW_TINT, half_width=80):
    """The frame with a shadow `half_width` columns either side of column `centre` alone."""
    return in_shadow_over(
        frame, slice(max(centre - half_width, 0), centre + half_width), brightness, tint
    )


def measure(
    realdata,
    detector_config,
    name,
    first_row,
    shadow=1.0,
    tint=SKY_SHADOW_TINT,
    stripe=None,
    columns=None,
):
    """The band at first_row of the frame; below 1, `shadow` is the light left on it (in_shadow,
    with `tint`), or, given `stripe` (a column), on the stripe round that column alone, or, given
    `columns` (a slice), on those columns alone."""
    camera = nominal_camera()
    config = detector_config()
    config.band = core.BandConfig(distance_m=band_distance(camera, first_row), rows=BAND_ROWS)
    frame = load(realdata, name)
    if shadow < 1:
        if stripe is not None:
            frame = in_stripe_of_shadow(frame, stripe, shadow, tint)
        elif columns is not None:
            frame = in_shadow_over(frame, columns, shadow, tint)
        else:
            frame = in_shadow(frame, shadow, tint)
    band = core.LineDetector(config, camera).detect(frame).band
    assert band.row_begin == first_row
    return band


def verdict(band, label):
    if label is None:
        return not band.found
    return band.found and abs(band.centroid_x - label) <= TOLERANCE_PX


def test_the_line_is_found_within_25_px_and_no_line_where_there_is_none(realdata, record_property):
    rows, misses = [], []
    for (name, first_row), label in LABELS.items():
        band = measure(realdata, core.LineDetectorConfig, name, first_row)
        found = f"{band.centroid_x:.0f}" if band.found else "none"
        ok = verdict(band, label)
        rows.append(f"{name}@{first_row}: truth {label}, found {found} {'ok' if ok else 'MISS'}")
        if not ok:
            misses.append(rows[-1])
    hits = len(LABELS) - len(misses)
    record_property("summary", f"real line frames: {hits}/{len(LABELS)} within {TOLERANCE_PX} px")
    print("\n".join(rows))
    # Every labelled band, so that >= 95 % holds with margin; no line where there is none.
    assert not misses, misses


def lecture_config():
    """The lecture's pipeline: its colour box (H 20-30, S and V >= 100), no floor test, no width
    gate, and every pixel in the box counts."""
    config = core.LineDetectorConfig()
    config.lower = core.HsvColor(h=20, s=100, v=100)
    config.upper = core.HsvColor(h=30, s=255, v=255)
    config.floor_margin = 0
    config.line_width_factor = 0.0
    config.blob_saturation_fraction = 0.0
    return config


def misses(realdata, detector_config):
    return [
        (name, first_row)
        for (name, first_row), label in LABELS.items()
        if not verdict(measure(realdata, detector_config, name, first_row), label)
    ]


def test_the_lectures_pipeline_is_what_the_colour_casts_break(realdata):
    """The same frames through the lecture's pipeline: the warm casts flood the band with floor,
    so the label set does catch it."""
    missed = misses(realdata, lecture_config)
    assert len(missed) >= 4, missed
    assert all(name.startswith("pic") for name, _ in missed), missed


def with_changes(**changes):
    def config():
        config = core.LineDetectorConfig()
        for field, value in changes.items():
            setattr(config, field, value)
        return config

    return config


def test_the_floor_test_not_a_v_floor_keeps_dark_floor_out(realdata):
    """Without the floor test a V floor low enough for paint in a shadow lets dark, warm floor in
    (a line reported on frames without one, or the line lost in a floor blob); with it, no V floor
    is needed at all."""
    no_floor_test = misses(realdata, with_changes(floor_margin=0))
    assert len(no_floor_test) >= 5, no_floor_test
    assert misses(realdata, with_changes(lower=core.HsvColor(h=20, s=100, v=0))) == []


LINES = sum(label is not None for label in LABELS.values())


def count_in_shadow(
    realdata, detector_config, brightness, tint=SKY_SHADOW_TINT, stripe=False, columns=None
):
    """Over the labelled bands in a shadow: (lines found, bands without a line left without one).
    `stripe`: the shadow over a stripe round the label (the middle column without one) alone;
    `columns`: over those columns alone."""
    hits = clean = 0
    for (name, first_row), label in LABELS.items():
        column = (320 if label is None else label) if stripe else None
        band = measure(
            realdata, detector_config, name, first_row, brightness, tint, column, columns
        )
        if label is None:
            clean += not band.found
        else:
            hits += verdict(band, label)
    return hits, clean


def test_the_line_in_a_shadow_on_the_real_frames(realdata, record_property):
    """Every labelled frame as if a bluish hard shadow covered it: at 55 % of the light nearly
    every line is still found, at 30 % most. There real paint's yellowness is ~45, at the floor
    test's full margin (40), which found 15 of 24; the margin now dims with the band's brightest
    pixels. The misses are paint the shadow takes out of the colour box (S < 100, or V < 40 on
    the dark warm cast of pic2). A line where there is none, never. The lecture finds none at
    30 %."""
    found = {}
    for brightness in (0.55, 0.3):
        hits, clean = count_in_shadow(realdata, core.LineDetectorConfig, brightness)
        lecture_hits, _ = count_in_shadow(realdata, lecture_config, brightness)
        found[brightness] = hits
        record_property(f"shadow {brightness}", f"{hits}/{LINES} lines, lecture {lecture_hits}")
        assert clean == len(LABELS) - LINES, brightness
        if brightness == 0.3:
            assert lecture_hits == 0
    assert found[0.55] >= 22, found
    assert found[0.3] >= 21, found


def test_the_line_in_a_bluer_shadow_needs_the_wider_hue_window(realdata, record_property):
    """The frames under a bluer shadow (BGR gains 1.3, 1.0, 0.85: lit by clear sky alone), whose
    tint moves real paint's hue towards green: the default hue window (h_max 40) still finds
    nearly as many lines as under the mild tint, the former 34 about half to 60 % as many; a
    line where there is none, never."""
    narrow = with_changes(upper=core.HsvColor(h=34, s=255, v=255))
    found = {}
    for brightness in (0.55, 0.3):
        for name, config in (("default", core.LineDetectorConfig), ("h_max 34", narrow)):
            hits, clean = count_in_shadow(realdata, config, brightness, BLUER_SHADOW_TINT)
            assert clean == len(LABELS) - LINES, (name, brightness)
            found[name, brightness] = hits
        record_property(
            f"bluer shadow {brightness}",
            f"{found['default', brightness]}/{LINES} lines, "
            f"h_max 34: {found['h_max 34', brightness]}",
        )
    # Measured: 20 and 16 of 24 with the default; 12 and 8 with h_max 34 (before the floor
    # test's margin dimmed with the band: 20 and 12; 12 and 6).
    assert found["default", 0.55] >= 20 and found["default", 0.3] >= 16, found
    assert found["h_max 34", 0.55] <= 13 and found["h_max 34", 0.3] <= 9, found


def test_the_line_in_a_shadow_over_it_alone_on_the_real_frames(realdata, record_property):
    """Every labelled band under a bluer shadow 160 columns wide centred on its label (or on the
    middle column where there is no line), the floor beside it lit: the band's floor statistic
    is the lit floor's, so each column block is judged in its own light. Measured: 20 and 18 of
    24 lines at 55 % and 30 % of the light (5 of 24 at 30 % with one threshold for the band, 16
    and 15 with blobs compared by chroma, which the shadow dims, instead of saturation); the
    misses are paint whose tinted hue leaves the colour box, or a lit warm cast elsewhere in the
    band; a line where there is none, never."""
    found = {}
    for brightness in (0.55, 0.3):
        hits, clean = count_in_shadow(
            realdata, core.LineDetectorConfig, brightness, BLUER_SHADOW_TINT, stripe=True
        )
        assert clean == len(LABELS) - LINES, brightness
        found[brightness] = hits
        record_property(f"shadow stripe {brightness}", f"{hits}/{LINES} lines")
    assert found[0.55] >= 20 and found[0.3] >= 18, found


# A shadow's edge across every labelled band: the shadow over these columns, the rest lit.
SHADOW_EDGES = {
    "left half": slice(0, 320),
    "right half": slice(320, None),
    "left 70 %": slice(0, 448),
    "right 70 %": slice(192, None),
}
# Lines found at 55 % and 30 % of the light (measured).
LINES_BESIDE_AN_EDGE = {
    "left half": (21, 14),
    "right half": (24, 24),
    "left 70 %": (20, 11),
    "right 70 %": (23, 22),
}


def test_the_lit_floor_beside_a_shadow_edge_is_no_line_on_the_real_frames(
    realdata, record_property
):
    """Every labelled band with a bluer shadow's edge across it: where the shadow covers most of
    the band, the lit floor beside the edge is judged by a lit block's own floor test, so it is
    never a line where there is none (before that rule, a false line in five of these cases:
    pic5 rows 450 or 226nightCoordination_0016). Most lines lost are in the shadow at 30 %, with
    a warm cast's glare left in the lit part."""
    for edge, columns in SHADOW_EDGES.items():
        for brightness, least in zip((0.55, 0.3), LINES_BESIDE_AN_EDGE[edge], strict=True):
            hits, clean = count_in_shadow(
                realdata, core.LineDetectorConfig, brightness, BLUER_SHADOW_TINT, columns=columns
            )
            record_property(f"shadow {edge} {brightness}", f"{hits}/{LINES} lines, {clean} clean")
            assert clean == len(LABELS) - LINES, (edge, brightness)
            assert hits >= least, (edge, brightness, hits)
