"""The camera's per-frame effects a realism turns on (`Sensor.apply`): motion blur over the
exposure, vignetting, exposure drift and per-channel white balance, brightness-dependent noise,
JPEG artefacts. Keyed by the run's seed and the frame's index, so a run repeats exactly.
"""

from __future__ import annotations

import functools
import math
from statistics import NormalDist

import cv2
import numpy as np

from harness.realism import Realism, rng_for


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
