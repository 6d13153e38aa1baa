"""The bag doctor: replays a recording through a behaviour's own core and shows what it saw.

`rosrun follow_bot inspect BAG [--behaviour follower|beacons|parker] [--out DIR] [--fit-colours]`
reads the bag with the rosbag API (no ROS master): the camera's frames (sensor_msgs/Image, or
CompressedImage in any format OpenCV decodes, the old raspicam "jpg" included), camera_info,
tf_static (the camera's mounting), odom and cmd_vel where present. Each frame goes through the
detector and controller the node runs (follow_bot.core), then DIR gets:

- timeline.png: found / lost, the sighting's position, and the commands in the bag against the
  ones the core would send;
- worst_frames.png: the lost frames and the largest jumps, each with the detector's debug overlay
  and its mask;
- report.json: the figures (frames, detection rate, lost spans, jumps, commands, per-frame
  records);
- with --fit-colours (follower, beacons): fitted_params.yaml, the colour thresholds fitted to
  the bag, with the detection rate before and after (printed, and in report.json).
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

try:
    import cv2
except ImportError:  # Debian's python3 without python3-opencv: main() says what to install
    cv2 = None

MISSING_LIBRARIES = (
    "inspect needs OpenCV and matplotlib for Python: install python3-opencv and "
    "python3-matplotlib (rosdep install --from-paths src --ignore-src), or run it with a Python "
    "that has them"
)
BEHAVIOURS = ("follower", "beacons", "parker")
# The node a behaviour's fitted_params.yaml is for, and what the fit sets.
NODES = {"follower": ("follower", "colour band"), "beacons": ("beacon_chaser", "colour thresholds")}
IMAGE_TYPES = ("sensor_msgs/Image", "sensor_msgs/CompressedImage")
TWIST_TYPES = ("geometry_msgs/Twist", "geometry_msgs/TwistStamped")
# Frames shown on the contact sheet by default.
SHEET_FRAMES = 12
# A sighting this confident (core.BandMeasurement.confidence) seeds the colour fit.
CONFIDENT = 0.8
# A beacon seeds the colour fit when its circle is this large (px radius): its inner part
# (BALL_INNER of the radius) is the ball's colour, beyond BALL_OUTER the background.
CONFIDENT_RADIUS = 8
BALL_INNER, BALL_OUTER = 0.8, 1.5
SUBSAMPLE = 4  # every 4th pixel of a beacon frame's rows and columns goes into the fit
# Frames whose band rows are kept for the colour fit (evenly spread over the bag).
FIT_SAMPLES = 300
# The line's hue spread in the fit: pixels this far (OpenCV hue) from the histogram's peak.
HUE_WINDOW = 12
HUE_MARGIN = 3  # widens the fitted hue range on either side (sensor noise, compression)
LOWER_MARGIN = 10  # below the line's 2nd percentile of saturation and value: their floor
LINE_KEPT = 0.8  # the fraction of the line's pixels in each frame the value bound keeps
MIN_LINE_PIXELS = (
    30  # line pixels in a sampled band for it to bound the fit (the min_pixels default)
)
HUE_COUNT = 180  # OpenCV hue


@dataclass
class Topics:
    image: str
    image_type: str
    camera_info: str | None = None
    cmd_vel: str | None = None
    cmd_vel_type: str | None = None
    odom: str | None = None
    tf_static: str | None = None
    frames: int = 0


def pick_topics(bag, image_topic: str | None = None, cmd_vel_topic: str | None = None) -> Topics:
    """The bag's camera (the image topic with the most messages, or `image_topic`), the
    camera_info next to it, the busiest Twist topic (or `cmd_vel_topic`), odom and tf_static."""
    info = bag.get_type_and_topic_info().topics
    by_type: dict[str, list[str]] = {}
    for topic, entry in info.items():
        by_type.setdefault(entry.msg_type, []).append(topic)

    def busiest(types):
        topics = [t for ty in types for t in by_type.get(ty, [])]
        return max(sorted(topics), key=lambda t: info[t].message_count, default=None)

    image = image_topic or busiest(IMAGE_TYPES)
    if image is None or image not in info:
        raise ValueError(f"no camera image topic in the bag (topics: {', '.join(sorted(info))})")
    if info[image].msg_type not in IMAGE_TYPES:
        raise ValueError(f"{image} holds {info[image].msg_type}, not an image")
    namespace = image.rsplit("/", 1)[0] if "/" in image.lstrip("/") else ""
    infos = sorted(by_type.get("sensor_msgs/CameraInfo", []))
    near = [t for t in infos if t.rsplit("/", 1)[0] == namespace]
    cmd = cmd_vel_topic or busiest(TWIST_TYPES)
    odoms = sorted(by_type.get("nav_msgs/Odometry", []))
    tf_static = "/tf_static" if "/tf_static" in info else None
    return Topics(
        image=image,
        image_type=info[image].msg_type,
        camera_info=(near or infos or [None])[0],
        cmd_vel=cmd,
        cmd_vel_type=info[cmd].msg_type if cmd in info else None,
        odom=odoms[0] if odoms else None,
        tf_static=tf_static,
        frames=info[image].message_count,
    )


RAW_ENCODINGS = {  # encoding: (channels, conversion to BGR or None)
    "bgr8": (3, None), "8UC3": (3, None), "rgb8": (3, "COLOR_RGB2BGR"),
    "bgra8": (4, "COLOR_BGRA2BGR"), "rgba8": (4, "COLOR_RGBA2BGR"),
    "mono8": (1, "COLOR_GRAY2BGR"), "8UC1": (1, "COLOR_GRAY2BGR"),
}  # fmt: skip


def decode_image(msg) -> np.ndarray:
    """A contiguous HxWx3 uint8 BGR frame of a sensor_msgs/Image or CompressedImage; ValueError
    for an encoding or format it cannot read."""
    if hasattr(msg, "format"):  # CompressedImage: "jpeg", raspicam's "jpg", "bgr8; png ..."
        image = cv2.imdecode(np.frombuffer(msg.data, np.uint8), cv2.IMREAD_COLOR)
        if image is None:
            raise ValueError(f"cannot decode a compressed frame of format {msg.format!r}")
        return image
    if msg.encoding not in RAW_ENCODINGS:
        raise ValueError(f"unsupported encoding {msg.encoding!r} (8-bit colour or mono only)")
    channels, conversion = RAW_ENCODINGS[msg.encoding]
    rows = np.frombuffer(msg.data, np.uint8, count=msg.height * msg.step).reshape(msg.height, -1)
    image = rows[:, : msg.width * channels].reshape(msg.height, msg.width, channels)
    if conversion:
        return cv2.cvtColor(image, getattr(cv2, conversion))
    return np.ascontiguousarray(image)


def stamp_of(msg, recorded) -> float:
    """The message's header stamp in s, or the time it was recorded when it has none."""
    header = getattr(msg, "header", None)
    if header is not None and (header.stamp.secs or header.stamp.nsecs):
        return header.stamp.to_sec()
    return recorded.to_sec()


def twist_of(msg) -> tuple[float, float]:
    twist = getattr(msg, "twist", msg)  # TwistStamped, Odometry (twist.twist) or Twist
    twist = getattr(twist, "twist", twist)
    return twist.linear.x, twist.angular.z


def mounting_from_tf(transforms, optical_frame: str, base_frames=("base_footprint", "base_link")):
    """(height m, pitch rad down, x offset m) of `optical_frame` from a chain of tf_static
    transforms (geometry_msgs/TransformStamped) rooted at a base frame, or None. A camera
    mounted with a visible roll or yaw is not modelled (None, with the reason)."""
    parent_of = {t.child_frame_id.lstrip("/"): t for t in transforms}
    frame = optical_frame.lstrip("/")
    rotation, origin = np.eye(3), np.zeros(3)
    while frame in parent_of and frame not in base_frames:
        t = parent_of[frame]
        q = t.transform.rotation
        r = quaternion_matrix(q.x, q.y, q.z, q.w)
        p = t.transform.translation
        origin = r @ origin + np.array([p.x, p.y, p.z])
        rotation = r @ rotation
        frame = t.header.frame_id.lstrip("/")
    if frame not in base_frames or frame == optical_frame.lstrip("/"):
        return None, f"no tf_static chain from {optical_frame!r} to {' or '.join(base_frames)}"
    if frame == "base_link" and "base_link" in parent_of:  # base_link above base_footprint
        origin = origin + np.array([0.0, 0.0, parent_of["base_link"].transform.translation.z])
    axis_z, axis_x = rotation[:, 2], rotation[:, 0]  # optical: z forward, x right
    if abs(axis_z[1]) > math.sin(math.radians(1.0)) or abs(axis_x[2]) > math.sin(math.radians(1.0)):
        return None, f"{optical_frame!r} is rolled or turned sideways; default mounting used"
    return (origin[2], math.atan2(-axis_z[2], axis_z[0]), origin[0]), ""


def quaternion_matrix(x, y, z, w) -> np.ndarray:
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


# ---- the behaviours, one frame at a time ----------------------------------------------------


class FollowerReplay:
    """The follower nodelet's step: LineDetector (keeping the last sighting's blob), the
    steering law, the velocity limiter."""

    name = "follower"

    def __init__(self, core, camera, detector_config=None, steering=None):
        self.core, self.camera = core, camera
        self.detector = core.LineDetector(detector_config or core.LineDetectorConfig(), camera)
        self.law = core.make_steering_law(steering or core.SteeringConfig(), camera)
        self.seen = None

    def step(self, frame, stamp, applied):
        self.seen = self.detector.detect(frame, self.seen)
        band = self.seen.band
        desired = self.law.step(
            self.seen, stamp, self.core.Twist2D(linear=applied[0], angular=applied[1])
        )
        figures = {
            "found": bool(band.found),
            "position": band.error_normalised if band.pixel_count else None,
            "confidence": round(band.confidence, 3),
            "pixels": band.pixel_count,
            "state": self.law.state.name,
        }
        return self.seen, figures, desired

    def overlay(self, frame, seen):
        drawn = frame.copy()
        self.detector.draw_debug(drawn, seen)
        return drawn

    def mask(self, frame, seen):
        return self.detector.debug_mask(frame)

    def sample(self, frame, seen):
        """The band's rows and, in a confident sighting, the line's pixels in them."""
        band = seen.band
        rows = slice(band.row_begin, band.row_end)
        confident = band.found and band.confidence >= CONFIDENT
        return frame[rows].copy(), self.detector.debug_mask(frame)[rows] if confident else None

    @staticmethod
    def fit(samples):
        return fit_line_colours(samples)


class BeaconsReplay:
    """The beacon chaser's step: ColourBlobDetector, BeaconController (position: the followed
    colour's centroid, -1 left edge .. 1 right edge)."""

    name = "beacons"

    def __init__(self, core, camera, detector_config=None):
        self.core, self.camera = core, camera
        self.config = detector_config or core.ColourBlobConfig()
        self.detector = core.ColourBlobDetector(self.config)
        self.controller = core.BeaconController(core.BeaconControllerConfig(camera=camera))
        self.follow = self.controller.config.follow_colour

    def step(self, frame, stamp, applied):
        result = self.detector.detect(frame)
        blobs = {b.name: b for b in result.colours}
        desired = self.controller.update(result, stamp)
        followed = blobs.get(self.follow)
        half = result.image_width / 2.0
        figures = {
            "found": bool(followed and followed.found),
            "position": (followed.centroid[0] - half) / half
            if followed and followed.found
            else None,
            "confidence": None,
            "pixels": int(followed.area) if followed and followed.found else 0,
            "state": str(self.controller.state).rsplit(".", 1)[-1],
            "colours": sorted(name for name, b in blobs.items() if b.found),
        }
        return result, figures, desired

    def overlay(self, frame, result):
        drawn = frame.copy()
        for blob in result.colours:
            if blob.found:
                x, y, w, h = (int(v) for v in blob.bounding_box)
                cv2.rectangle(drawn, (x, y), (x + w, y + h), (255, 255, 255), 2)
                cv2.putText(
                    drawn,
                    blob.name,
                    (x, max(12, y - 4)),
                    cv2.FONT_HERSHEY_SIMPLEX,
                    0.5,
                    (255, 255, 255),
                    1,
                    cv2.LINE_AA,
                )
        return drawn

    def mask(self, frame, result):
        masks = [self.detector.mask(frame, b.name) for b in result.colours]
        return np.maximum.reduce(masks) if masks else np.zeros(frame.shape[:2], np.uint8)

    def sample(self, frame, result):
        """The frame (every SUBSAMPLE-th pixel) and a mask of it: 255 inside the circles of
        the beacons found large enough, 0 for the background, 128 near a found blob (its rim,
        its shading: neither). None without a confident beacon."""
        mask = np.zeros(frame.shape[:2], np.uint8)
        confident = False
        for blob in result.colours:
            if not blob.found:
                continue
            centre = tuple(int(round(c)) for c in blob.circle_centre)
            radius = blob.circle_radius
            if radius >= CONFIDENT_RADIUS:
                cv2.circle(mask, centre, int(BALL_OUTER * radius), 128, -1)
                cv2.circle(mask, centre, int(BALL_INNER * radius), 255, -1)
                confident = True
            else:
                x, y, w, h = (int(v) for v in blob.bounding_box)
                cv2.rectangle(
                    mask, (x - w // 2, y - h // 2), (x + w + w // 2, y + h + h // 2), 128, -1
                )
        step = slice(None, None, SUBSAMPLE)
        return frame[step, step].copy(), mask[step, step] if confident else None

    def fit(self, samples):
        return fit_beacon_colours(samples, [spec.hue_centre for spec in self.config.colours])


class ParkerReplay:
    """The parker's step with its tag target: TagDetector, ParkingServo (position: the tag's
    bearing, rad, positive right)."""

    name = "parker"

    def __init__(self, core, camera):
        self.core, self.camera = core, camera
        self.detector = core.TagDetector()
        self.servo = core.ParkingServo(core.ParkingServoConfig(camera=camera))

    def step(self, frame, stamp, applied):
        grey = cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
        tag = self.detector.detect(grey, self.camera)
        desired = self.servo.update(tag, stamp)
        x, _, z = tag.translation if tag is not None else (0.0, 0.0, 1.0)
        figures = {
            "found": tag is not None,
            "position": math.atan2(x, z) if tag is not None else None,
            "confidence": None,
            "pixels": 0,
            "state": str(self.servo.state).rsplit(".", 1)[-1],
        }
        return tag, figures, desired

    def overlay(self, frame, tag):
        drawn = frame.copy()
        if tag is not None:
            corners = np.rint(tag.corners).astype(np.int32)
            cv2.polylines(drawn, [corners], True, (0, 0, 255), 2)
        return drawn

    def mask(self, frame, tag):
        return cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)


# ---- the replay --------------------------------------------------------------------------------


@dataclass
class Replay:
    records: list[dict] = field(default_factory=list)
    kept: dict[int, tuple[np.ndarray, object]] = field(default_factory=dict)  # frame, result
    # Pixels for the colour fit and the mask of the target's among them (None: no confident one).
    samples: list[tuple[np.ndarray, np.ndarray | None]] = field(default_factory=list)
    decode_errors: dict[str, int] = field(default_factory=dict)


def camera_from(core, info, shape, mounting):
    """core.CameraGeometry of the bag's camera_info (or the default intrinsics scaled to the
    frame) and the mounting (height, pitch, x offset) or the default one."""
    default = core.CameraGeometry()
    height, width = shape[:2]
    if info is not None and info.K[0] > 0 and info.K[4] > 0:
        # A camera_info for another resolution (the stream was scaled): its K scaled to the frame.
        sx = width / info.width if info.width else 1.0
        sy = height / info.height if info.height else 1.0
        fx, cx, fy, cy = info.K[0] * sx, info.K[2] * sx, info.K[4] * sy, info.K[5] * sy
    else:
        scale = width / (2.0 * default.cx)
        fx, fy, cx, cy = default.fx * scale, default.fy * scale, width / 2.0, height / 2.0
    h, pitch, x_offset = mounting or (default.height_m, default.pitch_rad, default.x_offset_m)
    return core.CameraGeometry(
        fx=fx, fy=fy, cx=cx, cy=cy, height_m=h, pitch_rad=pitch, x_offset_m=x_offset
    )


def replay(core, bag_path, topics, make_behaviour, keep=(), sample_every=0):
    """Plays the bag's frames through make_behaviour(camera) (made at the first frame), with the
    bag's odometry (else its commands) as what the robot did between frames, as the node. Keeps
    the frames whose index is in `keep`; every `sample_every`-th frame's behaviour.sample().
    Returns the Replay and the behaviour."""
    import rosbag

    out = Replay()
    behaviour = limiter = None
    info = bag_cmd = odom_twist = None
    sent, last_stamp, t0 = (0.0, 0.0), None, None
    wanted = [t for t in (topics.image, topics.camera_info, topics.cmd_vel, topics.odom) if t]
    with rosbag.Bag(str(bag_path)) as bag:
        for topic, msg, recorded in bag.read_messages(topics=wanted):
            if topic == topics.camera_info:
                info = info or msg
                continue
            if topic == topics.cmd_vel:
                bag_cmd = twist_of(msg)
                continue
            if topic == topics.odom:
                odom_twist = twist_of(msg)
                continue
            stamp = stamp_of(msg, recorded)
            index = len(out.records)
            try:
                frame = decode_image(msg)
            except ValueError as error:
                out.decode_errors[str(error)] = out.decode_errors.get(str(error), 0) + 1
                continue
            if behaviour is None:
                t0 = stamp
                behaviour = make_behaviour(info, frame.shape)
                limiter = core.VelocityLimiter()
            applied = odom_twist if odom_twist is not None else sent
            result, figures, desired = behaviour.step(frame, stamp, applied)
            dt = stamp - last_stamp if last_stamp is not None else 0.0
            command = limiter.limit(desired, max(dt, 0.0))
            sent, last_stamp = (command.linear, command.angular), stamp
            record = {"frame": index, "t": round(stamp - t0, 4), **figures}
            record.update(core_v=round(command.linear, 4), core_w=round(command.angular, 4))
            if bag_cmd is not None:
                record.update(bag_v=round(bag_cmd[0], 4), bag_w=round(bag_cmd[1], 4))
            out.records.append(record)
            if index in keep:
                out.kept[index] = (frame, result)
            if sample_every and index % sample_every == 0:
                out.samples.append(behaviour.sample(frame, result))
    if behaviour is None:
        raise ValueError(f"no frame of {topics.image} could be decoded: {out.decode_errors}")
    return out, behaviour


# ---- figures -----------------------------------------------------------------------------------


def lost_spans(records) -> list[dict]:
    """Runs of frames without a sighting: first and last frame, start and end time (s)."""
    spans, start = [], None
    for i, r in enumerate([*records, {"found": True}]):
        if not r["found"] and start is None:
            start = i
        elif r["found"] and start is not None:
            first, last = records[start], records[i - 1]
            spans.append(
                {
                    "first_frame": first["frame"],
                    "last_frame": last["frame"],
                    "start_s": first["t"],
                    "end_s": last["t"],
                    "frames": i - start,
                }
            )
            start = None
    return spans


def jumps(records) -> list[dict]:
    """The sighting's moves between consecutive found frames, largest first."""
    out = []
    for a, b in itertools.pairwise(records):
        if a["found"] and b["found"] and a["position"] is not None and b["position"] is not None:
            out.append(
                {
                    "frame": b["frame"],
                    "t": b["t"],
                    "jump": round(abs(b["position"] - a["position"]), 4),
                }
            )
    return sorted(out, key=lambda j: -j["jump"])


def worst_frames(records, count=SHEET_FRAMES) -> list[tuple[int, str]]:
    """Up to `count` frames (index, why), in bag order: half of them lost frames (spread evenly
    over all lost frames), the rest the largest jumps, then more lost frames if jumps run out."""
    lost = [r["frame"] for r in records if not r["found"]]
    span_of = {}
    for span in lost_spans(records):
        for frame in range(span["first_frame"], span["last_frame"] + 1):
            span_of[frame] = f"lost ({span['frames']} frames from #{span['first_frame']})"

    def spread(frames, n):
        if n >= len(frames):
            return list(frames)
        return [frames[round(k)] for k in np.linspace(0, len(frames) - 1, n)]

    chosen = {frame: span_of[frame] for frame in spread(lost, (count + 1) // 2)}
    for j in jumps(records):
        if len(chosen) >= count:
            break
        chosen.setdefault(j["frame"], f"jump {j['jump']:.2f}")
    for frame in spread(lost, count):
        if len(chosen) >= count:
            break
        chosen.setdefault(frame, span_of[frame])
    return sorted(chosen.items())


def summary(records, topics, replay_result) -> dict:
    found = [r for r in records if r["found"]]
    positions = np.array([r["position"] for r in found if r["position"] is not None])
    duration = records[-1]["t"] - records[0]["t"] if len(records) > 1 else 0.0
    spans = lost_spans(records)
    figures = {
        "image_topic": topics.image,
        "image_type": topics.image_type,
        "camera_info": topics.camera_info,
        # What the robot did between frames (the path law's motion), as the node: odom's
        # twist, else the commands the core sent.
        "applied_from": topics.odom or "the core's commands",
        "frames": len(records),
        "undecodable_frames": replay_result.decode_errors,
        "duration_s": round(duration, 3),
        "frame_rate_hz": round((len(records) - 1) / duration, 2) if duration > 0 else None,
        "detection_rate": round(len(found) / len(records), 4),
        "lost_spans": spans,
        "longest_lost_s": max((s["end_s"] - s["start_s"] for s in spans), default=0.0),
        "position": {
            "mean": round(float(positions.mean()), 4),
            "std": round(float(positions.std()), 4),
            "min": round(float(positions.min()), 4),
            "max": round(float(positions.max()), 4),
        }
        if len(positions)
        else None,
        "largest_jumps": jumps(records)[:5],
    }
    with_cmd = [r for r in records if "bag_v" in r]
    figures["commands"] = {"topic": topics.cmd_vel, "frames_with_a_bag_command": len(with_cmd)}
    if with_cmd:
        dv = np.array([r["bag_v"] - r["core_v"] for r in with_cmd])
        dw = np.array([r["bag_w"] - r["core_w"] for r in with_cmd])
        figures["commands"].update(
            rms_linear_difference=round(float(np.sqrt(np.mean(dv**2))), 4),
            rms_angular_difference=round(float(np.sqrt(np.mean(dw**2))), 4),
        )
    return figures


# ---- pictures ----------------------------------------------------------------------------------


def plot_timeline(path, records, title, fitted_records=None):
    """found / lost, the sighting's position, the angular and linear commands against time."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib import pyplot

    t = np.array([r["t"] for r in records])
    fig, axes = pyplot.subplots(4, 1, figsize=(9, 7), sharex=True, dpi=72)
    found = np.array([r["found"] for r in records], float)
    # Found frames as bars: the replayed parameters' on top, the fitted colours' below.
    axes[0].fill_between(t, 0.55, 0.55 + 0.45 * found, step="post", color="tab:green", lw=0)
    ticks, labels = [0.775], ["as set"]
    if fitted_records is not None:
        fitted = np.array([r["found"] for r in fitted_records], float)
        axes[0].fill_between(t, 0.0, 0.45 * fitted, step="post", color="tab:blue", lw=0)
        ticks, labels = [0.225, 0.775], ["fitted", "as set"]
    axes[0].set_ylim(0, 1)
    axes[0].set_yticks(ticks, labels)
    axes[0].set_ylabel("found")
    position = np.array([np.nan if r["position"] is None else r["position"] for r in records])
    axes[1].plot(t, np.where(found > 0, position, np.nan), ".", ms=3, color="tab:orange")
    axes[1].set_ylabel("position")
    for span in lost_spans(records):
        for axis in axes:
            axis.axvspan(span["start_s"], span["end_s"] + 1e-3, color="tab:red", alpha=0.15, lw=0)
    for axis, key, unit in ((axes[2], "w", "rad/s"), (axes[3], "v", "m/s")):
        axis.plot(t, [r[f"core_{key}"] for r in records], color="tab:blue", lw=1, label="core")
        if any(f"bag_{key}" in r for r in records):
            bag = [r.get(f"bag_{key}", np.nan) for r in records]
            axis.plot(t, bag, color="black", lw=1, ls="--", label="in the bag")
        axis.set_ylabel(f"{key}, {unit}")
        axis.legend(loc="upper right", fontsize=8)
    axes[-1].set_xlabel("time, s (red: lost)")
    axes[0].set_title(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path)
    pyplot.close(fig)


TILE_HEIGHT = 180


def contact_sheet(path, behaviour, kept, chosen, records, columns=2):
    """A grid of the chosen frames: the debug overlay and the mask side by side, captioned."""
    tiles = []
    for index, why in chosen:
        frame, result = kept[index]
        overlay = behaviour.overlay(frame, result)
        mask = cv2.cvtColor(behaviour.mask(frame, result), cv2.COLOR_GRAY2BGR)
        scale = TILE_HEIGHT / frame.shape[0]
        size = (max(1, round(frame.shape[1] * scale)), TILE_HEIGHT)
        pair = np.hstack(
            [
                cv2.resize(overlay, size, interpolation=cv2.INTER_AREA),
                cv2.resize(mask, size, interpolation=cv2.INTER_NEAREST),
            ]
        )
        caption = np.full((22, pair.shape[1], 3), 255, np.uint8)
        text = f"#{index}  t={records[index]['t']:.2f} s  {why}"
        cv2.putText(
            caption, text, (4, 16), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (0, 0, 0), 1, cv2.LINE_AA
        )
        tiles.append(np.vstack([caption, pair]))
    if not tiles:
        tiles = [np.full((TILE_HEIGHT, 2 * TILE_HEIGHT, 3), 255, np.uint8)]
    width = max(t.shape[1] for t in tiles)
    tiles = [
        cv2.copyMakeBorder(
            t, 0, 4, 0, width - t.shape[1] + 4, cv2.BORDER_CONSTANT, value=(255, 255, 255)
        )
        for t in tiles
    ]
    while len(tiles) % columns:
        tiles.append(np.full_like(tiles[0], 255))
    rows = [np.hstack(tiles[i : i + columns]) for i in range(0, len(tiles), columns)]
    cv2.imwrite(str(path), np.vstack(rows))


# ---- the colour fit ----------------------------------------------------------------------------


def hue_distance(hues, centres) -> np.ndarray:
    """Each hue's distance (OpenCV hue, around the circle) to the nearest of `centres`."""
    offsets = hues.astype(int)[:, None] - np.asarray(centres)[None, :]
    return np.abs((offsets + HUE_COUNT // 2) % HUE_COUNT - HUE_COUNT // 2).min(axis=1)


def colour_outliers(pixels) -> tuple[np.ndarray, np.ndarray]:
    """The HSV pixels (Nx3) of a BGR image and which stand out of its colour: Otsu on the a*b*
    distance from the image's median colour."""
    hsv = cv2.cvtColor(pixels, cv2.COLOR_BGR2HSV).reshape(-1, 3)
    lab = cv2.cvtColor(pixels, cv2.COLOR_BGR2LAB).reshape(-1, 3).astype(np.float32)
    distance = np.linalg.norm(lab[:, 1:] - np.median(lab[:, 1:], axis=0), axis=1)
    scaled = np.clip(distance * 4.0, 0, 255).astype(np.uint8)  # a*b* units of 1/4
    threshold, _ = cv2.threshold(scaled, 0, 255, cv2.THRESH_BINARY + cv2.THRESH_OTSU)
    # An image with no colour outlier at all (a grey floor only): Otsu splits noise; a line's
    # paint or a ball stands at least 8 a*b* units off the floor.
    return hsv, scaled > max(threshold, 32)


def line_and_floor_pixels(samples) -> tuple[list[np.ndarray], np.ndarray]:
    """HSV pixels of the line (Nx3 per sampled band) and of the floor (Nx3, all bands). The
    line: pixels the default band finds in confident frames, and in every frame the band's
    colour outliers (colour_outliers) near the outliers' hue histogram peak."""
    outliers_hsv, line, floor = [], [], []
    for band, mask in samples:
        hsv, outlier = colour_outliers(band)
        confident = mask.reshape(-1) > 0 if mask is not None else np.zeros(len(hsv), bool)
        outliers_hsv.append((hsv, outlier, confident))
    candidates = np.vstack([h[o] for h, o, _ in outliers_hsv]) if outliers_hsv else np.empty((0, 3))
    if len(candidates) == 0:
        return [], np.empty((0, 3), np.uint8)
    histogram = np.bincount(candidates[:, 0], weights=candidates[:, 1].astype(float), minlength=180)
    histogram = np.convolve(np.r_[histogram[-2:], histogram, histogram[:2]], np.ones(5), "valid")
    peak = int(np.argmax(histogram))
    for hsv, outlier, confident in outliers_hsv:
        is_line = confident | (outlier & (hue_distance(hsv[:, 0], [peak]) <= HUE_WINDOW))
        line.append(hsv[is_line])
        floor.append(hsv[~is_line & ~outlier])
    return line, np.vstack(floor)


def lower_threshold(line_values, floor_values, highest: int = 255) -> int:
    """The lower bound of one channel: the t in 0..255 minimising (line values below t) / line
    + (floor values >= t) / floor, the two-class split with each class weighted equally; but no
    higher than `highest`, and, where no floor pixel competes, the line's 2nd percentile less
    LOWER_MARGIN (dark or grey pixels of the right hue, whose hue is noise, stay out)."""
    line_counts = np.bincount(line_values, minlength=256)[:256]
    floor_counts = np.bincount(floor_values, minlength=256)[:256]
    line_below = np.r_[0.0, np.cumsum(line_counts)[:-1]] / max(len(line_values), 1)
    floor_below = np.r_[0.0, np.cumsum(floor_counts)[:-1]] / max(len(floor_values), 1)
    split = int(np.argmin(line_below + (1.0 - floor_below)))
    return max(min(split, highest), int(np.percentile(line_values, 2)) - LOWER_MARGIN, 0)


def kept_in_every_frame(per_frame, channel) -> int:
    """The highest lower bound on `channel` that keeps LINE_KEPT of the target's pixels in every
    sampled frame with a target: a line or ball in a shadow in a few frames is still one."""
    frames = [f[:, channel] for f in per_frame if len(f) >= MIN_LINE_PIXELS]
    return int(min((np.percentile(f, 100 * (1 - LINE_KEPT)) for f in frames), default=255))


def saturation_and_value_floors(per_frame, background) -> tuple[int, int]:
    """s_min and v_min splitting the target's HSV pixels (Nx3 per sampled frame) from the
    background's of the target's hue. Saturation: the split alone (paint keeps its saturation
    in a shadow, and a white line a cast tints is among the outliers, low in saturation);
    value: no higher than what keeps the target in every frame (a shadowed one is darker)."""
    target = np.vstack(per_frame)
    s_min = lower_threshold(target[:, 1], background[:, 1])
    saturated = [f[f[:, 1] >= s_min] for f in per_frame]
    v_highest = kept_in_every_frame(saturated, 2)
    in_box = background[:, 1] >= s_min
    return s_min, lower_threshold(
        target[target[:, 1] >= s_min, 2], background[in_box, 2], v_highest
    )


def fit_line_colours(samples) -> dict | None:
    """h_min, h_max, s_min, s_max, v_min, v_max (cfg/Follower.cfg's names) fitted to the sampled
    bands, or None when no line-coloured pixels stand out."""
    per_frame, floor = line_and_floor_pixels(samples)
    if sum(len(f) >= MIN_LINE_PIXELS for f in per_frame) == 0:
        return None
    line = np.vstack(per_frame)
    h_min, h_max = np.percentile(line[:, 0], [1, 99])
    h_min, h_max = max(0, int(h_min) - HUE_MARGIN), min(179, int(math.ceil(h_max)) + HUE_MARGIN)
    in_hue = (floor[:, 0] >= h_min) & (floor[:, 0] <= h_max)
    s_min, v_min = saturation_and_value_floors(per_frame, floor[in_hue])
    return {
        "h_min": h_min, "h_max": h_max, "s_min": s_min, "s_max": 255, "v_min": v_min, "v_max": 255,
    }  # fmt: skip


def fit_beacon_colours(samples, centres) -> dict | None:
    """sensitivity, s_min, v_min (cfg/BeaconChaser.cfg's names, shared by every colour) fitted
    to the sampled frames, or None without a beacon found confidently. The hue half-width
    covers the hues of the confident beacons (the insides of their circles) around their
    colours' centres, short of the next colour's window; the beacons' pixels are theirs and,
    in every frame, the colour outliers (colour_outliers) in that window: a ball the default
    thresholds miss still stands out of the room's colour."""
    labelled = []
    for pixels, mask in samples:
        hsv, outlier = colour_outliers(pixels)
        labels = mask.reshape(-1) if mask is not None else np.zeros(len(hsv), np.uint8)
        labelled.append((hsv, outlier, labels))
    seeds = [hsv[labels == 255] for hsv, _, labels in labelled]
    if sum(len(f) >= MIN_LINE_PIXELS for f in seeds) == 0:
        return None
    pairs = itertools.combinations(centres, 2)
    gap = min((hue_distance(np.array([a]), [b])[0] for a, b in pairs), default=HUE_COUNT)
    spread = int(math.ceil(np.percentile(hue_distance(np.vstack(seeds)[:, 0], centres), 99)))
    sensitivity = min(spread + HUE_MARGIN, (gap - 1) // 2)
    per_frame, background = [], []
    for hsv, outlier, labels in labelled:
        in_hue = hue_distance(hsv[:, 0], centres) <= sensitivity
        is_beacon = (labels == 255) | (outlier & in_hue & (labels == 0))
        per_frame.append(hsv[is_beacon])
        background.append(hsv[~is_beacon & ~outlier & in_hue & (labels == 0)])
    s_min, v_min = saturation_and_value_floors(per_frame, np.vstack(background))
    return {"sensitivity": sensitivity, "s_min": s_min, "v_min": v_min}


# The follower's ~params its nodelet maps itself (the colour box and the bands); every other one
# sets a field that a core's CFG_FIELDS lists (the C++ field lists the nodelets expand too).
BOX_AND_BAND_PARAMS = ("h_min", "h_max", "s_min", "s_max", "v_min", "v_max", "band_distance",
                       "band_rows", "look_ahead_distance")  # fmt: skip
COLOUR_PARAMS = ("sensitivity", "s_min", "v_min")  # the beacon chaser's, every colour's
FITTED_BEHAVIOURS = ("follower", "beacons")


def cfg_params(*config_types) -> set:
    """The ~params that set fields of these core config classes."""
    return {param for config_type in config_types for _, param, _ in config_type.CFG_FIELDS}


def known_params(core, behaviour) -> set:
    """The ~params a replay of `behaviour` applies."""
    if behaviour == "follower":
        return {*BOX_AND_BAND_PARAMS, "mode",
                *cfg_params(core.LineDetectorConfig, core.SteeringConfig, core.PdConfig,
                            core.LineSearchConfig, core.PathConfig)}  # fmt: skip
    return {*COLOUR_PARAMS, "roundness_tolerance", *cfg_params(core.ColourBlobConfig)}


def set_from_params(config, params: dict):
    """Sets each field of `config` that a ~param in `params` sets, scaled to its unit."""
    for name, param, scale in type(config).CFG_FIELDS:
        if param in params:
            value = params[param]
            setattr(config, name, value if scale == 1.0 else value * scale)
    return config


def detector_config_with(core, params: dict):
    """core.LineDetectorConfig of follower ~params (cfg/Follower.cfg names; missing: default),
    as the follower nodelet maps them."""
    config = core.LineDetectorConfig()
    lower, upper = config.lower, config.upper
    config.lower = core.HsvColor(
        params.get("h_min", lower.h), params.get("s_min", lower.s), params.get("v_min", lower.v)
    )
    config.upper = core.HsvColor(
        params.get("h_max", upper.h), params.get("s_max", upper.s), params.get("v_max", upper.v)
    )
    rows = params.get("band_rows", config.band.rows)
    distance = params.get("band_distance", config.band.distance_m)
    config.band = core.BandConfig(distance_m=distance, rows=rows)
    ahead = params.get("look_ahead_distance", config.look_ahead.distance_m)
    config.look_ahead = core.BandConfig(distance_m=ahead, rows=rows)
    return set_from_params(config, params)


def beacon_config_with(core, params: dict):
    """core.ColourBlobConfig of beacon chaser ~params (cfg/BeaconChaser.cfg names; missing:
    default), as the beacon chaser nodelet maps them to its detector."""
    config = core.ColourBlobConfig()
    colours = config.colours
    for spec in colours:
        for name in COLOUR_PARAMS:
            setattr(spec, name, params.get(name, getattr(spec, name)))
    config.colours = colours
    config.roundness_tolerance = params.get("roundness_tolerance", config.roundness_tolerance)
    return set_from_params(config, params)


def steering_config_with(core, params: dict):
    """core.SteeringConfig of follower ~params, as the follower nodelet maps them."""
    config = set_from_params(core.SteeringConfig(), params)
    if "mode" in params:
        config.mode = params["mode"]
    config.pd = set_from_params(config.pd, params)
    config.search = set_from_params(config.search, params)
    config.path = set_from_params(config.path, params)
    return config


def load_params(path, behaviour="follower") -> dict:
    """The behaviour's ~params in a YAML file (unknown names: ValueError naming them)."""
    import yaml

    from follow_bot import core

    params = yaml.safe_load(Path(path).read_text()) or {}
    if behaviour not in FITTED_BEHAVIOURS:
        raise ValueError(f"--params: the {behaviour} replay takes none")
    unknown = sorted(set(params) - known_params(core, behaviour))
    if unknown:
        raise ValueError(f"{path}: not {behaviour} parameters: {', '.join(unknown)}")
    return params


def write_params(path, fitted: dict, comment: str):
    """A YAML of ~params for `rosparam load FILE /NODE` or the node's launch params:=FILE."""
    lines = [f"# {line}" for line in comment.splitlines()]
    lines += [f"{name}: {value}" for name, value in fitted.items()]
    Path(path).write_text("\n".join(lines) + "\n")


# ---- the command -------------------------------------------------------------------------------


def parse_args(argv):
    parser = argparse.ArgumentParser(
        prog="rosrun follow_bot inspect",
        description=__doc__.split("\n\n", 1)[1],
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="Needs no ROS master. Manual: follow_bot/doc/robot.md, 'On a real robot'.",
    )
    parser.add_argument("bag", type=Path, help="the recording (.bag)")
    parser.add_argument("--behaviour", choices=BEHAVIOURS, default="follower")
    parser.add_argument("--out", type=Path, help="report folder (default: BAG's name + _report)")
    parser.add_argument(
        "--fit-colours",
        action="store_true",
        help="fit the colour thresholds to the bag (follower: the line's band; beacons: "
        "sensitivity, s_min, v_min) and write fitted_params.yaml",
    )
    parser.add_argument(
        "--params",
        type=Path,
        help="a YAML of the behaviour's ~params (cfg/Follower.cfg or cfg/BeaconChaser.cfg "
        "names, e.g. a fitted_params.yaml) to replay with instead of the defaults",
    )
    parser.add_argument("--image-topic", help="default: the bag's busiest image topic")
    parser.add_argument("--cmd-vel-topic", help="default: the bag's busiest Twist topic")
    parser.add_argument(
        "--camera-height",
        type=float,
        help="m; default: tf_static, else the " "nodes' default mounting",
    )
    parser.add_argument("--camera-pitch-deg", type=float, help="down positive; as above")
    parser.add_argument("--sheet-frames", type=int, default=SHEET_FRAMES)
    return parser.parse_args(argv)


def bag_mounting(bag_path, topics, args):
    """(height, pitch, x offset) from the arguments, else the bag's tf_static, else None (the
    default), and where it came from."""
    import rosbag

    found, source = None, "default (no tf_static)"
    if topics.tf_static:
        with rosbag.Bag(str(bag_path)) as bag:
            transforms = [
                t for _, m, _ in bag.read_messages([topics.tf_static]) for t in m.transforms
            ]
            frame = next((m.header.frame_id for _, m, _ in bag.read_messages([topics.image])), "")
        found, why = mounting_from_tf(transforms, frame)
        source = "tf_static" if found else f"default ({why})"
    if args.camera_height is not None or args.camera_pitch_deg is not None:
        from follow_bot import core

        default = core.CameraGeometry()
        h, pitch, x = found or (default.height_m, default.pitch_rad, default.x_offset_m)
        if args.camera_height is not None:
            h = args.camera_height
        if args.camera_pitch_deg is not None:
            pitch = math.radians(args.camera_pitch_deg)
        found, source = (h, pitch, x), "arguments"
    return found, source


def make_replay(core, behaviour, mounting, params=None):
    """make_behaviour(camera_info, frame shape) for replay(); `params`: the behaviour's ~params."""

    def make(info, shape):
        camera = camera_from(core, info, shape, mounting)
        if behaviour == "follower":
            return FollowerReplay(
                core, camera, detector_config_with(core, params or {}),
                steering_config_with(core, params or {}),
            )  # fmt: skip
        if behaviour == "beacons":
            return BeaconsReplay(core, camera, beacon_config_with(core, params or {}))
        return ParkerReplay(core, camera)

    return make


def inspect(bag_path, out, behaviour="follower", fit_colours=False, args=None) -> dict:
    """Writes the report into `out`; returns report.json's figures."""
    import rosbag

    from follow_bot import core

    args = args or parse_args([str(bag_path)])
    out.mkdir(parents=True, exist_ok=True)
    with rosbag.Bag(str(bag_path)) as bag:
        topics = pick_topics(bag, args.image_topic, args.cmd_vel_topic)
    mounting, mounting_source = bag_mounting(bag_path, topics, args)
    params = load_params(args.params, behaviour) if args.params else {}
    if fit_colours and behaviour not in FITTED_BEHAVIOURS:
        raise ValueError("--fit-colours fits the follower's line band or the beacons' colours")
    sample_every = max(1, math.ceil(topics.frames / FIT_SAMPLES)) if fit_colours else 0
    first, replayed = replay(
        core, bag_path, topics, make_replay(core, behaviour, mounting, params), (), sample_every
    )
    chosen = worst_frames(first.records, args.sheet_frames)
    second, _ = replay(
        core,
        bag_path,
        topics,
        make_replay(core, behaviour, mounting, params),
        {i for i, _ in chosen},
    )
    figures = {
        "bag": str(bag_path),
        "behaviour": behaviour,
        **summary(first.records, topics, first),
    }
    camera = replayed.camera
    figures["camera"] = {
        "mounting": mounting_source,
        "height_m": round(camera.height_m, 4),
        "pitch_deg": round(math.degrees(camera.pitch_rad), 2),
        "x_offset_m": round(camera.x_offset_m, 4),
        "fx": round(camera.fx, 2),
        "cx": round(camera.cx, 2),
        "cy": round(camera.cy, 2),
    }
    fitted_records = None
    if fit_colours:
        fitted = replayed.fit(first.samples)
        fit = {
            "sampled_frames": len(first.samples),
            "detection_rate_before": figures["detection_rate"],
        }
        if fitted is None:
            fit["error"] = (
                "no line-coloured pixels stand out of the floor in the band"
                if behaviour == "follower"
                else "no beacon found confidently (a circle of radius "
                f"{CONFIDENT_RADIUS} px or more) to fit to"
            )
        else:
            after, _ = replay(
                core, bag_path, topics, make_replay(core, behaviour, mounting, {**params, **fitted})
            )
            fitted_records = after.records
            found_after = sum(r["found"] for r in after.records)
            rate = found_after / len(after.records)
            fit.update(parameters=fitted, detection_rate_after=round(rate, 4))
            # Thresholds that find the target in fewer frames than the ones replayed are no advice.
            fit["better"] = found_after >= sum(r["found"] for r in first.records)
            fit["file"] = str(out / "fitted_params.yaml")
            node, what = NODES[behaviour]
            write_params(
                fit["file"],
                fitted,
                (
                    f"The {node}'s {what}, fitted by `inspect --fit-colours` to\n"
                    f"{bag_path.name} ({len(first.records)} frames): detection rate "
                    f"{fit['detection_rate_before']:.3f} before, {rate:.3f} after.\n"
                    f"Load: rosparam load {Path(fit['file']).name} /{node}, or {node}.launch "
                    f"params:={Path(fit['file']).name}"
                ),
            )
        figures["fit"] = fit
    plot_timeline(
        out / "timeline.png",
        first.records,
        f"{bag_path.name}: {behaviour}, "
        f"{figures['frames']} frames, detection rate {figures['detection_rate']:.3f}",
        fitted_records,
    )
    contact_sheet(out / "worst_frames.png", replayed, second.kept, chosen, first.records)
    figures["worst_frames"] = [{"frame": i, "why": why} for i, why in chosen]
    figures["files"] = {name: str(out / name) for name in ("timeline.png", "worst_frames.png")}
    figures["records"] = first.records
    (out / "report.json").write_text(json.dumps(figures, indent=1))
    return figures


def main(argv=None) -> int:
    args = parse_args(sys.argv[1:] if argv is None else argv)
    try:
        import matplotlib  # checked here, used by plot_timeline
    except ImportError:
        matplotlib = None
    if cv2 is None or matplotlib is None:
        print(MISSING_LIBRARIES, file=sys.stderr)
        return 1
    out = args.out or args.bag.with_name(args.bag.stem + "_report")
    try:
        figures = inspect(args.bag, out, args.behaviour, args.fit_colours, args)
    except (ValueError, OSError) as error:
        print(f"inspect: {error}", file=sys.stderr)
        return 2
    print(
        f"{args.bag}: {figures['frames']} frames of {figures['image_topic']}, detection rate "
        f"{figures['detection_rate']:.3f}, {len(figures['lost_spans'])} lost spans "
        f"(longest {figures['longest_lost_s']:.2f} s)"
    )
    if "fit" in figures:
        fit = figures["fit"]
        if "error" in fit:
            print(f"colour fit: {fit['error']}")
        else:
            if not fit["better"]:
                print("colour fit: WORSE than the parameters replayed; keep yours")
            print(
                f"colour fit: detection rate {fit['detection_rate_before']:.3f} -> "
                f"{fit['detection_rate_after']:.3f}; {fit['parameters']} in {fit['file']}"
            )
    print(f"report: {out}/report.json, timeline.png, worst_frames.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
