"""A camera as real as a robot's, its options: floor textures, walls, shadows, distractors and
sensor effects, as the `Realism` the rest of the harness applies.

Everything is an option of the world's `realism` section or a scenario's `perturbations.realism`
(schema in worlds/SCHEMA.md); `profile: realistic` turns on a plausible mix. All of it is drawn
from RNGs keyed by the run's seed, so a run repeats exactly:
- scene (once per world): a generated floor texture, hard shadow bands baked into the floor, walls
  along the floor's edge (harness.textures), and distractors added to the world
  (harness.distractors);
- sensor (per frame, harness.sensor's `Sensor.apply`): motion blur over the exposure, vignetting,
  exposure drift and per-channel white balance, brightness-dependent noise, JPEG artefacts;
- drifting shadow bands (harness.textures' `DriftingShadows`, drawn over the floor of each
  frame), a barrel lens,
  dropped frames, and the base's actuation delay and first-order motor lag (harness.simulation).
A numeric option may be a range [low, high]: each run draws its value from the run's seed
(`realism_from`), so `profile: harsh` is a different room, camera and base in every run.
"""

from __future__ import annotations

import functools
import zlib
from dataclasses import dataclass, fields, replace
from typing import Any

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
            out[key] = f.get(key, functools.partial(_option, key))
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
