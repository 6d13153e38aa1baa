"""Seeded fuzzer for the camera nodes: malformed and random frames, CameraInfo and odometry.

Starts a roscore of its own (a free port) and every node under test as its own process, sends
each node a seeded storm (or the named crash cases), then checks per node that the original
process is still alive, that a valid frame afterwards gets the right answer, that every
Twist it ever published was finite and within the limits, and that the node's own counters on
/diagnostics (frames accepted, dropped by reason; camera_infos accepted and dropped) match, per
reason, what the fuzzer knows it sent (count_errors). Prints one line of counts per node, the
counters as counted/expected, and a JSON summary; exits 1 when any node fails.

    rosrun harness fuzz --messages 10000 --seed 1          # the storm, every node
    rosrun harness fuzz --cases          # the known killers, each on fresh nodes
    rosrun harness fuzz --nodes parker_tag parker_sign --messages 500
"""

from __future__ import annotations

import argparse
import json
import math
import os
import random
import subprocess
import sys
import threading
import time
import zlib
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path

import cv2
import numpy as np

from follow_bot import core
from follow_bot.cfg import BeaconChaserConfig
from harness.apriltag_image import tag_image
from harness.processes import private_master, stop
from harness.render import Renderer
from harness.world import package_dir
from harness.world_file import parse_world

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
MAX_STAMP_SEC = 2**32 - 1
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

VALID_ENCODINGS = ["bgr8", "rgb8", "bgra8", "rgba8", "mono8", "mono16", "8UC1", "8UC3"]
INVALID_ENCODINGS = ["bayer_rggb8", "32FC1", "16UC1", "rgb16", "bgra16", "8UC4", "yuv422", "", "x"]
BYTES_PER_PIXEL = {"bgr8": 3, "rgb8": 3, "bgra8": 4, "rgba8": 4, "mono8": 1, "mono16": 2}
BYTES_PER_PIXEL.update({"8UC1": 1, "8UC3": 3})


# --- messages -----------------------------------------------------------------------------------


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


def _png_chunk(kind: bytes, body: bytes) -> bytes:
    return len(body).to_bytes(4, "big") + kind + body + zlib.crc32(kind + body).to_bytes(4, "big")


def malformed_compressed() -> list:
    """CompressedImages no decoder can turn into a usable frame (case `malformed_compressed`)."""
    from sensor_msgs.msg import CompressedImage

    good = compressed_msg(probe_frame("line")).data
    jpeg = cv2.imencode(".jpg", floor())[1].tobytes()
    # A well-formed PNG header announcing a 65535 x 65535 image, then nothing.
    bomb = b"\x89PNG\r\n\x1a\n" + _png_chunk(
        b"IHDR", (65535).to_bytes(4, "big") * 2 + bytes([8, 2, 0, 0, 0])
    )
    payloads = [
        ("bgr8; jpeg compressed bgr8", b""),
        ("bgr8; jpeg compressed bgr8", bytes(range(256)) * 4),
        ("bgr8; jpeg compressed bgr8", jpeg[: len(jpeg) // 3]),  # truncated
        ("bgr8; png compressed bgr8", bomb),
        ("yuv422; png compressed bgr8", good),  # an encoding nobody decodes to
        ("bgr8; png compressed bgr8", good[:40]),
    ]
    messages = []
    for fmt, data in payloads:
        msg = CompressedImage(format=fmt, data=data)
        msg.header.stamp.secs = 1000
        messages.append(msg)
    return messages


def broken_camera_infos() -> list:
    """CameraInfos a node must ignore (NaN or zero K, P; a D of the wrong size for its model, an
    unknown model with distortion, NaN D, an R that is no rotation) and lenses that are usable
    but extreme, each followed by a valid frame, which the node then reads through that lens
    (case `broken_camera_info`)."""
    nan = float("nan")
    barrel = [-0.28, 0.07, 0.0, 0.0, 0.0]
    broken = [
        {"K": [nan] * 9},
        {"K": [0.0] * 9, "P": [0.0] * 12},
        {"P": [nan] * 12},
        {"D": barrel[:3]},
        {"distortion_model": "rational_polynomial", "D": barrel},
        {"distortion_model": "equidistant", "D": barrel[:4]},
        {"D": [nan, 0.0, 0.0, 0.0, 0.0]},
        {"D": barrel, "R": [2.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]},
        {"D": [1e308, -1e308, 1e308, 0.0, 1e308]},
        {"D": [50.0, 0.0, 0.0, 0.0, 0.0]},
        {"D": barrel, "P": [0.0] * 12},
        {"D": barrel},
    ]
    line = probe_frame("line")
    messages = []
    for fields in broken:
        info = pinhole_info()
        for name, value in fields.items():
            setattr(info, name, value)
        info.header.stamp.secs = 1000
        messages += [info, line]
    return messages


# Cases sent through the `compressed` transport: the nodes run with _image_transport:=compressed.
COMPRESSED_CASES = {"malformed_compressed"}


def crash_cases() -> dict[str, list]:
    """The four killers the first fuzzing run found, each a short message list,
    malformed payloads of the compressed transport and broken camera_info."""
    line = probe_frame("line")
    return {
        # Passes step >= width*2 and data == height*step, but a 16-bit cv::Mat needs an even step.
        "mono16_odd_step": [image_msg(8, 4, "mono16", 17, bytes(68), (1000, 0))],
        # cv_bridge turns big-endian 16-bit data into a 2-channel image.
        "mono16_big_endian": [image_msg(2, 2, "mono16", 4, bytes(8), (1000, 0), big_endian=1)],
        # Two valid frames stamped more than 2^31 s apart: ros::Duration cannot hold the gap.
        "stamp_jump": [_restamp(line, (0, 1)), _restamp(line, (MAX_STAMP_SEC, 0))],
        # libapriltag's quad search reads outside images only a few rows high.
        "tiny_frames": [
            bgr_msg(np.full((h, w, 3), 128, np.uint8), (1000, 0))
            for w, h in [(4, 4), (640, 1), (640, 2), (640, 3), (640, 4), (66, 3), (1, 1), (3, 640)]
        ],
        "malformed_compressed": malformed_compressed(),
        "broken_camera_info": broken_camera_infos(),
    }


def _restamp(msg, stamp):
    msg = image_msg(msg.width, msg.height, msg.encoding, msg.step, msg.data, stamp)
    return msg


class Storm:
    """A seeded sequence of random Image, CameraInfo and Odometry messages."""

    def __init__(self, seed: int):
        self.rng = random.Random(seed)

    def stamp(self):
        r = self.rng
        choice = r.random()
        if choice < 0.15:
            return (0, 0)
        if choice < 0.25:
            return (0, 1)
        if choice < 0.35:
            return (MAX_STAMP_SEC, r.choice([0, 999_999_999]))
        if choice < 0.45:
            return (r.randrange(2**32), r.randrange(2**32))  # nsecs past 1e9 too
        return (int(time.time()), r.randrange(1_000_000_000))

    def image(self):
        r = self.rng
        if r.random() < 0.13:
            return self.valid_image()
        encoding = r.choice(VALID_ENCODINGS + INVALID_ENCODINGS)
        bpp = BYTES_PER_PIXEL.get(encoding, r.choice([1, 2, 3, 4, 8]))
        kind = r.random()
        if kind < 0.25:  # huge dimensions with short data
            width = r.choice([0, 1, 2**16, 2**31, 2**32 - 1, r.randrange(2**32)])
            height = r.choice([0, 1, 2**16, 2**31, 2**32 - 1, r.randrange(2**32)])
        else:
            width, height = r.randrange(0, 80), r.randrange(0, 80)
        step_kind = r.random()
        if step_kind < 0.4:
            step = (width * bpp) % 2**32
        elif step_kind < 0.6:
            step = (width * bpp + r.choice([-1, 1, 3])) % 2**32
        else:
            step = r.randrange(0, 2**32) if r.random() < 0.3 else r.randrange(0, 400)
        size_kind = r.random()
        full = height * step
        if size_kind < 0.5 and full < 200_000:
            size = full  # consistent sizes reach the deeper checks
        else:
            size = r.randrange(0, min(full, 2000) + 1) if full else r.randrange(0, 64)
        data = r.randbytes(size)
        return image_msg(width, height, encoding, step, data, self.stamp(), r.randrange(2))

    def valid_image(self):
        r = self.rng
        encoding = r.choice(VALID_ENCODINGS)
        bpp = BYTES_PER_PIXEL[encoding]
        if r.random() < 0.75:
            # The camera_info's image resized (tiny ones too): the nodes scale its intrinsics and
            # process the frame.
            scale = r.randrange(1, 50)
            width, height = WIDTH // 160 * scale, HEIGHT // 160 * scale
        elif r.random() < 0.2:
            width, height = r.randrange(1, 12), r.randrange(1, 12)  # tiny frames
        else:  # mostly of another shape than camera_info's: dropped, named in an error
            width, height = r.randrange(1, 200), r.randrange(1, 160)
        step = width * bpp + r.choice([0, 0, 0, 2, 4])  # padded rows are valid (even: mono16)
        return image_msg(width, height, encoding, step, r.randbytes(height * step), self.stamp())

    def camera_info(self):
        """A CameraInfo and whether a node must take it: usable ones (a sane lens for 640x480
        frames, so a frame's fate never depends on which of them came last) or random ones with
        at least one defect, by construction, that the nodes must refuse."""
        r = self.rng
        if r.random() < 0.3:
            fx = FX * r.uniform(0.5, 2.0)
            info = pinhole_info(fx, fx * r.uniform(0.9, 1.1), WIDTH / 2 * r.uniform(0.8, 1.2),
                                   HEIGHT / 2 * r.uniform(0.8, 1.2))  # fmt: skip
            if r.random() < 0.5:
                info.D = [r.uniform(-0.3, 0.3), r.uniform(-0.1, 0.1), 0.0, 0.0, 0.0]
            info.header.stamp.secs, info.header.stamp.nsecs = self.stamp()
            return info, True
        special = [0.0, -1.0, float("nan"), float("inf"), -float("inf"), 1e308, 1e-308]

        def value(typical):
            return r.choice(special) if r.random() < 0.4 else typical * r.uniform(0.01, 3)

        info = pinhole_info(value(FX), value(FX), value(WIDTH / 2), value(HEIGHT / 2))
        info.width = r.choice([0, 1, WIDTH, 2**32 - 1, r.randrange(2**32)])
        info.height = r.choice([0, 1, HEIGHT, 2**32 - 1, r.randrange(2**32)])
        info.D = [r.choice([*special, 0.1]) for _ in range(r.choice([0, 1, 5, 8, 14, 50]))]
        info.K = [k if r.random() < 0.8 else r.choice(special) for k in info.K]
        info.distortion_model = r.choice(["plumb_bob", "rational_polynomial", "", "??"])
        info.R = [x if r.random() < 0.9 else r.choice(special) for x in info.R]
        info.P = [x if r.random() < 0.8 else r.choice(special) for x in info.P]
        info.header.stamp.secs, info.header.stamp.nsecs = self.stamp()
        self.break_camera_info(info)
        return info, False

    def break_camera_info(self, info) -> None:
        """One defect that makes `info` unusable whatever its other fields (follow_bot_common's
        README: a size no frame has, a focal length that is not positive and finite, a D of the
        wrong size for its model, an unknown model with distortion, a NaN D, an R that is no
        rotation)."""
        r = self.rng
        nan = float("nan")
        defect = r.randrange(7)
        if defect == 0:
            info.width = 2**32 - 1
        elif defect in (1, 2):  # P's focal length when P is set, else K's: both broken
            info.K[0] = info.P[0] = nan if defect == 1 else r.choice([0.0, -FX])
        elif defect == 3:
            info.distortion_model, info.D = "plumb_bob", [0.1, 0.1, 0.1]
        elif defect == 4:
            info.distortion_model, info.D = "??", [0.1] * 5
        elif defect == 5:
            info.distortion_model, info.D = "plumb_bob", [nan, 0.0, 0.0, 0.0, 0.0]
        else:
            info.distortion_model, info.D = "plumb_bob", [-0.28, 0.07, 0.0, 0.0, 0.0]
            info.R = [2.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]

    def odom(self, random_yaw: bool = True):
        r = self.rng
        odom = odom_msg(r.uniform(-4, 4) if random_yaw else 0.0)
        q = odom.pose.pose.orientation
        if r.random() < 0.3:
            garbage = [0.0, float("nan"), float("inf"), 1e300]
            q.x, q.y, q.z, q.w = (r.choice(garbage) for _ in "xyzw")
        odom.twist.twist.linear.x = r.choice([0.0, float("nan"), 1e300, r.uniform(-1, 1)])
        return odom


# --- what a node must do with each message --------------------------------------------------------

FRAME_OUTCOMES = ["frames_accepted", "dropped_bad_encoding", "dropped_bad_size"]
FRAME_OUTCOMES += ["dropped_bad_stamp", "dropped_size_mismatch", "dropped_error"]
CAMERA_INFO_OUTCOMES = ["camera_info_accepted", "dropped_bad_camera_info"]
MAX_DIMENSION = 16384
# Messages lost in transport that a node's counters may miss, a fraction of those sent (see
# count_errors): the fuzzer's queues lose none, and the storm waits for the answer to every
# frame a node must accept, so a node's input queue of 1 loses a message only when the machine
# holds the node's thread for longer than the next two messages take to arrive (measured: 0 to
# 1 % at a load of 20 on 2 cores); and how long the final counters may take to reach
# /diagnostics.
LOST_ALLOWED = 0.03
COUNTS_TIMEOUT_S = 10.0
DIAGNOSTIC_PERIOD_S = 0.2
QUEUE = 100  # the fuzzer's publisher queues
PROCESSED_TIMEOUT_S = 5.0  # for a node's answer to a frame it must accept
MAX_UNANSWERED = 3


def frame_outcome(msg, behaviour: bool) -> str:
    """The diagnostics counter an Image must land in, by the frame rules the nodes document
    (image_converter/README.md, follow_bot_common/README.md), checked in their order: a known
    encoding, then a consistent layout (sides 1 to 16384, a step of at least width x bytes per
    pixel and a whole number of values, data = height x step), then stamp nanoseconds < 10^9;
    a behaviour then takes only frames that are the camera_info's 640x480 image resized by one
    factor (every usable camera_info this fuzzer sends is for 640x480)."""
    bpp = BYTES_PER_PIXEL.get(msg.encoding)
    if bpp is None:
        return "dropped_bad_encoding"
    value_bytes = 2 if msg.encoding == "mono16" else 1
    if (
        not (0 < msg.width <= MAX_DIMENSION and 0 < msg.height <= MAX_DIMENSION)
        or msg.step < msg.width * bpp
        or msg.step % value_bytes
        or len(msg.data) != msg.height * msg.step
    ):
        return "dropped_bad_size"
    if msg.header.stamp.nsecs >= 10**9:
        return "dropped_bad_stamp"
    if behaviour and msg.width * HEIGHT != msg.height * WIDTH:
        return "dropped_size_mismatch"
    return "frames_accepted"


# --- probes: a valid frame and the answer it must get --------------------------------------------


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


def expected_range(probe: str) -> float | None:
    """Marker distance the probe frame shows (fronto-parallel, centred)."""
    if probe == "tag":
        return FX * TAG_SIZE_M / (12 * 8)
    if probe == "sign":
        return FX * SIGN_WIDTH_M / 240
    return None


# --- the driver ---------------------------------------------------------------------------------


class NodeUnderTest:
    def __init__(
        self, key: str, spec: NodeSpec, env: dict, log_dir: Path, run: int, compressed: bool
    ):
        import rospy
        from geometry_msgs.msg import PoseStamped, Twist
        from nav_msgs.msg import Odometry
        from sensor_msgs.msg import CameraInfo, Image

        self.key, self.spec = key, spec
        # A fresh name per run: the master shuts down a same-named node's old address, which a
        # new process may have been given.
        self.name = f"fuzz{run}_{key}"
        ns = f"/fuzz{run}/{key}"
        topics = {"camera/rgb/image_raw": "image", "camera/rgb/camera_info": "camera_info"}
        topics |= {"cmd_vel": "cmd_vel", "odom": "odom"}
        args = [f"{name}:={ns}/{short}" for name, short in topics.items()]
        args.append(f"_diagnostic_period:={DIAGNOSTIC_PERIOD_S}")  # the final counters sooner
        if compressed:
            args.append("_image_transport:=compressed")
        self.compressed = compressed
        log_dir.mkdir(parents=True, exist_ok=True)
        self.log = open(log_dir / f"{key}.log", "w")  # noqa: SIM115 (closed in finish)
        self.process = subprocess.Popen(
            ["rosrun", *spec.rosrun_args(f"__name:={self.name}", *args)],
            env=env, stdout=self.log, stderr=subprocess.STDOUT,
        )  # fmt: skip
        self.lock = threading.Lock()
        self.twists = 0
        self.non_finite = 0
        self.over_limit = 0
        self.answers: list = []
        self.counts: dict[str, int] = {}  # its diagnostics' frame counters, latest
        if compressed:
            from sensor_msgs.msg import CompressedImage

            self.image_pub = rospy.Publisher(
                f"{ns}/image/compressed", CompressedImage, queue_size=1, tcp_nodelay=True
            )
        else:  # a queue: the fuzzer loses none; the node's own input queue is 1
            self.image_pub = rospy.Publisher(
                f"{ns}/image", Image, queue_size=QUEUE, tcp_nodelay=True
            )
        self.info_pub = rospy.Publisher(
            f"{ns}/camera_info", CameraInfo, queue_size=QUEUE, tcp_nodelay=True
        )
        self.odom_pub = rospy.Publisher(f"{ns}/odom", Odometry, queue_size=1)
        # Every frame a node processes gets one answer: a behaviour's ~status, image_converter's
        # ~output. The storm waits for it after each frame the node must accept (wait_processed).
        self.processed = 0
        self.processed_cond = threading.Condition()
        self.awaiting = 0  # the processed count the last frame it must accept brings
        self.unanswered = 0  # frames it must accept whose answer never came
        self.subs = []
        if spec.behaviour:
            from follow_bot_msgs.msg import BehaviourStatus

            topic, answer_type = f"/{self.name}/status", BehaviourStatus
        else:
            topic, answer_type = f"/{self.name}/output", Image
        self.subs.append(rospy.Subscriber(topic, answer_type, self._on_processed, tcp_nodelay=True))
        if spec.probe == "overlay":
            topic = f"/{self.name}/output"
            self.subs.append(rospy.Subscriber(topic, Image, self._on_answer, tcp_nodelay=True))
        else:
            twists = rospy.Subscriber(f"{ns}/cmd_vel", Twist, self._on_twist, tcp_nodelay=True)
            self.subs.append(twists)
        if spec.probe in ("tag", "sign"):
            topic = f"/{self.name}/target_pose"
            self.subs.append(rospy.Subscriber(topic, PoseStamped, self._on_answer))
        if spec.probe == "line":
            from follow_bot.msg import LineStatus

            self.subs.append(rospy.Subscriber(f"/{self.name}/line", LineStatus, self._on_answer))
        if spec.probe == "idle":  # an idle behaviour answers on ~status only, never cmd_vel
            from follow_bot_msgs.msg import BehaviourStatus

            topic = f"/{self.name}/status"
            self.subs.append(rospy.Subscriber(topic, BehaviourStatus, self._on_answer))
        if spec.probe == "green":
            from follow_bot.msg import BeaconDetections

            topic = f"/{self.name}/detections"
            self.subs.append(rospy.Subscriber(topic, BeaconDetections, self._on_answer))
        self.capture_reply = None
        self.sent = {"image": 0, "camera_info": 0, "odom": 0}
        # The node's diagnostics counters as each message sent must move them (frame_outcome,
        # Storm.camera_info); None once a message's fate is not known (a compressed payload the
        # transport may drop before the node sees it, a camera_info of unknown usability).
        self.expected: dict[str, int] | None = dict.fromkeys(self.outcome_keys(), 0)

    def _on_twist(self, msg):
        values = [msg.linear.x, msg.linear.y, msg.linear.z, msg.angular.x, msg.angular.y]
        values.append(msg.angular.z)
        with self.lock:
            self.twists += 1
            if not all(math.isfinite(v) for v in values):
                self.non_finite += 1
            elif (
                abs(msg.linear.x) > LIMIT_LINEAR
                or abs(msg.angular.z) > LIMIT_ANGULAR
                or any(values[1:5])
            ):
                self.over_limit += 1
            if self.spec.probe in ("twist", "turning"):
                self.answers.append(msg)

    def _on_answer(self, msg):
        with self.lock:
            self.answers.append(msg)

    def _on_processed(self, _msg):
        with self.processed_cond:
            self.processed += 1
            self.processed_cond.notify_all()

    def wait_processed(self, timeout: float) -> None:
        """Waits until the node answered the last frame it must accept: the messages after it
        then find its input queue empty, unless the machine starves the node (count_errors).
        A node that left MAX_UNANSWERED such frames unanswered is not waited for any more: it
        drops frames it must accept, which its counters will show."""
        if self.unanswered >= MAX_UNANSWERED:
            return
        with self.processed_cond:
            if not self.processed_cond.wait_for(lambda: self.processed >= self.awaiting, timeout):
                self.unanswered += 1

    def wait_connected(self, timeout: float) -> bool:
        deadline = time.monotonic() + timeout
        pubs = [self.image_pub]
        while time.monotonic() < deadline:
            alive = self.process.poll() is None
            if not alive:
                return False
            if all(p.get_num_connections() > 0 for p in pubs) and all(
                s.get_num_connections() > 0 for s in self.subs
            ):
                return True
            time.sleep(0.05)
        return False

    def prepare(self):
        """Intrinsics and a pose; a capture running in the background when asked."""
        self.send(pinhole_info(), usable=True)
        self.odom_pub.publish(odom_msg())
        time.sleep(0.1)
        if self.spec.capturing:
            self.start_capture()

    def start_capture(self):
        import rospy
        from std_srvs.srv import Trigger

        service = f"/{self.name}/capture"
        rospy.wait_for_service(service, timeout=20)
        frame = self.valid(probe_frame("idle"))
        for _ in range(3):
            self.send(frame)
            time.sleep(0.05)

        def call():
            try:
                self.capture_reply = rospy.ServiceProxy(service, Trigger)()
            except Exception as error:  # the node going away mid-call is reported elsewhere
                self.capture_reply = error

        threading.Thread(target=call, daemon=True).start()
        time.sleep(0.2)

    def keep_capturing(self):
        """A valid frame for a capturing node: invalid ones do not count against the frame
        timeout (~frame_timeout, 1 s) that would end the capture."""
        if self.spec.capturing:
            self.send(self.valid(probe_frame("idle")))
            time.sleep(0.05)

    def valid(self, frame):
        """A valid bgr8 frame in this node's transport."""
        return compressed_msg(frame) if self.compressed else frame

    def outcome_keys(self) -> list[str]:
        return FRAME_OUTCOMES + (CAMERA_INFO_OUTCOMES if self.spec.behaviour else [])

    def send(self, msg, usable: bool | None = None):
        """Publishes `msg` and counts what the node must do with it (`usable`: a camera_info's
        fate, known by construction)."""
        kind = {"sensor_msgs/CameraInfo": "camera_info", "nav_msgs/Odometry": "odom"}.get(
            msg._type, "image"
        )
        with self.processed_cond:
            processed = self.processed
        {"image": self.image_pub, "camera_info": self.info_pub, "odom": self.odom_pub}[
            kind
        ].publish(msg)
        self.sent[kind] += 1
        if self.expected is None or kind == "odom":
            return
        if kind == "camera_info":
            if not self.spec.behaviour:  # image_converter reads none
                return
            outcome = None if usable is None else CAMERA_INFO_OUTCOMES[0 if usable else 1]
        else:
            outcome = None if self.compressed else frame_outcome(msg, self.spec.behaviour)
        if outcome is None:
            self.expected = None
        else:
            self.expected[outcome] += 1
            if outcome == "frames_accepted":
                self.awaiting = processed + 1

    def on_diagnostics(self, status: dict) -> None:
        """The node's latest frame counters (its "<node>: behaviour" or "<node>: frames")."""
        with self.lock:
            self.counts = {k: int(status[k]) for k in self.outcome_keys() if k in status}

    def diagnostics_name(self) -> str:
        # diagnostic_updater's "<node name without its leading slash>: <status>"
        return f"{self.name}: " + ("behaviour" if self.spec.behaviour else "frames")

    def wait_counts(self, timeout: float) -> dict[str, int]:
        """The node's counters once they add up to every message sent (or at the timeout: then
        the shortfall is what transport lost). With no expectation (a message's fate unknown)
        there is nothing to wait for: the counters as they are."""
        if self.expected is None:
            with self.lock:
                return dict(self.counts)
        deadline = time.monotonic() + timeout
        while True:
            with self.lock:
                counts = dict(self.counts)
            if sum(counts.values()) >= sum(self.expected.values()) or time.monotonic() > deadline:
                return counts
            time.sleep(0.05)

    def probe(self) -> str:
        """Empty when a valid frame gets the right answer, else what went wrong."""
        self.send(pinhole_info(), usable=True)
        self.odom_pub.publish(odom_msg())
        time.sleep(0.2)
        probe = self.spec.probe
        error = "no answer"
        for _ in range(5):  # the first answers may still be the watchdog's stop
            with self.lock:
                self.answers.clear()
            self.send(self.valid(probe_frame(probe)))
            deadline = time.monotonic() + 3.0
            while time.monotonic() < deadline:
                with self.lock:
                    answers = list(self.answers)
                if answers:
                    time.sleep(0.05)
                    with self.lock:
                        answers = list(self.answers)
                    error = check_answer(probe, answers)
                    break
                time.sleep(0.01)
            if not error:
                return ""
            time.sleep(0.05)
        return error

    def finish(self) -> dict:
        alive = self.process.poll() is None
        code = self.process.returncode
        probe_error = self.probe() if alive else "process died"
        if self.spec.probe == "idle" and self.twists and not probe_error:
            probe_error = f"idle node sent {self.twists} cmd_vel Twists"
        alive = alive and self.process.poll() is None
        counts = self.wait_counts(COUNTS_TIMEOUT_S) if alive else {}
        stop(self.process)
        self.log.close()
        with self.lock:
            return {
                "expected": self.expected,
                "counts": counts,
                "count_errors": count_errors(self.expected, counts),
                "node": self.key,
                "messages": sum(self.sent.values()),
                **self.sent,
                "alive": alive,
                "exit_code": None if alive else code,
                "crashes": 0 if alive else 1,
                "probe": probe_error or "ok",
                "twists": self.twists,
                "non_finite": self.non_finite,
                "over_limit": self.over_limit,
            }


def count_errors(expected: dict[str, int] | None, counts: dict[str, int]) -> list[str]:
    """How a node's own counters disagree with what it was sent. Every message is counted once,
    under the outcome the fuzzer expects: no counter may exceed its expected count (a message
    counted under the wrong reason fails); only messages lost in transport (the node's input
    queue of 1 drops the older message when a newer one arrives before the node took it) go
    uncounted, at most LOST_ALLOWED of all sent, and each counter may fall short by no more than
    were lost in all."""
    if expected is None:
        return []
    if not counts:
        return ["no frame counters on /diagnostics"]
    sent, counted = sum(expected.values()), sum(counts.values())
    lost = sent - counted
    errors = []
    if lost < 0:
        errors.append(f"{counted} messages counted, {sent} sent")
    elif lost > LOST_ALLOWED * sent:
        allowed = f"transport may lose {LOST_ALLOWED:.0%}"
        errors.append(f"{lost} of {sent} messages uncounted ({allowed})")
    for key, want in expected.items():
        got = counts.get(key, 0)
        if not want - max(lost, 0) <= got <= want:
            errors.append(f"{key}: {got} counted, {want} expected")
    return errors


def check_answer(probe: str, answers: list) -> str:
    last = answers[-1]
    if probe == "overlay":
        from follow_bot_msgs.ros_image import msg_to_bgr

        image = msg_to_bgr(last)
        # The red circle (radius 25) crosses the centre row 25 px right of the centre.
        if image.shape != (64, 64, 3) or tuple(image[32, 57]) != (0, 0, 255):
            return f"overlay wrong: {image.shape} {image[32, 57] if image.ndim == 3 else ''}"
        if tuple(image[32, 32]) != (90, 90, 90):
            return "overlay changed the centre pixel"
        return ""
    if probe == "line":
        if not last.found or abs(last.centroid_x - WIDTH / 2) > 1.0:
            return f"line at {last.centroid_x} found={last.found}, expected {WIDTH / 2}"
        return ""
    if probe == "green":
        green = [d for d in last.detections if d.colour == "green"]
        if not green or not green[0].found or abs(green[0].centroid_x - WIDTH / 2) > 2:
            return f"green beacon not found at the centre: {green}"
        return ""
    if probe in ("tag", "sign"):
        z = last.pose.position.z
        expected = expected_range(probe)
        if abs(z - expected) > 0.05 * expected or abs(last.pose.position.x) > 0.05:
            return f"marker at z={z:.3f} x={last.pose.position.x:.3f}, expected z={expected:.3f}"
        return ""
    if probe == "idle":  # BehaviourStatus answers
        if any(s.active or s.command_sent for s in answers):
            return f"idle panorama steering: {last.state}, sent {last.command_sent}"
        return ""
    if probe == "turning":
        if not last.angular.z > 0.0:
            return f"capturing panorama not turning toward the left end: {last.angular.z}"
        return ""
    return f"unknown probe {probe}"


class Dispatch:
    """A subscriber callback that can be pointed at the nodes of each run in turn."""

    def __init__(self):
        self.callback = lambda msg: None

    def __call__(self, msg):
        self.callback(msg)


def run(keys, messages, seed, cases, log_dir: Path, pause: float) -> list[dict]:
    log_dir.mkdir(parents=True, exist_ok=True)
    with private_master() as env:
        env.pop("ROS_NAMESPACE", None)
        os.environ.update(ROS_MASTER_URI=env["ROS_MASTER_URI"])
        import rospy

        rospy.init_node("fuzzer", anonymous=True, disable_signals=True)
        try:
            return run_batches(keys, messages, seed, cases, log_dir, pause, env)
        finally:
            rospy.signal_shutdown("fuzzing done")


def run_batches(keys, messages, seed, cases, log_dir: Path, pause: float, env: dict) -> list[dict]:
    """The storm (or each crash case) on fresh copies of the nodes, under a running master."""
    import rospy
    from diagnostic_msgs.msg import DiagnosticArray

    results = []
    diagnostics = Dispatch()
    rospy.Subscriber("/diagnostics", DiagnosticArray, diagnostics, queue_size=100)
    batches = [(case, msgs) for case, msgs in crash_cases().items()] if cases else [("storm", None)]
    for run_index, (case, case_msgs) in enumerate(batches):
        compressed = case in COMPRESSED_CASES
        nodes = [
            NodeUnderTest(k, NODES[k], env, log_dir / case, run_index, compressed) for k in keys
        ]
        by_status = {node.diagnostics_name(): node for node in nodes}
        diagnostics.callback = lambda array, nodes=by_status: [
            nodes[s.name].on_diagnostics({kv.key: kv.value for kv in s.values})
            for s in array.status
            if s.name in nodes
        ]
        for node in nodes:
            if not node.wait_connected(30.0):
                raise RuntimeError(f"{node.key} did not start (see {node.log.name})")
        for node in nodes:
            node.prepare()
        if case_msgs is not None:
            for msg in case_msgs:
                for node in nodes:
                    node.send(msg)  # a case's camera_info: its fate not predicted
                time.sleep(0.1)
                for node in nodes:
                    node.keep_capturing()
        else:
            storm_all(nodes, messages, seed, pause)
        time.sleep(0.3)
        # A capture aborts after ~frame_timeout (1 s) without frames: probe it first.
        for node in sorted(nodes, key=lambda n: not n.spec.capturing):
            result = node.finish()
            result["case"] = case
            results.append(result)
    return results


def storm_all(nodes, messages: int, seed: int, pause: float):
    """Each node gets its own seeded storm, interleaved so they run side by side."""
    storms = {node.key: Storm(seed + i) for i, node in enumerate(nodes)}
    for _ in range(messages):
        for node in nodes:
            storm = storms[node.key]
            r = storm.rng.random()
            if r < 0.15:
                info, usable = storm.camera_info()
                node.send(info, usable)
            elif r < 0.2:
                # A capture must stay running: its yaw only ever garbage, never another heading.
                node.send(storm.odom(random_yaw=not node.spec.capturing))
            else:
                node.send(storm.image())
        for node in nodes:
            node.wait_processed(PROCESSED_TIMEOUT_S)
        # Valid frames cost real work; give the slowest node time to take the next message.
        time.sleep(pause)


def print_table(results: list[dict]) -> None:
    head = f"{'case':<18}{'node':<20}{'messages':>9}{'crashes':>8}{'non-finite':>11}"
    print(head + f"{'over-limit':>11}{'twists':>8}  probe")
    for r in results:
        print(
            f"{r['case']:<18}{r['node']:<20}{r['messages']:>9}{r['crashes']:>8}"
            f"{r['non_finite']:>11}{r['over_limit']:>11}{r['twists']:>8}  {r['probe']}"
        )
    counted = [r for r in results if r["expected"] is not None]
    if not counted:
        return
    # The nodes' own counters, each as counted/expected; received: frames and camera_infos.
    short = {"frames_accepted": "accepted", "camera_info_accepted": "info ok"}
    short |= {k: k.removeprefix("dropped_") for k in FRAME_OUTCOMES + CAMERA_INFO_OUTCOMES[1:]}
    keys = FRAME_OUTCOMES + CAMERA_INFO_OUTCOMES
    print(f"\n{'case':<18}{'node':<20}{'received':>11}" + "".join(f"{short[k]:>16}" for k in keys))
    for r in counted:
        got, want = r["counts"], r["expected"]
        received = f"{sum(got.values())}/{sum(want.values())}"
        cells = "".join(
            f"{got.get(k, 0)}/{want[k]}".rjust(16) if k in want else f"{'-':>16}" for k in keys
        )
        errors = "; ".join(r["count_errors"])
        print(f"{r['case']:<18}{r['node']:<20}{received:>11}{cells}  {errors}")


def failed(result: dict) -> bool:
    return bool(
        result["crashes"] or result["non_finite"] or result["over_limit"] or result["count_errors"]
    ) or (result["probe"] != "ok")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--nodes", nargs="+", choices=list(NODES), default=list(NODES))
    parser.add_argument("--messages", type=int, default=10000, help="messages per node")
    parser.add_argument("--seed", type=int, default=12)
    parser.add_argument("--cases", action="store_true", help="the known crash cases instead")
    parser.add_argument("--pause", type=float, default=0.002, help="wall s between rounds")
    parser.add_argument("--logs", type=Path, default=Path("/tmp/follow_bot_fuzz"))
    parser.add_argument("--json", type=Path, help="write the results here")
    args = parser.parse_args(argv)
    results = run(args.nodes, args.messages, args.seed, args.cases, args.logs, args.pause)
    print_table(results)
    if args.json:
        args.json.write_text(json.dumps(results, indent=1))
    return 1 if any(failed(r) for r in results) else 0


if __name__ == "__main__":
    sys.exit(main())
