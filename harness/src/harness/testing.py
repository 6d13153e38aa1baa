"""The fixtures of the tests in tests/, in one module: the source tree they read (REPO); the
camera nodes under test and their parameters (NODES), the harness camera, message builders, and
probe frames with the answer each must get; a ROS client stepping a behaviour in lockstep on its
~status (Lockstep); textured scenes for stitching.
"""

from __future__ import annotations

import math
import threading
import time
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path

import cv2
import numpy as np

from follow_bot import core
from follow_bot.cfg import BeaconChaserConfig
from harness.apriltag_image import tag_image
from harness.render import Renderer
from harness.world import package_dir
from harness.world_file import parse_world

# The source tree the tests run from and read (this file is harness/src/harness/testing.py in it).
REPO = Path(__file__).resolve().parents[3]
SIGN_IMAGE = package_dir("follow_bot") / "assets" / "parking_sign.png"
SIGN_WIDTH_M = 0.40
TAG_SIZE_M = 0.30
# The shared limits' defaults (follow_bot_common/cfg/CommandOutput.cfg: ~limit_linear,
# ~limit_angular), as the core's limiter takes them.
LIMIT_LINEAR = core.VelocityLimiterConfig().max_linear
LIMIT_ANGULAR = core.VelocityLimiterConfig().max_angular
# The harness camera: 640x480, 60 deg horizontal field of view.
WIDTH, HEIGHT = 640, 480
FX = 554.2562584220408
# The beacon nodes' balls (BeaconChaser.cfg ~ball_radius; the approach node's sphere target is
# given the same ~target_size): the size gate takes only a blob a ball of this radius resting on
# the floor would make. The probe's ball stands this far straight ahead, wholly in view.
BALL_RADIUS_M = BeaconChaserConfig.defaults["ball_radius"]
PROBE_BALL_DISTANCE_M = 3.0


@dataclass(frozen=True)
class NodeSpec:
    """How to start one node under test and what its answer to a valid frame must be."""

    package: str
    executable: str
    params: dict = field(default_factory=dict)
    probe: str = "twist"  # which valid frame and answer check (see Probe)
    capturing: bool = False  # panorama: keep a capture running through the storm
    # Reads camera_info (every behaviour; image_converter does not): frames of a shape it does
    # not describe are dropped, and its counts are in "<node>: behaviour", not "<node>: frames".
    behaviour: bool = True

    def rosrun_args(self, *extra: str) -> list[str]:
        """`rosrun`'s arguments for this node: package, executable, `extra`, then its ~params."""
        return [
            self.package,
            self.executable,
            *extra,
            *(f"_{k}:={v}" for k, v in self.params.items()),
        ]


# Nodes run without a robot description: each behaviour takes its camera's mounting from its
# ~params rather than waiting for tf (follow_bot_common/README.md).
PARAMS_MOUNTING = {"camera_mounting": "params"}


NODES: dict[str, NodeSpec] = {
    "image_converter": NodeSpec(
        "image_converter", "image_converter", probe="overlay", behaviour=False
    ),
    "follower": NodeSpec("follow_bot", "follower", PARAMS_MOUNTING, probe="line"),
    "beacon_follow": NodeSpec("follow_bot", "beacon_chaser", PARAMS_MOUNTING, probe="green"),
    "beacon_approach": NodeSpec(
        "follow_bot",
        "beacon_chaser",
        {
            **PARAMS_MOUNTING,
            "mode": "approach",
            "target_shape": "sphere",
            "target_size": BALL_RADIUS_M,
        },
        probe="green",
    ),
    "parker_tag": NodeSpec("follow_bot", "parker", PARAMS_MOUNTING, probe="tag"),
    "parker_sign": NodeSpec(
        "follow_bot",
        "parker",
        {
            **PARAMS_MOUNTING,
            "target": "sign",
            "sign_image": str(SIGN_IMAGE),
            "sign_width": SIGN_WIDTH_M,
        },
        probe="sign",
    ),
    "panorama_idle": NodeSpec("follow_bot", "panorama", PARAMS_MOUNTING, probe="idle"),
    "panorama_capturing": NodeSpec(
        "follow_bot",
        "panorama",
        {**PARAMS_MOUNTING, "capture_timeout": 3600.0},
        probe="turning",
        capturing=True,
    ),
}


def image_msg(width, height, encoding, step, data, stamp=(0, 0), big_endian=0):
    from sensor_msgs.msg import Image

    msg = Image()
    msg.header.stamp.secs, msg.header.stamp.nsecs = stamp
    msg.header.frame_id = "camera_rgb_optical_frame"
    msg.width, msg.height, msg.encoding, msg.step = width, height, encoding, step
    msg.is_bigendian = big_endian
    msg.data = bytes(data)
    return msg


def bgr_msg(bgr: np.ndarray, stamp=(0, 0)):
    h, w = bgr.shape[:2]
    return image_msg(w, h, "bgr8", w * 3, np.ascontiguousarray(bgr).tobytes(), stamp)


def pinhole_info(fx=FX, fy=FX, cx=WIDTH / 2, cy=HEIGHT / 2, width=WIDTH, height=HEIGHT):
    """The CameraInfo of a distortion-free camera."""
    from follow_bot_msgs.ros_image import camera_info_msg

    return camera_info_msg(width, height, [fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0])


def odom_msg(yaw=0.0):
    from nav_msgs.msg import Odometry

    odom = Odometry()
    odom.pose.pose.orientation.z = math.sin(yaw / 2)
    odom.pose.pose.orientation.w = math.cos(yaw / 2)
    return odom


def compressed_msg(msg):
    """A bgr8 Image as the `compressed` image_transport sends it, PNG-coded (lossless, so the
    probes' exact answers still hold)."""
    from sensor_msgs.msg import CompressedImage

    from follow_bot_msgs.ros_image import msg_to_bgr

    out = CompressedImage()
    out.header = msg.header
    out.format = "bgr8; png compressed bgr8"
    out.data = cv2.imencode(".png", msg_to_bgr(msg))[1].tobytes()
    return out


def floor(colour=(120, 120, 120)) -> np.ndarray:
    return np.full((HEIGHT, WIDTH, 3), colour, np.uint8)


@cache
def ball_frame() -> np.ndarray:
    """A green ball of the beacon nodes' radius on the floor straight ahead (its centroid in the
    middle column), rendered for the camera as the nodes are mounted: PARAMS_MOUNTING without
    ~camera_height or ~camera_pitch_deg, so the core's default mounting."""
    mounting = core.CameraGeometry()
    world = parse_world({
        "name": "probe_ball",
        "ground": {"size": [8.0, 8.0], "metres_per_pixel": 0.01},
        "objects": [{
            "kind": "sphere", "name": "green", "colour": [0, 200, 0], "radius": BALL_RADIUS_M,
            "position": [PROBE_BALL_DISTANCE_M, 0.0, BALL_RADIUS_M],
        }],
        "lighting": {"shadows": False},
        "camera": {
            "width": WIDTH, "height": HEIGHT, "height_m": mounting.height_m,
            "pitch_deg": math.degrees(mounting.pitch_rad), "x_offset_m": mounting.x_offset_m,
        },
    })  # fmt: skip
    image = Renderer(world).render((0.0, 0.0, 0.0), frame=0)
    image.flags.writeable = False
    return image


def probe_frame(probe: str):
    """The valid frame whose answer proves a node still works."""
    image = floor()
    if probe == "line":
        image[:, WIDTH // 2 - 8 : WIDTH // 2 + 8] = (0, 220, 255)
    elif probe == "green":
        image = ball_frame()
    elif probe == "tag":
        image = floor((255, 255, 255))
        tag = tag_image()  # 10x10 cells, 8 of them the black square
        cell = 12
        big = cv2.resize(tag, None, fx=cell, fy=cell, interpolation=cv2.INTER_NEAREST)
        y0, x0 = (HEIGHT - big.shape[0]) // 2, (WIDTH - big.shape[1]) // 2
        image[y0 : y0 + big.shape[0], x0 : x0 + big.shape[1]] = big[:, :, None]
    elif probe == "sign":
        sign = cv2.imread(str(SIGN_IMAGE))
        sign = cv2.resize(sign, (240, 200), interpolation=cv2.INTER_AREA)
        y0, x0 = (HEIGHT - 200) // 2, (WIDTH - 240) // 2
        image[y0 : y0 + 200, x0 : x0 + 240] = sign
    elif probe == "overlay":
        image = np.full((64, 64, 3), 90, np.uint8)
    # Stamped now to the nanosecond, as a camera does: limiters ramp by the time between stamps
    # (a capturing panorama stopped by the watchdog turns again only as its stamps advance).
    now = time.time_ns()
    return bgr_msg(image, (now // 10**9, now % 10**9))


def textured_scene(width: int, height: int, seed: int) -> np.ndarray:
    """Shapes of random colour on smoothed noise: corners for ORB everywhere."""
    rng = np.random.default_rng(seed)
    scene = cv2.GaussianBlur(rng.integers(0, 256, (height, width, 3), dtype=np.uint8), (0, 0), 2)
    for _ in range(width * height // 1500):
        colour = [int(c) for c in rng.integers(0, 256, 3)]
        x, y = int(rng.integers(0, width)), int(rng.integers(0, height))
        w, h = (int(v) for v in rng.integers(4, 30, 2))
        cv2.rectangle(scene, (x, y), (x + w, y + h), colour, cv2.FILLED)
    return cv2.GaussianBlur(scene, (0, 0), 1.0)


def expected_range(probe: str) -> float | None:
    """Marker distance the probe frame shows (fronto-parallel, centred)."""
    if probe == "tag":
        return FX * TAG_SIZE_M / (12 * 8)
    if probe == "sign":
        return FX * SIGN_WIDTH_M / 240
    return None


class Lockstep:
    """Frames to the node, its statuses and cmd_vel back, in lockstep on its ~status: publish a
    frame, wait for its status (and for the cmd_vel that status says went out)."""

    RATE = 30.0

    def __init__(self, node: str, reads_camera_info: bool = True):
        import rospy
        from diagnostic_msgs.msg import DiagnosticArray
        from geometry_msgs.msg import Twist
        from nav_msgs.msg import Odometry
        from sensor_msgs.msg import CameraInfo, Image

        from follow_bot_msgs.msg import BehaviourStatus

        self.cond = threading.Condition()
        self.statuses: list = []
        self.diagnostics: dict = {}  # the node's latest "<node>: behaviour" status
        self.twists: list[tuple[float, float, float]] = []  # (wall, linear, angular)
        self.image_pub = rospy.Publisher("/camera/rgb/image_raw", Image, queue_size=10)
        info_pub = rospy.Publisher("/camera/rgb/camera_info", CameraInfo, queue_size=1, latch=True)
        odom_pub = rospy.Publisher("/odom", Odometry, queue_size=1, latch=True)
        self.status_sub = rospy.Subscriber(f"/{node}/status", BehaviourStatus, self._on_status)
        self.cmd_sub = rospy.Subscriber("/cmd_vel", Twist, self._on_twist)
        self.diagnostics_name = f"{node}: behaviour"
        rospy.Subscriber("/diagnostics", DiagnosticArray, self._on_diagnostics)
        info_pub.publish(pinhole_info())
        odom_pub.publish(odom_msg(0.0))
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline and not (
            self.image_pub.get_num_connections()
            and self.status_sub.get_num_connections()
            and self.cmd_sub.get_num_connections()
        ):
            time.sleep(0.05)
        if reads_camera_info:  # a C++ behaviour: its diagnostics count the camera_info it took
            taken = self.wait_diagnostics(lambda d: d.get("camera_info_accepted") == "1")
            assert taken, f"the node never took the camera_info: {self.diagnostics}"
        self.t = 1000.0  # frame stamps, s: 1/RATE apart whatever the wall clock does

    def _on_status(self, msg) -> None:
        with self.cond:
            self.statuses.append(msg)
            self.cond.notify_all()

    def _on_diagnostics(self, array) -> None:
        for s in array.status:
            if s.name == self.diagnostics_name:
                with self.cond:
                    self.diagnostics = {"message": s.message, **{v.key: v.value for v in s.values}}
                    self.cond.notify_all()

    def wait_diagnostics(self, predicate, timeout: float = 20.0) -> bool:
        """Whether the node's diagnostics came to satisfy `predicate` within `timeout` s."""
        with self.cond:
            return self.cond.wait_for(lambda: predicate(self.diagnostics), timeout)

    def _on_twist(self, msg) -> None:
        with self.cond:
            self.twists.append((time.monotonic(), msg.linear.x, msg.angular.z))
            self.cond.notify_all()

    def frame(self, msg, wall_rate: bool = False) -> None:
        import rospy

        self.t += 1.0 / self.RATE
        msg.header.stamp = rospy.Time.from_sec(self.t)
        with self.cond:
            answered, heard = len(self.statuses), len(self.twists)
            self.image_pub.publish(msg)
            assert self.cond.wait_for(lambda: len(self.statuses) > answered, 10.0), "no status"
            # The frame's own cmd_vel, when its status says one went out (counted per frame: a
            # running total would be off by any Twist sent outside a frame, e.g. ~enable's zero).
            if self.statuses[-1].command_sent:
                assert self.cond.wait_for(lambda: len(self.twists) > heard, 10.0), "no cmd_vel"
        if wall_rate:
            time.sleep(1.0 / self.RATE)

    def summary(self) -> dict:
        with self.cond:
            return {
                "statuses": [
                    [s.active, s.command_sent, s.command.linear.x, s.command.angular.z, s.state]
                    for s in self.statuses
                ],
                "twists": self.twists[:],
            }
