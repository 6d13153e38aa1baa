"""The floor as one texture, composed once per world: its generated or image texture, the painted
lines, the objects' and the realism's baked shadows (harness.render warps it into each frame).
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from harness.realism import Realism
from harness.render_items import box_corners, marker_geometry
from harness.textures import (
    floor_texture,
    shadow_band_mask,
    shadow_gains,
)
from harness.world import Box, Sphere, World, WorldObject


def texture_to_world(shape: tuple[int, ...], metres_per_pixel: float, origin) -> np.ndarray:
    """3x3 affine map from image pixel (col, row, 1) to world (x, y, 1).

    `origin` is the world position of the image's lower-left corner; rows run towards -y,
    so the image reads like a map with +y up. Pixel centres sit at integer coordinates.
    """
    rows = shape[0]
    m = metres_per_pixel
    return np.array(
        [
            [m, 0.0, origin[0] + 0.5 * m],
            [0.0, -m, origin[1] + (rows - 0.5) * m],
            [0.0, 0.0, 1.0],
        ]
    )


def _stamp_polyline(alpha: np.ndarray, pts_px: np.ndarray, closed: bool, half_px: float) -> None:
    """Max-accumulate anti-aliased coverage of a thick polyline (pixel units) into alpha.

    Coverage is 0.5 exactly at the line edge (box-filter approximation), so the painted
    line's width and centre match the geometric ones to sub-pixel accuracy.
    """
    ends = np.roll(pts_px, -1, axis=0) if closed else pts_px[1:]
    starts = pts_px if closed else pts_px[:-1]
    reach = half_px + 1.0
    h, w = alpha.shape
    for a, b in zip(starts, ends, strict=False):
        x0 = max(int(math.floor(min(a[0], b[0]) - reach)), 0)
        x1 = min(int(math.ceil(max(a[0], b[0]) + reach)), w - 1)
        y0 = max(int(math.floor(min(a[1], b[1]) - reach)), 0)
        y1 = min(int(math.ceil(max(a[1], b[1]) + reach)), h - 1)
        if x0 > x1 or y0 > y1:
            continue
        gx, gy = np.meshgrid(np.arange(x0, x1 + 1), np.arange(y0, y1 + 1))
        d = b - a
        t = np.clip(((gx - a[0]) * d[0] + (gy - a[1]) * d[1]) / max(d @ d, 1e-12), 0.0, 1.0)
        dist = np.hypot(gx - a[0] - t * d[0], gy - a[1] - t * d[1])
        cover = np.clip(half_px - dist + 0.5, 0.0, 1.0)
        patch = alpha[y0 : y1 + 1, x0 : x1 + 1]
        np.maximum(patch, cover, out=patch)


def _blend(image: np.ndarray, alpha: np.ndarray, colour) -> None:
    """In place: image = image * (1 - alpha) + colour * alpha, for float alpha in [0, 1]."""
    a = alpha[..., None]
    image[...] = np.rint(image * (1.0 - a) + np.asarray(colour, dtype=np.float32) * a)


def _world_to_tex_px(world_to_px: np.ndarray, xy: np.ndarray) -> np.ndarray:
    h = np.column_stack([xy, np.ones(len(xy))]) @ world_to_px.T
    return h[:, :2] / h[:, 2:3]


def _shadow_outlines(obj: WorldObject, light: np.ndarray) -> np.ndarray:
    """World points whose projection onto the floor along the light bounds the object's shadow."""
    if isinstance(obj, Sphere):
        c = np.array(obj.position)
        u = np.cross(light, [1.0, 0.0, 0.0] if abs(light[0]) < 0.9 else [0.0, 1.0, 0.0])
        u /= np.linalg.norm(u)
        v = np.cross(light, u)
        ang = np.linspace(0.0, 2.0 * math.pi, 48, endpoint=False)
        return c + obj.radius * (np.outer(np.cos(ang), u) + np.outer(np.sin(ang), v))
    if isinstance(obj, Box):
        return box_corners(obj.size, obj.pose)
    marker = marker_geometry(obj)
    if marker.post is None:
        return marker.corners
    return np.vstack([marker.corners, box_corners(*marker.post)])


def ground_texture(
    world: World, with_shadows: bool = True, realism: Realism | None = None, seed: int = 0
) -> tuple[np.ndarray, np.ndarray]:
    """(BGR floor image without gain, 3x3 texture-pixel -> world map); built once per world.
    With `realism`: its generated floor under the lines, and its shadow bands over everything."""
    g = world.ground
    m = g.metres_per_pixel
    cols, rows = round(g.size[0] / m), round(g.size[1] / m)
    if realism is not None and realism.floor != "plain":
        tex = floor_texture(realism.floor, (rows, cols), m, seed)
    else:
        tex = np.empty((rows, cols, 3), np.uint8)
        tex[:] = g.colour
    tex_to_world = texture_to_world(tex.shape, m, g.origin)
    world_to_px = np.linalg.inv(tex_to_world)
    if g.texture is not None:
        src = texture_to_world(g.texture.image.shape, g.texture.metres_per_pixel, g.texture.origin)
        cv2.warpAffine(
            g.texture.image,
            (world_to_px @ src)[:2],
            (cols, rows),
            dst=tex,
            flags=cv2.INTER_LINEAR,
            borderMode=cv2.BORDER_TRANSPARENT,
        )
    for line in g.lines:
        alpha = np.zeros((rows, cols), np.float32)
        pts = _world_to_tex_px(world_to_px, line.points)
        _stamp_polyline(alpha, pts, line.closed, 0.5 * line.width / m)
        ys, xs = np.nonzero(alpha)
        if len(ys):
            sl = np.s_[ys.min() : ys.max() + 1, xs.min() : xs.max() + 1]
            _blend(tex[sl], alpha[sl], line.colour)
    lighting = world.lighting
    if with_shadows and lighting.shadows and world.objects:
        light = np.array(lighting.direction)
        shade = lighting.ambient / (lighting.ambient + (1.0 - lighting.ambient) * light[2])
        mask = np.zeros((rows, cols), np.uint8)
        for obj in world.objects:
            p = _shadow_outlines(obj, light)
            floor = p[:, :2] - np.outer(p[:, 2] / light[2], light[:2])
            hull = cv2.convexHull(_world_to_tex_px(world_to_px, floor).astype(np.float32))
            cv2.fillConvexPoly(mask, np.rint(hull * 16).astype(np.int32), 255, cv2.LINE_AA, 4)
        ys, xs = np.nonzero(mask)
        if len(ys):
            sl = np.s_[ys.min() : ys.max() + 1, xs.min() : xs.max() + 1]
            factor = 1.0 - (1.0 - shade) * mask[sl].astype(np.float32) / 255.0
            tex[sl] = np.rint(tex[sl] * factor[..., None])
    if realism is not None and realism.shadow_bands and not realism.shadow_drift:
        bands = shadow_band_mask((rows, cols), m, realism.shadow_bands, seed)
        if realism.shadow_tint:
            gains = shadow_gains(realism.shadow_depth, realism.shadow_tint)
            tex[:] = np.rint(tex * (1.0 - (1.0 - gains) * bands[..., None]))
        else:
            factor = 1.0 - (1.0 - realism.shadow_depth) * bands
            tex[:] = np.rint(tex * factor[..., None])
    return tex, tex_to_world
