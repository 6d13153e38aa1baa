"""Fast software renderer: floor by plane homography, then objects far to near.

Everything that does not depend on the robot pose (floor texture with lines and baked
shadows, face shading, tag bitmaps and their mip levels) is prepared once in the
constructor, so a frame costs one cv2.warpPerspective for the floor plus a few small
per-object draws.
"""

from __future__ import annotations

import math
import time
from dataclasses import replace

import cv2
import numpy as np

from harness.apriltag_image import family_geometry, tag_image
from harness.camera import PINHOLE, Camera
from harness.distractors import with_distractors
from harness.geometry import clip_polygon_near, rot_z
from harness.realism import Realism
from harness.robot import integrate_unicycle
from harness.sensor import Sensor, gaussian_table
from harness.textures import (
    DriftingShadows,
    floor_texture,
    shadow_band_mask,
    shadow_gains,
    wall_texture,
)
from harness.world import AprilTagMarker, Box, Sphere, TextureMarker, World, WorldObject

Pose = tuple[float, float, float]

NEAR_M = 0.02  # near clipping distance in front of the optical centre
TAG_PX_PER_CELL = 64  # finest mip level of a tag board
POST_COLOUR = (90, 90, 90)
POST_SIDE_M = 0.04
BOARD_BACK_COLOUR = (150, 150, 150)
# Corner order of a box: bottom ring then top ring, counter-clockwise seen from above.
_RING = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]]
_BOX_SIGNS = np.array([[*xy, z] for z in (0.0, 1.0) for xy in _RING])
_BOX_FACES = (  # (corner indices in cyclic order, outward normal in the box frame)
    ((0, 1, 2, 3), (0.0, 0.0, -1.0)),
    ((4, 5, 6, 7), (0.0, 0.0, 1.0)),
    ((1, 2, 6, 5), (1.0, 0.0, 0.0)),
    ((0, 3, 7, 4), (-1.0, 0.0, 0.0)),
    ((2, 3, 7, 6), (0.0, 1.0, 0.0)),
    ((0, 1, 5, 4), (0.0, -1.0, 0.0)),
)


def lambert(normal: np.ndarray, light: np.ndarray, ambient: float) -> np.ndarray:
    """Brightness factor in [ambient, 1]: a surface facing the light shows its full colour."""
    return ambient + (1.0 - ambient) * np.maximum(0.0, normal @ light)


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
        return _box_corners(obj.size, obj.pose)
    marker = _marker_geometry(obj)
    if marker.post is None:
        return marker.corners
    return np.vstack([marker.corners, _box_corners(*marker.post)])


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


class _View:
    """Per-frame camera data shared by all object draws."""

    def __init__(self, camera: Camera, pose: Pose, light_world: np.ndarray):
        self.camera = camera
        self.r, self.t = camera.world_to_camera(pose)
        self.position = -self.r.T @ self.t
        self.light = self.r @ light_world

    def to_camera(self, points: np.ndarray) -> np.ndarray:
        return points @ self.r.T + self.t


def _fill_polygon(image: np.ndarray, camera: Camera, poly_cam: np.ndarray, colour) -> None:
    """Fill a convex optical-frame polygon, clipped at the near plane, at 1/16 px precision."""
    if poly_cam[:, 2].min() < NEAR_M:
        poly_cam = clip_polygon_near(poly_cam, NEAR_M)
        if len(poly_cam) < 3:
            return
    uv = camera.project_camera(poly_cam)
    cv2.fillConvexPoly(image, np.rint(uv * 16).astype(np.int32), colour, cv2.LINE_AA, 4)


def _box_corners(size, pose) -> np.ndarray:
    length, width, height = size
    x, y, yaw = pose
    local = _BOX_SIGNS * [length / 2.0, width / 2.0, height]
    return local @ rot_z(yaw).T + [x, y, 0.0]


class _BoxItem:
    """Box on the floor: back-face culled, per-face Lambert colour precomputed."""

    def __init__(self, size, pose, colour, gain: float, light: np.ndarray, ambient: float):
        self.corners = _box_corners(size, pose)
        self.anchor = np.array([pose[0], pose[1], size[2] / 2.0])
        rot = rot_z(pose[2])
        self.faces = []
        for idx, n in _BOX_FACES:
            normal = rot @ np.array(n)
            shade = gain * float(lambert(normal, light, ambient))
            col = tuple(min(255.0, c * shade) for c in colour)
            self.faces.append((list(idx), normal, self.corners[list(idx)].mean(axis=0), col))

    def draw(self, image: np.ndarray, view: _View) -> None:
        cam = view.to_camera(self.corners)
        in_front = cam[:, 2].min() >= NEAR_M
        if in_front:  # common case: project the 8 corners once
            uv16 = np.rint(view.camera.project_camera(cam) * 16).astype(np.int32)
        for idx, normal, centre, col in self.faces:
            if normal @ (view.position - centre) <= 0.0:
                continue
            if in_front:
                cv2.fillConvexPoly(image, uv16[idx], col, cv2.LINE_AA, 4)
            else:
                _fill_polygon(image, view.camera, cam[idx], col)


class _SphereItem:
    """Sphere ray-cast inside the bounding box of its exact (elliptic) silhouette."""

    def __init__(self, sphere: Sphere, gain: float, ambient: float):
        self.centre = np.array(sphere.position, dtype=float)
        self.anchor = self.centre
        self.radius = sphere.radius
        self.colour = np.array(sphere.colour, np.float32) * gain
        self.ambient = ambient

    def silhouette(self, view: _View) -> np.ndarray | None:
        """3x3 conic C of the silhouette (p^T C p > 0 inside), or None if not an ellipse."""
        c = view.to_camera(self.centre)
        k = c @ c - self.radius**2
        if k <= 0.0 or c[2] * math.sqrt(k) <= math.hypot(c[0], c[1]) * self.radius:
            return None
        k_inv = np.linalg.inv(view.camera.K)
        return k_inv.T @ (np.outer(c, c) - k * np.eye(3)) @ k_inv

    def draw(self, image: np.ndarray, view: _View) -> None:
        cam = view.camera
        c = view.to_camera(self.centre)
        k = float(c @ c - self.radius**2)
        if k <= 0.0:
            return  # camera inside the sphere
        conic = self.silhouette(view)
        if conic is None:
            u0, v0, u1, v1 = 0, 0, cam.width - 1, cam.height - 1
        else:
            dual = np.linalg.inv(conic)
            bounds = []
            for i in (0, 1):
                mid, half = dual[i, 2] / dual[2, 2], dual[i, 2] ** 2 - dual[2, 2] * dual[i, i]
                half = math.sqrt(max(half, 0.0)) / abs(dual[2, 2])
                bounds.append((math.floor(mid - half) - 1, math.ceil(mid + half) + 1))
            u0, u1 = max(bounds[0][0], 0), min(bounds[0][1], cam.width - 1)
            v0, v1 = max(bounds[1][0], 0), min(bounds[1][1], cam.height - 1)
            if u0 > u1 or v0 > v1:
                return
        f32 = np.float32
        cx, cy, cz = f32(c[0]), f32(c[1]), f32(c[2])
        dx = ((np.arange(u0, u1 + 1, dtype=f32) - f32(cam.cx)) / f32(cam.fx))[None, :]
        dy = ((np.arange(v0, v1 + 1, dtype=f32) - f32(cam.cy)) / f32(cam.fy))[:, None]
        kf = f32(k)
        dc = dx * cx + dy * cy + cz  # ray (dx, dy, 1) dotted with the centre
        d2 = dx * dx + dy * dy + f32(1.0)
        f = dc * dc - d2 * kf  # > 0 inside the silhouette cone
        grad_u = (dc * cx - dx * kf) * f32(2.0 / cam.fx)
        grad_v = (dc * cy - dy * kf) * f32(2.0 / cam.fy)
        signed_px = f / np.sqrt(grad_u * grad_u + grad_v * grad_v + f32(1e-30))
        alpha = np.clip(signed_px + f32(0.5), 0.0, 1.0) * (dc > 0.0)
        if not alpha.any():
            return
        inv_norm = f32(1.0) / np.sqrt(d2)
        b = dc * inv_norm
        t = b - np.sqrt(np.maximum(b * b - kf, 0.0))  # distance to the near intersection
        light = view.light
        # n.L with n = (t * ray_unit - c) / r, without forming the normal vectors.
        ray_l = (dx * f32(light[0]) + dy * f32(light[1]) + f32(light[2])) * inv_norm
        n_dot_l = (t * ray_l - f32(c @ light)) * f32(1.0 / self.radius)
        shade = f32(self.ambient) + f32(1.0 - self.ambient) * np.maximum(n_dot_l, 0.0)
        roi = image[v0 : v1 + 1, u0 : u1 + 1]
        a = alpha[..., None]
        mixed = roi * (f32(1.0) - a) + self.colour * (shade * alpha)[..., None]
        roi[...] = np.rint(np.minimum(mixed, 255.0))


class _MarkerGeometry:
    """World corners (front view: top-left, top-right, bottom-right, bottom-left) and post."""

    def __init__(self, pose, board_w: float, board_h: float, post: bool):
        x, y, z, yaw = pose
        self.centre = np.array([x, y, z])
        self.normal = np.array([math.cos(yaw), math.sin(yaw), 0.0])
        self.right = np.array([-math.sin(yaw), math.cos(yaw), 0.0])  # as seen from the front
        self.down = np.array([0.0, 0.0, -1.0])
        hw, hh = board_w / 2.0, board_h / 2.0
        self.corners = np.array(
            [self.centre + sx * hw * self.right + sy * hh * self.down for sx, sy in _QUAD]
        )
        post_height = z - hh + POST_SIDE_M
        behind = self.centre - (POST_SIDE_M / 2.0 + 0.005) * self.normal
        self.post = (
            ((POST_SIDE_M, POST_SIDE_M, post_height), (behind[0], behind[1], yaw)) if post else None
        )


_QUAD = ((-1, -1), (1, -1), (1, 1), (-1, 1))


def _tag_board(marker: AprilTagMarker) -> tuple[np.ndarray, float]:
    """Finest board bitmap (grey: white margin + library tag) and its physical edge in metres."""
    _, total, border = family_geometry(marker.family)
    first = (total - border) // 2
    bits = tag_image(marker.family, marker.tag_id)[first : first + border, first : first + border]
    square = np.kron(bits, np.ones((TAG_PX_PER_CELL, TAG_PX_PER_CELL), np.uint8))
    px_per_m = border * TAG_PX_PER_CELL / marker.size
    margin_px = round(marker.margin * px_per_m)
    board = cv2.copyMakeBorder(square, *[margin_px] * 4, cv2.BORDER_CONSTANT, value=255)
    return board, board.shape[1] / px_per_m


def _marker_geometry(marker: AprilTagMarker | TextureMarker) -> _MarkerGeometry:
    w, h = marker.board_size
    return _MarkerGeometry(marker.pose, w, h, marker.post)


class _MarkerItem:
    """Vertical board: texture warped by a plane homography from a mip level, plus a post."""

    def __init__(self, marker, gain: float, light: np.ndarray, ambient: float):
        if isinstance(marker, AprilTagMarker):
            board, edge = _tag_board(marker)
            self.geom = _MarkerGeometry(marker.pose, edge, edge, marker.post)
        else:
            board = marker.image
            self.geom = _marker_geometry(marker)
        g = self.geom
        self.anchor = g.centre
        front = gain * float(lambert(g.normal, light, ambient))
        back = gain * float(lambert(-g.normal, light, ambient))
        self.back_colour = tuple(min(255.0, c * back) for c in BOARD_BACK_COLOUR)
        level = cv2.convertScaleAbs(board, alpha=front)
        self.levels = [level]
        while min(level.shape[:2]) >= 16:
            level = cv2.resize(
                level, (level.shape[1] // 2, level.shape[0] // 2), interpolation=cv2.INTER_AREA
            )
            self.levels.append(level)
        self.post = _BoxItem(*g.post, POST_COLOUR, gain, light, ambient) if g.post else None

    def draw(self, image: np.ndarray, view: _View) -> None:
        g = self.geom
        facing = g.normal @ (view.position - g.centre) > 0.0
        if self.post is not None and facing:
            self.post.draw(image, view)
        if facing:
            self._draw_front(image, view)
        else:
            _fill_polygon(image, view.camera, view.to_camera(g.corners), self.back_colour)
        if self.post is not None and not facing:
            self.post.draw(image, view)

    def _draw_front(self, image: np.ndarray, view: _View) -> None:
        _draw_board(image, view, self.geom.corners, self.levels)


def _draw_board(
    image: np.ndarray, view: _View, corners: np.ndarray, levels: list, exact: bool = True
) -> None:
    """A textured flat quad (world corners: top-left, top-right, bottom-right, bottom-left as
    seen from the front) from the finest mip level in `levels` that suits its size. `exact`:
    supersampled, anti-aliased edges (markers); else one sample per pixel and hard edges
    (walls: big, and nothing measures their edges)."""
    cam = view.camera
    p = view.to_camera(corners)
    clipped = clip_polygon_near(p, NEAR_M) if p[:, 2].min() < NEAR_M else p
    if len(clipped) < 3:
        return
    uv = cam.project_camera(clipped)
    u0, v0 = np.floor(uv.min(axis=0)).astype(int) - 1
    u1, v1 = np.ceil(uv.max(axis=0)).astype(int) + 1
    u0, v0 = max(u0, 0), max(v0, 0)
    u1, v1 = min(u1, cam.width - 1), min(v1, cam.height - 1)
    if u0 > u1 or v0 > v1:
        return
    size = (u1 - u0 + 1, v1 - v0 + 1)
    # Supersample small boards so edges get true area coverage (what the detector's
    # sub-pixel edge refinement expects); big ones are sharp enough as they are.
    ss = 4 if size[0] * size[1] <= 40_000 else 2 if size[0] * size[1] <= 160_000 else 1
    ss = ss if exact else 1
    edge_px = np.max(np.hypot(*(uv - np.roll(uv, 1, axis=0)).T)) if len(clipped) == 4 else 1e9
    # Finest level whose texels cover at least one (super)sample: bilinear magnification
    # then puts every black/white edge's 50 % point exactly where the geometry says.
    tex = next((lv for lv in levels if lv.shape[1] <= edge_px * ss), levels[-1])
    rows, cols = tex.shape[:2]
    sx = (corners[1] - corners[0]) / cols  # metres per texel along the board's right
    sy = (corners[3] - corners[0]) / rows  # ... and down
    origin = corners[0] + 0.5 * sx + 0.5 * sy  # centre of texel (0, 0)
    plane = np.column_stack([view.r @ sx, view.r @ sy, view.r @ origin + view.t])
    off = 0.5 / ss - 0.5  # sample (i, j) of the fine grid sits at u0 + (i + 0.5) / ss - 0.5
    fine = np.array([[1.0 / ss, 0.0, u0 + off], [0.0, 1.0 / ss, v0 + off], [0.0, 0.0, 1.0]])
    warped = cv2.warpPerspective(
        tex,
        np.linalg.inv(cam.K @ plane) @ fine,
        (size[0] * ss, size[1] * ss),
        flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
        borderMode=cv2.BORDER_REPLICATE,
    )
    if ss > 1:
        warped = cv2.resize(warped, size, interpolation=cv2.INTER_AREA)
    if warped.ndim == 2:  # tag boards are grey: warping one channel is a third of the work
        warped = cv2.cvtColor(warped, cv2.COLOR_GRAY2BGR)
    mask = np.zeros((size[1], size[0]), np.uint8)
    pts = np.rint((uv - [u0, v0]) * 16).astype(np.int32)
    roi = image[v0 : v1 + 1, u0 : u1 + 1]
    if not exact:
        cv2.fillConvexPoly(mask, pts, 255, cv2.LINE_8, 4)
        cv2.copyTo(warped, mask, roi)
        return
    cv2.fillConvexPoly(mask, pts, 255, cv2.LINE_AA, 4)
    # Blend only the anti-aliased rim; inside, the board's pixels are copied as they are (what
    # the blend gives there too, at a fraction of the cost for a board that fills the view).
    cv2.copyTo(warped, (mask == 255).view(np.uint8), roi)
    rim = (mask > 0) & (mask < 255)
    a = mask[rim].astype(np.float32)[:, None] / 255.0
    roi[rim] = np.rint(roi[rim] * (1.0 - a) + warped[rim] * a)


class _WallItem:
    """A wall along one edge of the floor, seen from inside the room (a realism option)."""

    def __init__(self, a, b, height: float, texture: np.ndarray, gain: float, light, ambient):
        a3, b3 = np.array([*a, 0.0]), np.array([*b, 0.0])
        up = np.array([0.0, 0.0, height])
        # Walking a -> b the room is on the left; facing the wall from inside, b is on the left.
        self.corners = np.array([b3 + up, a3 + up, a3, b3])
        d = b3 - a3
        self.normal = np.array([-d[1], d[0], 0.0]) / np.linalg.norm(d)  # into the room
        shade = gain * float(lambert(self.normal, light, ambient))
        self.levels = [cv2.convertScaleAbs(texture, alpha=shade)]
        self.centre = self.corners.mean(axis=0)

    def draw(self, image: np.ndarray, view: _View) -> None:
        if self.normal @ (view.position - self.centre) > 0.0:
            _draw_board(image, view, self.corners, self.levels, exact=False)


class _Lens:
    """The plumb_bob lens of a camera: a pinhole view, rendered with a margin wide enough for the
    lens's field of view, is remapped into the distorted image. Each distorted pixel takes the
    pinhole pixel its ray passes through (cv2.undistortPoints of the pixel grid: the inverse of
    what cv2.initUndistortRectifyMap gives, which maps rectified pixels to distorted ones)."""

    def __init__(self, camera: Camera):
        w, h = camera.width, camera.height
        grid = np.stack(np.meshgrid(np.arange(w), np.arange(h)), axis=-1).astype(np.float64)
        criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-12)
        pinhole_px = cv2.undistortPointsIter(
            grid.reshape(-1, 1, 2), camera.K, np.array(camera.distortion), None, camera.K, criteria
        ).reshape(h, w, 2)
        low, high = pinhole_px.min(axis=(0, 1)), pinhole_px.max(axis=(0, 1))
        over = max(0.0, -low[0], -low[1], high[0] - (w - 1), high[1] - (h - 1))
        pad = math.ceil(over) + 2  # bilinear needs the neighbour too
        # Same fx, fy and mounting, principal point moved by the margin.
        self.pinhole = replace(
            camera,
            width=w + 2 * pad,
            height=h + 2 * pad,
            hfov=2.0 * math.atan((w / 2.0 + pad) / camera.fx),
            distortion=PINHOLE,
        )
        pinhole_px += pad
        self.maps = cv2.convertMaps(
            pinhole_px[..., 0].astype(np.float32), pinhole_px[..., 1].astype(np.float32),
            cv2.CV_16SC2,
        )  # fmt: skip

    def apply(self, pinhole_image: np.ndarray) -> np.ndarray:
        return cv2.remap(
            pinhole_image, *self.maps, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE
        )


class Renderer:
    """Renders BGR frames of a world from robot poses; deterministic for a given seed."""

    def __init__(
        self,
        world: World,
        camera: Camera | None = None,
        *,
        gain: float | None = None,
        noise_sigma: float | None = None,
        seed: int | None = None,
        realism: Realism | None = None,
        rate_hz: float = 30.0,
        starts: tuple[tuple[float, float], ...] = (),
    ):
        """`realism` (default: the world's) adds its scene and sensor effects; distractors keep
        clear of the world's robot start, `starts` and every object; `rate_hz` times the drift."""
        self.camera = camera or world.camera
        self._lens = _Lens(self.camera) if self.camera.distorted else None
        self._view_camera = self._lens.pinhole if self._lens else self.camera
        lighting = world.lighting
        self.gain = lighting.gain if gain is None else gain
        self.noise_sigma = world.noise.sigma if noise_sigma is None else noise_sigma
        self.seed = world.noise.seed if seed is None else seed
        self.realism = world.realism if realism is None else realism
        self.rate_hz = rate_hz
        if self.realism != Realism():
            starts = (tuple(world.robot.start[:2]), *starts)
            world = with_distractors(world, self.realism, self.seed, list(starts))
        self.world = world
        self.frame = 0  # frame counter keying the noise, so each frame gets fresh noise
        tex, tex_to_world = ground_texture(world, realism=self.realism, seed=self.seed)
        self._ground = cv2.convertScaleAbs(tex, alpha=self.gain)
        self._tex_to_world = tex_to_world
        self._floor = tuple(min(255.0, c * self.gain) for c in world.ground.colour)
        sky = tuple(min(255.0, c * self.gain) for c in world.background)
        self._sky = np.empty((self._view_camera.height, self._view_camera.width, 3), np.uint8)
        self._sky[:] = np.rint(sky).astype(np.uint8)
        self._light = np.array(lighting.direction)
        self._items = [self._item(obj, lighting.ambient) for obj in world.objects]
        self._walls = self._wall_items(world) if self.realism.walls else []
        drifting = self.realism.shadow_bands and self.realism.shadow_drift
        g = world.ground
        self._drifting = (
            DriftingShadows(self.realism, g.origin, g.size, self.seed) if drifting else None
        )
        if self._drifting is not None:  # shadow coverage 0..255 -> 255 * that pixel's gain
            cover = np.arange(256, dtype=np.float32)[:, None] / 255.0
            table = 255.0 * (1.0 - (1.0 - self._drifting.gains) * cover)
            self._shadow_lut = np.rint(table).astype(np.uint8).reshape(1, 256, 3)
        self._sensor = (
            Sensor(self.realism, self.camera.width, self.camera.height, self.seed, rate_hz)
            if self.realism.sensor_active
            else None
        )

    def _wall_items(self, world: World) -> list[_WallItem]:
        g, r = world.ground, self.realism
        x0, y0 = g.origin
        x1, y1 = x0 + g.size[0], y0 + g.size[1]
        ring = [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]
        light, ambient = self._light, world.lighting.ambient
        palette = ((200, 205, 210), (180, 200, 215), (215, 210, 200), (190, 190, 195))
        items = []
        for i, (a, b) in enumerate(zip(ring, ring[1:] + ring[:1], strict=True)):
            length = math.dist(a, b)
            texture = wall_texture(length, r.walls, palette[i], self.seed * 4 + i)
            items.append(_WallItem(a, b, r.walls, texture, self.gain, light, ambient))
        return items

    def _item(self, obj: WorldObject, ambient: float):
        if isinstance(obj, Sphere):
            return _SphereItem(obj, self.gain, ambient)
        if isinstance(obj, Box):
            return _BoxItem(obj.size, obj.pose, obj.colour, self.gain, self._light, ambient)
        return _MarkerItem(obj, self.gain, self._light, ambient)

    def render(
        self,
        pose: Pose,
        frame: int | None = None,
        hidden: frozenset[str] | set[str] = frozenset(),
        motion: tuple[float, float] = (0.0, 0.0),
    ) -> np.ndarray:
        """Return a (height, width, 3) uint8 BGR image seen from robot pose (x, y, yaw).

        Noise (if sigma > 0) is drawn from an RNG keyed by (seed, frame); `frame` defaults
        to an internal counter that advances on every call. Objects named in `hidden` are left
        out (their baked floor shadows stay). `motion` (v, w) is the base's velocity during the
        exposure, for the realism's motion blur.
        """
        cam = self._view_camera
        if frame is None:
            frame, self.frame = self.frame, self.frame + 1
        image = np.empty((cam.height, cam.width, 3), np.uint8)
        first = min(max(math.floor(cam.horizon_row()) + 1, 0), cam.height)
        image[:first] = self._sky[:first]
        if first < cam.height:
            tex_to_image = cam.ground_homography(pose) @ self._tex_to_world
            shift = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, first], [0.0, 0.0, 1.0]])
            cv2.warpPerspective(
                self._ground,
                np.linalg.inv(tex_to_image) @ shift,
                (cam.width, cam.height - first),
                dst=image[first:],
                flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                borderMode=cv2.BORDER_CONSTANT,
                borderValue=self._floor,
            )
        view = _View(cam, pose, self._light)
        if self._drifting is not None and first < cam.height:
            self._draw_drifting_shadows(image, view, frame / self.rate_hz)
        if self._items or self._walls:
            for wall in self._walls:  # inside the room: behind every object
                wall.draw(image, view)
            dist = [float(np.linalg.norm(it.anchor - view.position)) for it in self._items]
            for i in np.argsort(dist)[::-1]:
                if self.world.objects[i].name not in hidden:
                    self._items[i].draw(image, view)
        if self._lens is not None:
            image = self._lens.apply(image)
        if self.noise_sigma > 0.0:
            rng = np.random.default_rng((self.seed, frame))
            codes = np.frombuffer(rng.bytes(image.size * 2), np.uint16).reshape(image.shape)
            noise = gaussian_table()[codes]
            noise *= self.noise_sigma
            image = cv2.add(image, noise, dtype=cv2.CV_8U)  # rounds and saturates
        if self._sensor is not None:
            image = self._sensor.apply(image, frame, self.motion_flow(pose, motion))
        return image

    def _draw_drifting_shadows(self, image: np.ndarray, view: _View, t: float) -> None:
        """Darken (and tint) the floor where the drifting shadow bands lie at time t."""
        mask = np.zeros(image.shape[:2], np.uint8)
        for quad in self._drifting.quads(t):
            corners = view.to_camera(np.column_stack([quad, np.zeros(len(quad))]))
            _fill_polygon(mask, view.camera, corners, 255)
        x, y, w, h = cv2.boundingRect(mask)
        if not w:
            return
        roi = np.s_[y : y + h, x : x + w]
        factor = cv2.LUT(cv2.merge([mask[roi]] * 3), self._shadow_lut)  # 255 * gain, per channel
        image[roi] = cv2.multiply(image[roi], factor, scale=1.0 / 255.0)

    def _lens_pixels(self, pinhole_px: np.ndarray) -> np.ndarray:
        """Pinhole pixels where the camera's lens puts them."""
        pixels = np.asarray(pinhole_px, dtype=float).reshape(-1, 2)
        return self.camera.distort_pixels(pixels) if self._lens else pixels

    def motion_flow(self, pose: Pose, motion: tuple[float, float]) -> tuple[float, float]:
        """Image motion (du, dv) px over the exposure of the floor point seen at the centre of
        the row at 3/4 height (the followers' band), for velocity `motion` = (v, w)."""
        exposure = self.realism.exposure_time
        if not exposure or motion == (0.0, 0.0):
            return 0.0, 0.0
        cam = self.camera
        pixel = np.array([[cam.cx, 0.75 * cam.height]])
        point = cam.pixel_to_ground(pixel, pose)
        if not np.isfinite(point).all():
            return 0.0, 0.0
        opened = integrate_unicycle(pose, -motion[0], -motion[1], exposure)
        uv, depth = cam.project(np.array([[*point[0], 0.0]]), opened)
        if depth[0] <= 0.0:
            return 0.0, 0.0
        du, dv = (pixel - uv)[0]
        return float(du), float(dv)

    def object_projections(self, pose: Pose) -> list[dict]:
        """Ground truth per object: projected centre, depth, and shape-specific extras.

        Spheres add `blob_centre_px`, the centre of the exact silhouette ellipse (what a
        colour-blob centroid measures); markers add `corners_px` of the tag's black square
        (or the picture) in the order top-left, top-right, bottom-right, bottom-left as
        seen from the front.
        """
        cam = self.camera
        view = _View(cam, pose, self._light)
        out = []
        for obj, item in zip(self.world.objects, self._items, strict=False):
            c = view.to_camera(item.anchor)
            uv = self._lens_pixels(cam.project_camera(c))[0] if c[2] > 0.0 else np.full(2, np.nan)
            in_view = bool(c[2] > 0.0 and 0 <= uv[0] < cam.width and 0 <= uv[1] < cam.height)
            entry = {
                "name": obj.name,
                "kind": type(obj).__name__,
                "centre_px": uv.tolist(),
                "depth": float(c[2]),
                "in_view": in_view,
            }
            if isinstance(item, _SphereItem):
                conic = item.silhouette(view)
                centre = None if conic is None else np.linalg.solve(conic[:2, :2], -conic[:2, 2])
                centre = None if centre is None else self._lens_pixels(centre)[0]
                entry["blob_centre_px"] = None if centre is None else centre.tolist()
            elif isinstance(item, _MarkerItem):
                corners = item.geom.corners
                if isinstance(obj, AprilTagMarker):
                    corners = item.geom.centre + (corners - item.geom.centre) * (
                        obj.size / np.linalg.norm(corners[1] - corners[0])
                    )
                pix, depth = cam.project(corners, pose)
                pix = self._lens_pixels(pix)
                entry["corners_px"] = pix.tolist() if np.all(depth > 0.0) else None
            out.append(entry)
        return out


def bench_render(world: World, n: int = 300) -> float:
    """Frames per second over n frames along a short drive from the start pose, one thread."""
    renderer = Renderer(world, noise_sigma=0.0)
    x, y, yaw = world.robot.start
    step = 0.002  # metres per frame, with a slow turn, so the view keeps changing
    poses = [
        (x + step * i * math.cos(yaw), y + step * i * math.sin(yaw), yaw + 0.001 * i)
        for i in range(n)
    ]
    threads = cv2.getNumThreads()
    cv2.setNumThreads(1)
    try:
        renderer.render(poses[0])
        start = time.perf_counter()
        for pose in poses:
            renderer.render(pose)
        elapsed = time.perf_counter() - start
    finally:
        cv2.setNumThreads(threads)
    return n / elapsed
