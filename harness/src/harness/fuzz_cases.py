"""What the fuzzer sends: valid and malformed frames (any encoding, size, step, byte order,
stamp), malformed compressed frames, broken CameraInfo, odometry, the known crash cases, and
the outcome each message must have in a node's counters.
"""

from __future__ import annotations

import random
import time
import zlib
from typing import Any

import cv2
import numpy as np

from harness.testing import (
    FX,
    HEIGHT,
    WIDTH,
    bgr_msg,
    compressed_msg,
    floor,
    image_msg,
    odom_msg,
    pinhole_info,
    probe_frame,
)

MAX_STAMP_SEC = 2**32 - 1
VALID_ENCODINGS = ["bgr8", "rgb8", "bgra8", "rgba8", "mono8", "mono16", "8UC1", "8UC3"]
INVALID_ENCODINGS = ["bayer_rggb8", "32FC1", "16UC1", "rgb16", "bgra16", "8UC4", "yuv422", "", "x"]
BYTES_PER_PIXEL = {"bgr8": 3, "rgb8": 3, "bgra8": 4, "rgba8": 4, "mono8": 1, "mono16": 2}


BYTES_PER_PIXEL.update({"8UC1": 1, "8UC3": 3})


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
    broken: list[dict[str, Any]] = [
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


FRAME_OUTCOMES = ["frames_accepted", "dropped_bad_encoding", "dropped_bad_size"]
FRAME_OUTCOMES += ["dropped_bad_stamp", "dropped_size_mismatch", "dropped_error"]


CAMERA_INFO_OUTCOMES = ["camera_info_accepted", "dropped_bad_camera_info"]
MAX_DIMENSION = 16384


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
