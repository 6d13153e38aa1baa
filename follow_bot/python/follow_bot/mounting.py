"""Where a lab node's camera is mounted: from tf (the robot description) or from the mounting
~params, by the rules of the C++ behaviours' CameraMountingSource
(follow_bot_common/ros/camera_mounting_source.h), so a Python node on a robot sees its camera
where the C++ nodes do.

~params (declared, with their defaults, in follow_bot_common/cfg/Camera.cfg): ~camera_mounting
(tf: ~base_frame <- the frame's header.frame_id, looked up for every frame; params: the three
camera_* ones), ~base_frame, ~mounting_timeout (wall time the first frames wait for tf, the node
holding still, before the camera_* ~params are used; a transform that comes later still replaces
them), ~camera_height, ~camera_pitch_deg, ~camera_x_offset.
"""

import math
import time

import rospy
import tf2_ros

from follow_bot import core
from follow_bot.lab import fatal

FOOTPRINT_FRAME = "base_footprint"
DEFAULTS = core.CAMERA_DEFAULTS  # follow_bot_common/cfg/Camera.cfg's
MOUNTING = core.CameraGeometry()  # the camera_* ~params' defaults
HELP = {
    "camera_mounting": f"tf (the robot description) or params (the three below) "
    f"({DEFAULTS['camera_mounting']})",
    "base_frame": f"robot frame the camera is looked up in ({DEFAULTS['base_frame']})",
    "mounting_timeout": f"s the first frames wait for tf, then the ~params "
    f"({DEFAULTS['mounting_timeout']:g})",
    "camera_height": f"optical centre above the floor, m ({MOUNTING.height_m:g})",
    "camera_pitch_deg": f"camera pitch, deg, down positive ({math.degrees(MOUNTING.pitch_rad):g})",
    "camera_x_offset": f"optical centre forward of the base frame, m ({MOUNTING.x_offset_m:g})",
}


def with_mounting(camera, mounting):
    """`camera`'s intrinsics with `mounting`'s height, pitch and forward offset."""
    return core.CameraGeometry(
        fx=camera.fx, fy=camera.fy, cx=camera.cx, cy=camera.cy, height_m=mounting.height_m,
        pitch_rad=mounting.pitch_rad, x_offset_m=mounting.x_offset_m,
    )  # fmt: skip


class CameraMounting:
    """The mounting ~params read once; update() gives each frame's camera. See the module doc."""

    def __init__(self):
        self.name = rospy.get_name()
        pitch_deg = rospy.get_param("~camera_pitch_deg", math.degrees(MOUNTING.pitch_rad))
        try:
            self.fallback = core.CameraGeometry(
                height_m=rospy.get_param("~camera_height", MOUNTING.height_m),
                pitch_rad=math.radians(pitch_deg),
                x_offset_m=rospy.get_param("~camera_x_offset", MOUNTING.x_offset_m),
            )
        except (ValueError, TypeError) as error:
            names = "~camera_height, ~camera_pitch_deg, ~camera_x_offset"
            fatal(f"invalid parameter ({names}): {error}")
        source = rospy.get_param("~camera_mounting", DEFAULTS["camera_mounting"])
        if source not in ("tf", "params"):
            fatal(f"~camera_mounting must be 'tf' or 'params', got {source!r}")
        self.use_tf = source == "tf"
        self.base_frame = rospy.get_param("~base_frame", DEFAULTS["base_frame"])
        if not isinstance(self.base_frame, str) or not self.base_frame:
            fatal(f"~base_frame must be a frame name, got {self.base_frame!r}")
        self.timeout_s = rospy.get_param("~mounting_timeout", DEFAULTS["mounting_timeout"])
        if not (isinstance(self.timeout_s, int | float) and self.timeout_s > 0):
            fatal(f"~mounting_timeout must be > 0, got {self.timeout_s!r}")
        self.mounting = None  # the one in use, once known
        self.from_tf = False
        self.waiting_since = None
        if self.use_tf:
            self.buffer = tf2_ros.Buffer()
            self.listener = tf2_ros.TransformListener(self.buffer)

    def update(self, frame_id, camera):
        """`camera` (its intrinsics) with the mounting for a frame from `frame_id`, or None while
        waiting for tf (the node holds still, in state core.WAITING_FOR_MOUNTING)."""
        if not self.use_tf:
            return self._use(self.fallback, "~params (~camera_mounting params)", camera)
        try:
            mounted = self._from_tf(frame_id, camera)
        except (tf2_ros.TransformException, LookupError) as why:
            return self._without_tf(frame_id, str(why), camera)
        self.from_tf = True
        return self._use(mounted, f"tf ({self.base_frame} <- {frame_id})", camera)

    def _without_tf(self, frame_id, why, camera):
        if self.from_tf:  # known from tf before: kept, the description may be restarting
            rospy.logwarn_throttle(
                5.0, f"{self.name}: keeping the last camera mounting from tf: {why}"
            )
            return with_mounting(camera, self.mounting)
        if self.mounting is not None:  # fell back to the ~params; tf still replaces them
            return with_mounting(camera, self.mounting)
        now = time.monotonic()
        self.waiting_since = self.waiting_since or now
        if now - self.waiting_since < self.timeout_s:
            rospy.logwarn_throttle(2.0, (
                f"{self.name}: waiting for the camera mounting: no transform {self.base_frame} <- "
                f"'{frame_id}' in tf yet ({why}); holding still; the mounting ~params are used "
                f"after ~mounting_timeout {self.timeout_s:g} s"))  # fmt: skip
            return None
        rospy.logwarn(
            f"{self.name}: no camera mounting from tf ({self.base_frame} <- '{frame_id}') within "
            f"~mounting_timeout {self.timeout_s:g} s: falling back to the mounting ~params: "
            f"{core.describe_mounting(self.fallback)}")  # fmt: skip
        return self._use(self.fallback, "~params (tf fallback)", camera)

    def _from_tf(self, frame_id, camera):
        if not frame_id:
            raise LookupError("the image has no header.frame_id")
        latest = rospy.Time(0)
        transform = self.buffer.lookup_transform(self.base_frame, frame_id, latest).transform
        base_height = 0.0
        if self.base_frame != FOOTPRINT_FRAME and self.buffer._frameExists(FOOTPRINT_FRAME):
            base = self.buffer.lookup_transform(FOOTPRINT_FRAME, self.base_frame, latest)
            base_height = base.transform.translation.z
        t, q = transform.translation, transform.rotation
        try:
            mounted, warning = core.mounting_from_transform(
                (t.x, t.y, t.z), (q.x, q.y, q.z, q.w), base_height, camera
            )
        except ValueError as error:
            rospy.logerr_throttle(5.0, (
                f"{self.name}: cannot use the camera mounting from tf ({self.base_frame} <- "
                f"'{frame_id}'): {error}"))  # fmt: skip
            raise LookupError(str(error)) from None
        if warning:
            rospy.logwarn_once(f"{self.name}: camera mounting: {warning}")
        return mounted

    def _use(self, mounting, source, camera):
        if self.mounting is None or not core.same_mounting(mounting, self.mounting):
            rospy.loginfo(
                f"{self.name}: camera mounting from {source}: {core.describe_mounting(mounting)}"
            )
        self.mounting = mounting
        return with_mounting(camera, mounting)
