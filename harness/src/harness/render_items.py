"""What the renderer draws over the floor, each prepared once per world: boxes, spheres, tag and
texture boards on posts, walls, and the barrel lens the frame is remapped through.
"""

from __future__ import annotations

import math
from dataclasses import replace

import cv2
import numpy as np

from harness.apriltag_image import family_geometry, tag_image
from harness.camera import PINHOLE, Camera
from harness.geometry import clip_polygon_near, rot_z
from harness.world import AprilTagMarker, Sphere, TextureMarker

Pose = tuple[float, float, float]


def lambert(normal: np.ndarray, light: np.ndarray, ambient: float) -> np.ndarray:
    """Brightness factor in [ambient, 1]: a surface facing the light shows its full colour."""
    return ambient + (1.0 - ambient) * np.maximum(0.0, normal @ light)


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


class View:
    """Per-frame camera data shared by all object draws."""

    def __init__(self, camera: Camera, pose: Pose, light_world: np.ndarray):
        self.camera = camera
        self.r, self.t = camera.world_to_camera(pose)
        self.position = -self.r.T @ self.t
        self.light = self.r @ light_world

    def to_camera(self, points: np.ndarray) -> np.ndarray:
        return points @ self.r.T + self.t


def fill_polygon(image: np.ndarray, camera: Camera, poly_cam: np.ndarray, colour) -> None:
    """Fill a convex optical-frame polygon, clipped at the near plane, at 1/16 px precision."""
    if poly_cam[:, 2].min() < NEAR_M:
        poly_cam = clip_polygon_near(poly_cam, NEAR_M)
        if len(poly_cam) < 3:
            return
    uv = camera.project_camera(poly_cam)
    cv2.fillConvexPoly(image, np.rint(uv * 16).astype(np.int32), colour, cv2.LINE_AA, 4)


def box_corners(size, pose) -> np.ndarray:
    length, width, height = size
    x, y, yaw = pose
    local = _BOX_SIGNS * [length / 2.0, width / 2.0, height]
    return local @ rot_z(yaw).T + [x, y, 0.0]


class BoxItem:
    """Box on the floor: back-face culled, per-face Lambert colour precomputed."""

    def __init__(self, size, pose, colour, gain: float, light: np.ndarray, ambient: float):
        self.corners = box_corners(size, pose)
        self.anchor = np.array([pose[0], pose[1], size[2] / 2.0])
        rot = rot_z(pose[2])
        self.faces = []
        for idx, n in _BOX_FACES:
            normal = rot @ np.array(n)
            shade = gain * float(lambert(normal, light, ambient))
            col = tuple(min(255.0, c * shade) for c in colour)
            self.faces.append((list(idx), normal, self.corners[list(idx)].mean(axis=0), col))

    def draw(self, image: np.ndarray, view: View) -> None:
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
                fill_polygon(image, view.camera, cam[idx], col)


class SphereItem:
    """Sphere ray-cast inside the bounding box of its exact (elliptic) silhouette."""

    def __init__(self, sphere: Sphere, gain: float, ambient: float):
        self.centre = np.array(sphere.position, dtype=float)
        self.anchor = self.centre
        self.radius = sphere.radius
        self.colour = np.array(sphere.colour, np.float32) * gain
        self.ambient = ambient

    def silhouette(self, view: View) -> np.ndarray | None:
        """3x3 conic C of the silhouette (p^T C p > 0 inside), or None if not an ellipse."""
        c = view.to_camera(self.centre)
        k = c @ c - self.radius**2
        if k <= 0.0 or c[2] * math.sqrt(k) <= math.hypot(c[0], c[1]) * self.radius:
            return None
        k_inv = np.linalg.inv(view.camera.K)
        return k_inv.T @ (np.outer(c, c) - k * np.eye(3)) @ k_inv

    def draw(self, image: np.ndarray, view: View) -> None:
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
    board = cv2.copyMakeBorder(
        square, margin_px, margin_px, margin_px, margin_px, cv2.BORDER_CONSTANT, value=(255,)
    )
    return board, board.shape[1] / px_per_m


def marker_geometry(marker: AprilTagMarker | TextureMarker) -> _MarkerGeometry:
    w, h = marker.board_size
    return _MarkerGeometry(marker.pose, w, h, marker.post)


class MarkerItem:
    """Vertical board: texture warped by a plane homography from a mip level, plus a post."""

    def __init__(self, marker, gain: float, light: np.ndarray, ambient: float):
        if isinstance(marker, AprilTagMarker):
            board, edge = _tag_board(marker)
            self.geom = _MarkerGeometry(marker.pose, edge, edge, marker.post)
        else:
            board = marker.image
            self.geom = marker_geometry(marker)
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
        self.post = BoxItem(*g.post, POST_COLOUR, gain, light, ambient) if g.post else None

    def draw(self, image: np.ndarray, view: View) -> None:
        g = self.geom
        facing = g.normal @ (view.position - g.centre) > 0.0
        if self.post is not None and facing:
            self.post.draw(image, view)
        if facing:
            self._draw_front(image, view)
        else:
            fill_polygon(image, view.camera, view.to_camera(g.corners), self.back_colour)
        if self.post is not None and not facing:
            self.post.draw(image, view)

    def _draw_front(self, image: np.ndarray, view: View) -> None:
        _draw_board(image, view, self.geom.corners, self.levels)


def _draw_board(
    image: np.ndarray, view: View, corners: np.ndarray, levels: list, exact: bool = True
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


class WallItem:
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

    def draw(self, image: np.ndarray, view: View) -> None:
        if self.normal @ (view.position - self.centre) > 0.0:
            _draw_board(image, view, self.corners, self.levels, exact=False)


class Lens:
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
        map1, map2 = self.maps
        return cv2.remap(
            pinhole_image, map1, map2, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE
        )
