"""Pinhole camera on a REP-103 robot base, looking forward and pitched down.

Conventions used everywhere in the harness:
- world / base frames: x forward, y left, z up (REP-103); a robot pose is (x, y, yaw).
- optical frame: x right, y down, z forward (REP-103 ``_optical`` frames).
- pixels: (u, v) = (column, row) with pixel centres at integer coordinates, the OpenCV and
  ROS CameraInfo convention; the principal point is cx = width / 2, cy = height / 2.
- fx = fy = (width / 2) / tan(hfov / 2); an optional plumb_bob lens (k1, k2, p1, p2, k3), the
  model of ROS CameraInfo and OpenCV, distorts the pinhole image (the renderer draws a pinhole
  view and remaps it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from harness.geometry import rot_z

FRAME_ID = "camera_rgb_optical_frame"
DEFAULT_HFOV = math.radians(60.0)  # Kinect-like horizontal field of view
PINHOLE = (0.0, 0.0, 0.0, 0.0, 0.0)
# The default mounting is the behaviours' own (core.CameraGeometry, from follow_bot_common's
# cfg/Camera.cfg), so a world that leaves it out is seen by the nodes as they would assume it.
# Written as numbers so the simulator runs without the compiled core (an install of the harness
# alone); harness/test/test_camera.py holds them equal to the core's.
DEFAULT_HEIGHT_M = 0.30
DEFAULT_PITCH = math.radians(20.0)
DEFAULT_X_OFFSET_M = 0.0
# Named plumb_bob lenses (k1, k2, p1, p2, k3). turtlebot3: the visible barrel distortion of a
# cheap wide-angle board camera like a TurtleBot3's (straight lines bow ~12 px at the edges).
LENSES = {"pinhole": PINHOLE, "turtlebot3": (-0.28, 0.07, 0.0, 0.0, 0.0)}


@dataclass(frozen=True)
class Camera:
    """Camera intrinsics plus its mounting on the robot base (pose-independent data)."""

    width: int = 640
    height: int = 480
    hfov: float = DEFAULT_HFOV
    height_m: float = DEFAULT_HEIGHT_M
    pitch: float = DEFAULT_PITCH  # radians, positive tilts the axis down
    x_offset_m: float = DEFAULT_X_OFFSET_M  # forward of the base origin
    # Where the camera really sits off the mounting above, which is all the robot description
    # (and so the node under test) knows: a mounting error (scenario perturbation).
    y_offset_error_m: float = 0.0  # optical centre this far left of where it is said to be
    yaw_error: float = 0.0  # radians, optical axis turned this far left (about the base z)
    frame_id: str = FRAME_ID
    distortion: tuple[float, float, float, float, float] = PINHOLE  # plumb_bob k1 k2 p1 p2 k3

    @property
    def fx(self) -> float:
        return (self.width / 2.0) / math.tan(self.hfov / 2.0)

    @property
    def fy(self) -> float:
        return self.fx

    @property
    def cx(self) -> float:
        return self.width / 2.0

    @property
    def cy(self) -> float:
        return self.height / 2.0

    @property
    def K(self) -> np.ndarray:  # noqa: N802 - the conventional name of the intrinsic matrix
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])

    def camera_info_dict(self) -> dict:
        """Fields of a sensor_msgs/CameraInfo, as plain lists, for the ROS node to copy."""
        k = self.K
        p = np.hstack([k, np.zeros((3, 1))])
        return {
            "width": self.width,
            "height": self.height,
            "distortion_model": "plumb_bob",
            "D": [float(d) for d in self.distortion],
            "K": k.ravel().tolist(),
            "R": np.eye(3).ravel().tolist(),
            "P": p.ravel().tolist(),
            "frame_id": self.frame_id,
        }

    @property
    def distorted(self) -> bool:
        return any(self.distortion)

    def distort_pixels(self, pixels: np.ndarray) -> np.ndarray:
        """Pinhole pixels (Nx2) moved by the plumb_bob lens, as cv2.projectPoints does."""
        k1, k2, p1, p2, k3 = self.distortion
        x = (np.asarray(pixels, dtype=float).reshape(-1, 2) - [self.cx, self.cy]) / [
            self.fx,
            self.fy,
        ]
        r2 = (x**2).sum(axis=1)
        radial = 1.0 + k1 * r2 + k2 * r2**2 + k3 * r2**3
        xd = x[:, 0] * radial + 2 * p1 * x[:, 0] * x[:, 1] + p2 * (r2 + 2 * x[:, 0] ** 2)
        yd = x[:, 1] * radial + p1 * (r2 + 2 * x[:, 1] ** 2) + 2 * p2 * x[:, 0] * x[:, 1]
        return np.column_stack([self.fx * xd + self.cx, self.fy * yd + self.cy])

    def base_to_optical(self) -> np.ndarray:
        """Rotation whose columns are the optical x, y, z axes expressed in the base frame."""
        cp, sp = math.cos(self.pitch), math.sin(self.pitch)
        z_axis = np.array([cp, 0.0, -sp])  # forward, tilted down by the pitch
        x_axis = np.array([0.0, -1.0, 0.0])  # image right = robot right
        y_axis = np.cross(z_axis, x_axis)  # image down
        return np.column_stack([x_axis, y_axis, z_axis])

    def camera_in_world(self, pose: tuple[float, float, float]) -> tuple[np.ndarray, np.ndarray]:
        """(R_world_optical, camera position in world) for a robot pose (x, y, yaw)."""
        x, y, yaw = pose
        r_wb = rot_z(yaw)
        offset = np.array([self.x_offset_m, self.y_offset_error_m, self.height_m])
        position = np.array([x, y, 0.0]) + r_wb @ offset
        return r_wb @ rot_z(self.yaw_error) @ self.base_to_optical(), position

    def world_to_camera(self, pose: tuple[float, float, float]) -> tuple[np.ndarray, np.ndarray]:
        """(R, t) such that p_optical = R @ p_world + t."""
        r_wc, position = self.camera_in_world(pose)
        r_cw = r_wc.T
        return r_cw, -r_cw @ position

    def marker_pose(
        self, pose: tuple[float, float, float], marker_pose: tuple[float, float, float, float]
    ) -> tuple[np.ndarray, np.ndarray]:
        """(R, t) of a marker's frame in the optical frame, as a marker detector reports it.

        The marker frame has x right, y down, z into the board (seen from the front); the marker
        has world pose (x, y, z, yaw), yaw being the direction its front faces.
        """
        x, y, z, yaw = marker_pose
        r, t = self.world_to_camera(pose)
        right = [-math.sin(yaw), math.cos(yaw), 0.0]
        axes = np.column_stack([right, [0.0, 0.0, -1.0], [-math.cos(yaw), -math.sin(yaw), 0.0]])
        return r @ axes, r @ np.array([x, y, z]) + t

    def to_camera(self, points_world: np.ndarray, pose: tuple[float, float, float]) -> np.ndarray:
        """Transform Nx3 world points into the optical frame."""
        r, t = self.world_to_camera(pose)
        return np.asarray(points_world, dtype=float).reshape(-1, 3) @ r.T + t

    def project_camera(self, points_cam: np.ndarray) -> np.ndarray:
        """Pixel coordinates (Nx2) of optical-frame points; only meaningful for z > 0."""
        p = np.asarray(points_cam, dtype=float).reshape(-1, 3)
        z = p[:, 2]
        return np.column_stack([self.fx * p[:, 0] / z + self.cx, self.fy * p[:, 1] / z + self.cy])

    def project(
        self, points_world: np.ndarray, pose: tuple[float, float, float]
    ) -> tuple[np.ndarray, np.ndarray]:
        """(pixels Nx2, depth N) of world points; depth <= 0 means behind the camera."""
        p = self.to_camera(points_world, pose)
        with np.errstate(divide="ignore", invalid="ignore"):
            return self.project_camera(p), p[:, 2]

    def horizon_row(self) -> float:
        """Image row (v) of the horizon of a flat floor; rows below it (larger v) see floor."""
        return self.cy - self.fy * math.tan(self.pitch)

    def ground_homography(self, pose: tuple[float, float, float]) -> np.ndarray:
        """3x3 H mapping floor points (x, y, 1) in world metres to homogeneous pixels."""
        r, t = self.world_to_camera(pose)
        return self.K @ np.column_stack([r[:, 0], r[:, 1], t])

    def pixel_to_ground(self, pixels: np.ndarray, pose: tuple[float, float, float]) -> np.ndarray:
        """World floor points (Nx2) seen at pixels (Nx2); NaN for pixels above the horizon."""
        h_inv = np.linalg.inv(self.ground_homography(pose))
        uv = np.asarray(pixels, dtype=float).reshape(-1, 2)
        g = np.column_stack([uv, np.ones(len(uv))]) @ h_inv.T
        r_wc, _ = self.camera_in_world(pose)
        rays = np.column_stack([(uv - [self.cx, self.cy]) / [self.fx, self.fy], np.ones(len(uv))])
        below = (rays @ r_wc.T)[:, 2] < 0.0
        xy = g[:, :2] / g[:, 2:3]
        xy[~below] = np.nan
        return xy
