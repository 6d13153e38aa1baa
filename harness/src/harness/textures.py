"""The scene a realism generates once per world: floor textures, hard shadow bands baked into the
floor and the drifting ones drawn over each frame, walls along the floor's edge. Drawn from RNGs
keyed by the run's seed (harness.realism.rng_for), so a run repeats exactly.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from harness.realism import Realism, rng_for

WALL_TEXEL_M = 0.02
SHADOW_SOFT_M = 0.01  # penumbra width of a shadow band's edge


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
