"""Fast software renderer: floor by plane homography, then objects far to near.

Everything that does not depend on the robot pose (floor texture with lines and baked
shadows, face shading, tag bitmaps and their mip levels) is prepared once in the
constructor, so a frame costs one cv2.warpPerspective for the floor plus a few small
per-object draws.
"""

from __future__ import annotations

import math
import time

import cv2
import numpy as np

from harness.camera import Camera
from harness.distractors import with_distractors
from harness.ground import ground_texture
from harness.realism import Realism
from harness.render_items import (
    BoxItem,
    Lens,
    MarkerItem,
    Pose,
    SphereItem,
    View,
    WallItem,
    fill_polygon,
)
from harness.robot import integrate_unicycle
from harness.sensor import Sensor, gaussian_table
from harness.textures import (
    DriftingShadows,
    wall_texture,
)
from harness.world import AprilTagMarker, Box, Sphere, World, WorldObject


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
        self._lens = Lens(self.camera) if self.camera.distorted else None
        self._view_camera = self._lens.pinhole if self._lens else self.camera
        lighting = world.lighting
        self.gain = lighting.gain if gain is None else gain
        self.noise_sigma = world.noise.sigma if noise_sigma is None else noise_sigma
        self.seed = world.noise.seed if seed is None else seed
        self.realism = world.realism if realism is None else realism
        self.rate_hz = rate_hz
        if self.realism != Realism():
            starts = ((world.robot.start[0], world.robot.start[1]), *starts)
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

    def _wall_items(self, world: World) -> list[WallItem]:
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
            items.append(WallItem(a, b, r.walls, texture, self.gain, light, ambient))
        return items

    def _item(self, obj: WorldObject, ambient: float):
        if isinstance(obj, Sphere):
            return SphereItem(obj, self.gain, ambient)
        if isinstance(obj, Box):
            return BoxItem(obj.size, obj.pose, obj.colour, self.gain, self._light, ambient)
        return MarkerItem(obj, self.gain, self._light, ambient)

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
        view = View(cam, pose, self._light)
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

    def _draw_drifting_shadows(self, image: np.ndarray, view: View, t: float) -> None:
        """Darken (and tint) the floor where the drifting shadow bands lie at time t."""
        assert self._drifting is not None  # called only when shadows drift
        mask = np.zeros(image.shape[:2], np.uint8)
        for quad in self._drifting.quads(t):
            corners = view.to_camera(np.column_stack([quad, np.zeros(len(quad))]))
            fill_polygon(mask, view.camera, corners, 255)
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
        view = View(cam, pose, self._light)
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
            if isinstance(item, SphereItem):
                conic = item.silhouette(view)
                centre = None if conic is None else np.linalg.solve(conic[:2, :2], -conic[:2, 2])
                centre = None if centre is None else self._lens_pixels(centre)[0]
                entry["blob_centre_px"] = None if centre is None else centre.tolist()
            elif isinstance(item, MarkerItem):
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
