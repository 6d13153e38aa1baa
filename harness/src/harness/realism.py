"""A camera as real as a robot's: floor textures, walls, shadows, distractors and sensor effects.

Everything is an option of the world's `realism` section or a scenario's `perturbations.realism`
(schema in worlds/SCHEMA.md); `profile: realistic` turns on a plausible mix. All of it is drawn
from RNGs keyed by the run's seed, so a run repeats exactly:
- scene (once per world): a generated floor texture, hard shadow bands baked into the floor, walls
  along the floor's edge, and distractors added to the world (harness.distractors);
- sensor (per frame, `Sensor.apply`): motion blur over the exposure, vignetting, exposure drift and
  per-channel white balance, brightness-dependent noise, JPEG artefacts;
- drifting shadow bands (`DriftingShadows`, drawn over the floor of each frame), a barrel lens,
  dropped frames, and the base's actuation delay and first-order motor lag (harness.simulation).
A numeric option may be a range [low, high]: each run draws its value from the run's seed
(`realism_from`), so `profile: harsh` is a different room, camera and base in every run.
"""

from __future__ import annotations

import functools
import math
import zlib
from dataclasses import dataclass, fields, replace
from statistics import NormalDist
from typing import Any

import cv2
import numpy as np

from harness.validation import (
    Fields,
    ValidationError,
    boolean,
    integer,
    number,
    string,
)

FLOORS = ("plain", "wood", "tiles", "carpet", "concrete")
WALL_TEXEL_M = 0.02
SHADOW_SOFT_M = 0.01  # penumbra width of a shadow band's edge


@dataclass(frozen=True)
class Realism:
    """Every realism option; the defaults are the clean world (all off)."""

    floor: str = "plain"  # generated floor texture, one of FLOORS
    walls: float = 0.0  # height (m) of walls along the floor's edge; 0: open horizon
    shadow_bands: int = 0  # hard shadows (window frames, furniture) crossing the floor
    shadow_depth: float = 0.5  # brightness of the floor in a band (fraction of lit)
    exposure_drift: float = 0.0  # amplitude of the auto-exposure's slow gain drift (fraction)
    exposure_period: float = 9.0  # s, period of that drift
    white_balance: float = 0.0  # largest per-channel gain deviation (fraction), drifting too
    vignetting: float = 0.0  # brightness lost in the image corners (fraction)
    exposure_time: float = 0.0  # s: motion blur from the robot's motion during the exposure
    read_noise: float = 0.0  # grey levels, the noise floor
    shot_noise: float = 0.0  # noise variance per grey level of signal (photon noise)
    jpeg_quality: int = 0  # 1..100: frames pass through JPEG at this quality; 0: off
    lane_line: float = 0.0  # offset (m, right of line 0) of a parallel white line; 0: none
    tape: int = 0  # yellow tape pieces on the floor off the course
    yellow_box: bool = False  # a yellow box off the course
    clutter: int = 0  # extra coloured boxes and balls away from the robot's way
    posters: int = 0  # textured posters beside each marker (tag or sign)
    shadow_drift: float = 0.0  # m/s the shadow bands move across the floor; 0: baked, still
    shadow_tint: float = 0.0  # skylight in the shadows: blue gain 1 + tint, red 1 - tint
    barrel: float = 0.0  # barrel lens: plumb_bob k1 = -barrel, k2 = barrel / 4; 0: pinhole
    frame_drop: float = 0.0  # probability that a frame never reaches the behaviour
    actuation_delay: float = 0.0  # s from a command to the base acting on it
    motor_lag: float = 0.0  # s, time constant of the base's first-order velocity response

    @property
    def sensor_active(self) -> bool:
        return bool(
            self.exposure_drift or self.white_balance or self.vignetting or self.exposure_time
            or self.read_noise or self.shot_noise or self.jpeg_quality
        )  # fmt: skip


PROFILES: dict[str, dict[str, Any]] = {
    # A plausible indoor camera: a tiled floor under window shadows, walls, an auto-exposure
    # that breathes +-12 %, a warm white balance, a cheap lens's vignetting, 15 ms exposure,
    # photon noise, JPEG 60, and the clutter of a lab.
    "realistic": {
        "floor": "tiles",
        "walls": 1.2,
        "shadow_bands": 3,
        "shadow_depth": 0.55,
        "exposure_drift": 0.12,
        "white_balance": 0.08,
        "vignetting": 0.3,
        "exposure_time": 0.015,
        "read_noise": 1.5,
        "shot_noise": 0.04,
        "jpeg_quality": 60,
        "lane_line": 0.3,
        "tape": 6,
        "yellow_box": True,
        "clutter": 4,
        "posters": 2,
    },
    # A real room, camera and base, everything at once and at full strength; the ranges are
    # drawn per run from its seed. An oak floor whose hue sits near the line's, hard shadows
    # at 30-55 % drifting across the line with a bluish (skylight) tint, a barrel lens, exposure
    # and white-balance drift with vignetting, motion blur, JPEG 60, noise, dropped frames,
    # and a base that acts 50-150 ms late through a 0.1-0.2 s first-order motor lag.
    "harsh": {
        "floor": "wood",
        "walls": 1.2,
        "shadow_bands": (3, 6),
        "shadow_depth": (0.30, 0.55),
        "shadow_drift": (0.02, 0.10),
        "shadow_tint": (0.10, 0.25),
        "exposure_drift": (0.10, 0.25),
        "exposure_period": (4.0, 12.0),
        "white_balance": (0.05, 0.15),
        "vignetting": (0.25, 0.45),
        "exposure_time": (0.01, 0.03),
        "read_noise": (1.5, 4.0),
        "shot_noise": (0.04, 0.12),
        "jpeg_quality": 60,
        "lane_line": (0.15, 0.35),
        "tape": (4, 10),
        "yellow_box": True,
        "clutter": (2, 6),
        "posters": 2,
        "barrel": (0.20, 0.35),
        "frame_drop": (0.03, 0.15),
        "actuation_delay": (0.05, 0.15),
        "motor_lag": (0.10, 0.20),
    },
}

_OPTION_PARSERS = {
    "floor": string,
    "walls": number(ge=0.0),
    "shadow_bands": integer(ge=0),
    "shadow_depth": number(ge=0.0, le=1.0),
    "exposure_drift": number(ge=0.0, lt=1.0),
    "exposure_period": number(gt=0.0),
    "white_balance": number(ge=0.0, lt=1.0),
    "vignetting": number(ge=0.0, lt=1.0),
    "exposure_time": number(ge=0.0, le=0.2),
    "read_noise": number(ge=0.0),
    "shot_noise": number(ge=0.0),
    "jpeg_quality": integer(ge=0),
    "lane_line": number(),
    "tape": integer(ge=0),
    "yellow_box": boolean,
    "clutter": integer(ge=0),
    "posters": integer(ge=0),
    "shadow_drift": number(ge=0.0),
    "shadow_tint": number(ge=0.0, lt=1.0),
    "barrel": number(ge=0.0, le=1.0),
    "frame_drop": number(ge=0.0, lt=1.0),
    "actuation_delay": number(ge=0.0, le=1.0),
    "motor_lag": number(ge=0.0, le=2.0),
}
assert set(_OPTION_PARSERS) == {f.name for f in fields(Realism)}
# Options a range [low, high] may give (drawn per run); integers are drawn inclusively.
_NUMBERS = {f.name for f in fields(Realism) if f.type in ("float", "int")}
_INTEGERS = {f.name for f in fields(Realism) if f.type == "int"}


def _option(key: str, value: Any, where: str) -> Any:
    """One option's value, or for a numeric option given as [low, high] the range (a tuple)."""
    parse = _OPTION_PARSERS[key]
    if not (isinstance(value, list) and key in _NUMBERS):
        return parse(value, where)
    if len(value) != 2:
        raise ValidationError(f"{where}: a value or a range [low, high], got {value!r}")
    low, high = (parse(v, f"{where}[{i}]") for i, v in enumerate(value))
    if high < low:
        raise ValidationError(f"{where}: needs low <= high, got {value!r}")
    return (low, high)


def parse_realism(value: Any, where: str) -> dict[str, Any]:
    """The options a `realism` mapping sets: a `profile`'s, then the fields given beside it."""
    f = Fields(value, where, {"profile", *_OPTION_PARSERS})
    out: dict[str, Any] = {}
    if f.has("profile"):
        profile = f.get("profile", string)
        if profile not in PROFILES:
            raise ValidationError(
                f"{f.where('profile')}: unknown profile {profile!r} (known: {', '.join(PROFILES)})"
            )
        out.update(PROFILES[profile])
    for key in _OPTION_PARSERS:
        if f.has(key):
            out[key] = f.get(key, lambda v, w, key=key: _option(key, v, w))
    if out.get("floor", "plain") not in FLOORS:
        raise ValidationError(f"{f.where('floor')}: one of {', '.join(FLOORS)}")
    if max(np.atleast_1d(out.get("jpeg_quality", 0))) > 100:
        raise ValidationError(f"{f.where('jpeg_quality')}: 1..100, or 0 for no JPEG")
    return out


def drawn(options: dict[str, Any], seed: int) -> dict[str, Any]:
    """`options` with each range [low, high] replaced by the run's value: uniform (integers:
    each whole number in it equally likely) from an RNG keyed by the seed and the option's name,
    so one option's draw does not change when others are added or dropped."""
    out = dict(options)
    for key, value in options.items():
        if isinstance(value, tuple):
            rng = rng_for(seed, 11, zlib.crc32(key.encode()))
            low, high = value
            out[key] = (
                int(rng.integers(low, high + 1))
                if key in _INTEGERS
                else float(rng.uniform(low, high))
            )
    return out


def realism_from(options: dict[str, Any], base: Realism | None = None, seed: int = 0) -> Realism:
    """The Realism of `options` laid over `base`, ranges drawn from `seed` (the run's)."""
    return replace(base or Realism(), **drawn(options, seed))


def barrel_distortion(barrel: float) -> tuple[float, float, float, float, float]:
    """The plumb_bob coefficients of a barrel lens of strength `barrel` (0.28: turtlebot3's)."""
    return (-barrel, barrel / 4.0, 0.0, 0.0, 0.0)


def rng_for(seed: int, *stream: int) -> np.random.Generator:
    """An RNG of its own for each use of the run's seed (textures, placement, per-frame noise)."""
    return np.random.default_rng((seed, 7919, *stream))


# --- generated textures ---------------------------------------------------------------------


def smooth_noise(rng: np.random.Generator, shape: tuple[int, int], cells: int) -> np.ndarray:
    """Zero-mean, unit-ish float32 noise varying over about shape / cells pixels."""
    rows, cols = shape
    coarse = rng.standard_normal((max(2, rows // cells), max(2, cols // cells))).astype(np.float32)
    return cv2.resize(coarse, (cols, rows), interpolation=cv2.INTER_CUBIC)


def floor_texture(kind: str, shape: tuple[int, int], mpp: float, seed: int) -> np.ndarray:
    """BGR uint8 floor of `shape` pixels at `mpp` metres per pixel, drawn from `seed`."""
    rng = rng_for(seed, 1)
    rows, cols = shape
    px = 1.0 / mpp  # pixels per metre
    yy = np.arange(rows, dtype=np.float32)[:, None]
    xx = np.arange(cols, dtype=np.float32)[None, :]
    if kind == "wood":
        # Oak planks 12 cm wide, 0.9-1.5 m long, staggered; hue ~15 (OpenCV), below the
        # line's yellow (20-30); grain along each plank, a dark seam between planks.
        base = np.array([95, 140, 185], np.float32)
        width = 0.12 * px
        plank = (yy // width).astype(np.int64)
        n_planks = int(plank.max()) + 1
        length = 1.2 * px
        shift = rng.uniform(0.0, length, n_planks).astype(np.float32)[plank]
        piece = ((xx + shift) // length).astype(np.int64)
        tint = rng.normal(0.0, 0.07, (n_planks, int(piece.max()) + 2)).astype(np.float32)
        brightness = 1.0 + tint[plank, piece]
        across = (yy % width) / width
        grain = 0.05 * np.sin(2 * np.pi * (3.0 * across + 0.2 * xx / px + plank * 0.37))
        brightness = brightness + grain + 0.03 * smooth_noise(rng, shape, max(2, int(0.3 * px)))
        seam_px = max(1.0, 0.004 * px)
        seam = ((yy % width) < seam_px) | (((xx + shift) % length) < seam_px)
        brightness = np.where(seam, 0.55, brightness)
        return np.clip(base * brightness[..., None], 0, 255).astype(np.uint8)
    if kind == "tiles":
        # 30 cm ceramic tiles, each a slightly different cream, 8 mm grey grout.
        base = np.array([200, 210, 215], np.float32)
        tile = 0.30 * px
        grout = max(1.0, 0.008 * px)
        ti, tj = (yy // tile).astype(np.int64), (xx // tile).astype(np.int64)
        tint = rng.normal(0.0, 0.03, (int(ti.max()) + 1, int(tj.max()) + 1)).astype(np.float32)
        brightness = 1.0 + tint[ti, tj] + 0.02 * smooth_noise(rng, shape, max(2, int(0.1 * px)))
        image = base * brightness[..., None]
        is_grout = ((yy % tile) < grout) | ((xx % tile) < grout)
        image = np.where(is_grout[..., None], np.array([120, 125, 130], np.float32), image)
        return np.clip(image, 0, 255).astype(np.uint8)
    if kind == "carpet":
        # Blue-grey loop pile: per-pixel fibre noise over a mottled pattern.
        base = np.array([120, 100, 90], np.float32)
        fibre = rng.standard_normal(shape).astype(np.float32)
        mottle = smooth_noise(rng, shape, max(2, int(0.25 * px)))
        brightness = 1.0 + 0.12 * fibre + 0.06 * mottle
        return np.clip(base * brightness[..., None], 0, 255).astype(np.uint8)
    if kind == "concrete":
        # Polished grey concrete with stains at several scales and a few dark blots.
        base = np.array([135, 138, 140], np.float32)
        brightness = (
            1.0
            + 0.08 * smooth_noise(rng, shape, max(2, int(1.5 * px)))
            + 0.05 * smooth_noise(rng, shape, max(2, int(0.3 * px)))
            + 0.03 * rng.standard_normal(shape).astype(np.float32)
        )
        stains = np.zeros(shape, np.float32)
        for _ in range(int(rows * cols * mpp * mpp / 4.0) + 1):  # one per 4 m^2
            centre = (int(rng.uniform(0, cols)), int(rng.uniform(0, rows)))
            axes = (int(rng.uniform(0.1, 0.5) * px), int(rng.uniform(0.1, 0.4) * px))
            cv2.ellipse(stains, centre, axes, rng.uniform(0, 180), 0, 360, 1.0, -1)
        stains = cv2.GaussianBlur(stains, (0, 0), 0.05 * px)
        brightness -= 0.25 * stains
        return np.clip(base * brightness[..., None], 0, 255).astype(np.uint8)
    raise ValueError(f"unknown floor {kind!r}")


def shadow_band_mask(shape: tuple[int, int], mpp: float, count: int, seed: int) -> np.ndarray:
    """Float32 coverage in [0, 1] of `count` straight shadow bands (0.2-0.6 m wide) crossing the
    whole floor at random angles, with hard (1 cm penumbra) edges."""
    rng = rng_for(seed, 2)
    rows, cols = shape
    mask = np.zeros(shape, np.uint8)
    diag = math.hypot(rows, cols)
    for _ in range(count):
        centre = np.array([rng.uniform(0, cols), rng.uniform(0, rows)])
        angle = rng.uniform(0.0, math.pi)
        along = np.array([math.cos(angle), math.sin(angle)]) * diag
        across = np.array([-math.sin(angle), math.cos(angle)]) * rng.uniform(0.1, 0.3) / mpp
        quad = np.array([centre - along - across, centre + along - across,
                         centre + along + across, centre - along + across])  # fmt: skip
        cv2.fillConvexPoly(mask, np.rint(quad * 16).astype(np.int32), 255, cv2.LINE_AA, 4)
    soft = max(SHADOW_SOFT_M / mpp, 0.5)
    return cv2.GaussianBlur(mask.astype(np.float32) / 255.0, (0, 0), soft)


def shadow_gains(depth: float, tint: float) -> np.ndarray:
    """B, G, R brightness inside a shadow: `depth` of lit, bluer by `tint` (a shadow is lit by
    the blue sky only, not by the sun)."""
    return depth * np.array([1.0 + tint, 1.0, 1.0 - tint], np.float32)


class DriftingShadows:
    """Hard shadow bands (as `shadow_band_mask`'s) that move across the floor along their
    normals at `shadow_drift` m/s, each its own way, leaving one side of the floor and coming
    back at the other. The renderer draws them over the floor of each frame, before any
    object, with anti-aliased (not 1 cm soft) edges."""

    def __init__(self, realism: Realism, origin, size, seed: int):
        rng = rng_for(seed, 2)
        corners = np.array(origin) + np.array([[0, 0], [size[0], 0], [0, size[1]], size])
        self.normals, self.offsets, self.half, self.speed, self.low, self.span = (
            [] for _ in range(6)
        )
        for _ in range(realism.shadow_bands):
            centre = rng.uniform(origin, np.array(origin) + np.array(size))
            angle = rng.uniform(0.0, math.pi)
            normal = np.array([-math.sin(angle), math.cos(angle)])
            half = rng.uniform(0.1, 0.3)
            reach = corners @ normal
            self.normals.append(normal)
            self.offsets.append(float(centre @ normal))
            self.half.append(half)
            self.speed.append(realism.shadow_drift * rng.choice([-1.0, 1.0]))
            self.low.append(float(reach.min()) - half)
            self.span.append(float(reach.max() - reach.min()) + 2.0 * half)
        self.gains = shadow_gains(realism.shadow_depth, realism.shadow_tint)
        # Half the length of a band's quad, from the point of its centre line nearest the world
        # origin: beyond every corner of the floor.
        self.reach = float(np.max(np.hypot(*corners.T))) + 1.0

    def band_offsets(self, t: float) -> list[float]:
        """Each band's centre (its distance along its normal from the world origin) at time t."""
        return [
            low + (offset + speed * t - low) % span
            for offset, speed, low, span in zip(
                self.offsets, self.speed, self.low, self.span, strict=True
            )
        ]

    def quads(self, t: float) -> list[np.ndarray]:
        """Each band at time t as a floor quad (4 x 2, world metres), long enough to cross the
        whole floor."""
        out = []
        for normal, centre, half, span in zip(
            self.normals, self.band_offsets(t), self.half, self.span, strict=True
        ):
            along = np.array([-normal[1], normal[0]]) * max(span, self.reach)
            near, far = centre * normal - half * normal, centre * normal + half * normal
            out.append(np.array([near - along, near + along, far + along, far - along]))
        return out


def wall_texture(length_m: float, height_m: float, colour, seed: int) -> np.ndarray:
    """A painted wall: mottled paint, a dark skirting board, a door and a few framed pictures."""
    rng = rng_for(seed, 3)
    px = 1.0 / WALL_TEXEL_M
    rows, cols = max(2, round(height_m * px)), max(2, round(length_m * px))
    brightness = 1.0 + 0.04 * smooth_noise(rng, (rows, cols), 8)
    image = np.clip(np.asarray(colour, np.float32) * brightness[..., None], 0, 255).astype(np.uint8)
    skirting = max(1, round(0.08 * px))
    image[rows - skirting :] = (60, 65, 70)
    n_items = max(1, int(length_m / 2.5))
    for _ in range(n_items):
        w = int(rng.uniform(0.3, 0.9) * px)
        h = int(rng.uniform(0.2, 0.5) * px)
        x0 = int(rng.uniform(0, max(1, cols - w)))
        y0 = int(rng.uniform(0.1, 0.4) * px)
        col = tuple(int(c) for c in rng.integers(30, 200, 3))
        cv2.rectangle(image, (x0, y0), (x0 + w, min(rows - skirting, y0 + h)), col, -1)
    return image


# --- per-frame sensor -----------------------------------------------------------------------


@functools.cache
def gaussian_table() -> np.ndarray:
    """Standard-normal quantiles at the 65536 midpoints of [0, 1]: indexing it with random
    uint16 codes draws Gaussian noise ~5x faster than Generator.standard_normal."""
    dist = NormalDist()
    return np.array([dist.inv_cdf((i + 0.5) / 65536) for i in range(65536)], np.float32)


def vignette(width: int, height: int, strength: float) -> np.ndarray:
    """Float32 (height, width) gain: 1 at the centre, 1 - strength in the corners (cos^4-like)."""
    u = (np.arange(width, dtype=np.float32) - (width - 1) / 2.0) / ((width - 1) / 2.0)
    v = (np.arange(height, dtype=np.float32) - (height - 1) / 2.0) / ((height - 1) / 2.0)
    r2 = (u[None, :] ** 2 + v[:, None] ** 2) / 2.0  # 1 in the corners
    return (1.0 - strength * r2).astype(np.float32)


def line_kernel(dx: float, dy: float) -> np.ndarray | None:
    """Normalised box kernel along the motion (dx, dy) px; None when under half a pixel."""
    length = math.hypot(dx, dy)
    if length < 0.5:
        return None
    size = 2 * math.ceil(length / 2.0) + 1
    kernel = np.zeros((size, size), np.float32)
    c = size // 2
    steps = max(2, math.ceil(length * 4))
    for s in np.linspace(-0.5, 0.5, steps):
        x, y = c + s * dx, c + s * dy
        x0, y0 = math.floor(x), math.floor(y)
        fx, fy = x - x0, y - y0
        for ix, iy, wgt in ((x0, y0, (1 - fx) * (1 - fy)), (x0 + 1, y0, fx * (1 - fy)),
                            (x0, y0 + 1, (1 - fx) * fy), (x0 + 1, y0 + 1, fx * fy)):  # fmt: skip
            if 0 <= ix < size and 0 <= iy < size:
                kernel[iy, ix] += wgt
    return kernel / kernel.sum()


class Sensor:
    """The per-frame camera effects of a Realism, seeded; `apply(image, frame, flow)`."""

    def __init__(self, realism: Realism, width: int, height: int, seed: int, rate_hz: float):
        self.realism = realism
        self.seed = seed
        self.rate_hz = rate_hz
        rng = rng_for(seed, 6)
        self.wb = 1.0 + realism.white_balance * rng.uniform(-1.0, 1.0, 3)
        self.wb_phase = rng.uniform(0.0, 2.0 * math.pi, 3)
        self.exposure_phase = rng.uniform(0.0, 2.0 * math.pi)
        self.vignette = (
            np.repeat(vignette(width, height, realism.vignetting)[..., None], 3, axis=2)
            if realism.vignetting
            else None
        )
        levels = np.arange(256, dtype=np.float32)
        noisy = realism.read_noise > 0.0 or realism.shot_noise > 0.0
        sigma = np.sqrt(realism.read_noise**2 + realism.shot_noise * levels).astype(np.float32)
        self.noise_sigma = sigma if noisy else None

    def channel_gains(self, frame: int) -> np.ndarray:
        """B, G, R gain of frame `frame`: exposure drift times the (slowly drifting) balance."""
        r = self.realism
        t = frame / self.rate_hz
        phase = 2.0 * math.pi * t / r.exposure_period
        exposure = 1.0 + r.exposure_drift * math.sin(phase + self.exposure_phase)
        drift = 0.3 * r.white_balance * np.sin(0.37 * phase + self.wb_phase)
        return (exposure * (self.wb + drift)).astype(np.float32)

    def apply(self, image: np.ndarray, frame: int, flow_px: tuple[float, float]) -> np.ndarray:
        """Blur by `flow_px` (image motion over the exposure), then gains, noise and JPEG."""
        r = self.realism
        kernel = line_kernel(*flow_px) if r.exposure_time else None
        if kernel is not None:
            image = cv2.filter2D(image, -1, kernel, borderType=cv2.BORDER_REPLICATE)
        gains = self.channel_gains(frame)
        if self.vignette is not None:
            image = cv2.multiply(image, cv2.multiply(self.vignette, (*gains.tolist(), 0.0)),
                                 dtype=cv2.CV_8U)  # fmt: skip
        elif not np.allclose(gains, 1.0):
            image = cv2.multiply(image, (*gains.tolist(), 0.0), dtype=cv2.CV_8U)
        if self.noise_sigma is not None:
            # sigma^2 = read^2 + shot * signal, looked up per grey level; Gaussian draws from
            # uint16 codes through the quantile table (as the plain noise does, ~5x faster).
            rng = rng_for(self.seed, 8, frame)
            codes = np.frombuffer(rng.bytes(image.size * 2), np.uint16).reshape(image.shape)
            noise = gaussian_table()[codes]
            noise *= cv2.LUT(image, self.noise_sigma)
            image = cv2.add(image, noise, dtype=cv2.CV_8U)
        if r.jpeg_quality:
            ok, data = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, r.jpeg_quality])
            image = cv2.imdecode(data, cv2.IMREAD_COLOR)
        return image
