"""World files: load a world YAML (see worlds/SCHEMA.md) into harness.world's validated
dataclasses.

Every field is checked here so that a typo in a world file fails at load time with the
field path in the message, instead of as a numpy or OpenCV error deep inside rendering.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import yaml

from harness.camera import LENSES, PINHOLE, Camera
from harness.geometry import Arc, Straight, densify_polyline, trace_segments, wrap_angle
from harness.realism import parse_realism, realism_from
from harness.validation import (
    Fields,
    Parser,
    ValidationError,
    bgr_colour,
    boolean,
    describe,
    integer,
    join_path,
    number,
    sequence,
    string,
    vector,
)
from harness.world import (
    WORLDS_DIR,
    AprilTagMarker,
    Box,
    CameraTransport,
    Ground,
    GroundTexture,
    Lighting,
    Line,
    Noise,
    RobotConfig,
    Sphere,
    TextureMarker,
    World,
    WorldError,
    WorldObject,
    package_dir,
)

PACKAGE_URL = "package://"
# Sample spacing of line centrelines; the texture and the scoring use the same samples.
CENTRELINE_SPACING = 0.01
# Largest ground texture side, to keep memory and warp cost bounded.
MAX_GROUND_PIXELS = 8000
# Number of codes per supported AprilTag family (checked again against the library).
TAG_FAMILY_CODES = {"tag36h11": 587}
# A traced closed path must end this close to its start.
_CLOSE_TOL_M = 1e-3
_CLOSE_TOL_RAD = 1e-3
TRANSPORTS = ("raw", "compressed")
_TRANSPORT_FIELDS = {"transport", "jpeg_quality"}
_POSITIVE = number(gt=0.0)
_ANY = number()


def parse_camera_transport(value: Any, where: str) -> CameraTransport:
    """A `{transport, jpeg_quality}` mapping (fields of a world's `camera` or a scenario's
    `camera_transport`)."""
    f = Fields(value, where, {"transport", "jpeg_quality"})
    name = f.get("transport", string, "raw")
    if name not in TRANSPORTS:
        raise WorldError(f"{f.where('transport')}: must be one of {', '.join(TRANSPORTS)}")
    quality = f.get("jpeg_quality", integer(ge=1), 80)
    if quality > 100:
        raise WorldError(f"{f.where('jpeg_quality')}: must be at most 100, got {quality}")
    return CameraTransport(name, quality)


def _image_file(base_dir: Path) -> Parser:
    def parse(value: Any, where: str) -> tuple[Path, np.ndarray]:
        name = string(value, where)
        if name.startswith(PACKAGE_URL):  # package://<package>/<path>: another package's file
            package, _, relative = name[len(PACKAGE_URL) :].partition("/")
            path = package_dir(package) / relative
        else:
            path = base_dir / name
        image = cv2.imread(str(path), cv2.IMREAD_COLOR) if path.is_file() else None
        if image is None:
            raise WorldError(f"{where}: cannot read image file {str(path)!r}")
        return path, image

    return parse


def _parse_segment(value: Any, where: str) -> Straight | Arc:
    f = Fields(value, where, {"straight", "radius", "turn_deg"})
    if f.has("straight"):
        if f.has("radius") or f.has("turn_deg"):
            raise WorldError(f"{where}: give either 'straight' or 'radius' + 'turn_deg', not both")
        return Straight(f.get("straight", _POSITIVE))
    if not f.has("radius") and not f.has("turn_deg"):
        raise WorldError(f"{where}: needs 'straight' or 'radius' + 'turn_deg'")
    turn = f.get("turn_deg", _ANY)
    if turn == 0.0:
        raise WorldError(f"{f.where('turn_deg')}: must be non-zero (use 'straight')")
    return Arc(f.get("radius", _POSITIVE), math.radians(turn))


def _parse_line(value: Any, where: str) -> Line:
    f = Fields(value, where, {"width", "colour", "closed", "points", "start", "segments"})
    width = f.get("width", _POSITIVE, 0.05)
    colour = f.get("colour", bgr_colour, (0, 220, 255))
    closed = f.get("closed", boolean, False)
    if f.has("points") == f.has("segments"):
        raise WorldError(f"{where}: give exactly one of 'points' or 'start' + 'segments'")
    if f.has("points"):
        if f.has("start"):
            raise WorldError(f"{f.where('start')}: only used with 'segments'")
        raw = sequence(f.data["points"], f.where("points"), min_len=2)
        pts = np.array([vector(2)(p, join_path(f.where("points"), i)) for i, p in enumerate(raw)])
        if closed and np.allclose(pts[0], pts[-1], atol=1e-9):
            pts = pts[:-1]
        if np.any(np.hypot(*np.diff(pts, axis=0).T) == 0.0):
            raise WorldError(f"{f.where('points')}: consecutive points must differ")
        return Line(densify_polyline(pts, closed, CENTRELINE_SPACING), width, colour, closed)
    start: tuple[float, float, float] = f.get("start", vector(3))
    seg_where = f.where("segments")
    raw = sequence(f.data["segments"], seg_where, min_len=1)
    segments = [_parse_segment(s, join_path(seg_where, i)) for i, s in enumerate(raw)]
    pts, end = trace_segments(start, segments, CENTRELINE_SPACING)
    if closed:
        gap = math.hypot(end[0] - start[0], end[1] - start[1])
        turn = abs(float(wrap_angle(end[2] - start[2])))
        if gap > _CLOSE_TOL_M or turn > _CLOSE_TOL_RAD:
            raise WorldError(
                f"{seg_where}: closed path ends {gap:.3f} m and {math.degrees(turn):.1f} deg away "
                f"from its start (end pose {end[0]:.3f}, {end[1]:.3f}, "
                f"{math.degrees(end[2]):.1f} deg)"
            )
        pts = pts[:-1]
    return Line(pts, width, colour, closed)


def _parse_ground(value: Any, where: str, base_dir: Path) -> Ground:
    f = Fields(value, where, {"size", "origin", "colour", "metres_per_pixel", "lines", "texture"})
    size = f.get("size", vector(2, _POSITIVE))
    origin = f.get("origin", vector(2), (-size[0] / 2.0, -size[1] / 2.0))
    mpp = f.get("metres_per_pixel", _POSITIVE, 0.005)
    if max(size) / mpp > MAX_GROUND_PIXELS:
        raise WorldError(
            f"{f.where('metres_per_pixel')}: {mpp:g} m/px gives a texture side of "
            f"{max(size) / mpp:.0f} px; the limit is {MAX_GROUND_PIXELS}"
        )
    lines_where = f.where("lines")
    raw_lines = sequence(f.data.get("lines", []), lines_where)
    lines = tuple(_parse_line(v, join_path(lines_where, i)) for i, v in enumerate(raw_lines))
    texture = None
    if f.has("texture"):
        t = Fields(f.data["texture"], f.where("texture"), {"image", "metres_per_pixel", "origin"})
        path, image = t.get("image", _image_file(base_dir))
        texture = GroundTexture(
            path, image, t.get("metres_per_pixel", _POSITIVE), t.get("origin", vector(2), origin)
        )
    colour = f.get("colour", bgr_colour, (120, 120, 120))
    return Ground(size, origin, colour, mpp, lines, texture)


def _parse_marker_pose(f: Fields, board_height: float) -> tuple[float, float, float, float]:
    pose = f.get("pose", vector(4))
    if pose[2] - board_height / 2.0 < 0.0:
        raise WorldError(
            f"{f.where('pose')}[2]: centre height {pose[2]:g} m puts the board's lower edge "
            f"below the floor (board height {board_height:g} m)"
        )
    return pose


def _parse_object(value: Any, where: str, base_dir: Path, index: int) -> WorldObject:
    if not isinstance(value, dict):
        raise WorldError(f"{where}: must be a mapping, got {describe(value)}")
    kinds = ("apriltag", "box", "sphere", "texture")
    if "kind" not in value:
        raise WorldError(f"{where}.kind: missing required field (one of: {', '.join(kinds)})")
    kind = value["kind"]
    if kind not in kinds:
        raise WorldError(
            f"{where}.kind: unknown object kind {kind!r} (expected one of: {', '.join(kinds)})"
        )
    common = {"kind", "name"}
    if kind == "sphere":
        f = Fields(value, where, common | {"colour", "radius", "position"})
        return Sphere(
            f.get("name", string, f"sphere{index}"),
            f.get("colour", bgr_colour),
            f.get("radius", _POSITIVE),
            f.get("position", vector(3)),
        )
    if kind == "box":
        f = Fields(value, where, common | {"colour", "size", "pose"})
        name = f.get("name", string, f"box{index}")
        return Box(
            name,
            f.get("colour", bgr_colour),
            f.get("size", vector(3, _POSITIVE)),
            f.get("pose", vector(3)),
        )
    marker_fields = common | {"pose", "post"}
    if kind == "apriltag":
        f = Fields(value, where, marker_fields | {"family", "id", "size", "margin"})
        family = f.get("family", string, "tag36h11")
        if family not in TAG_FAMILY_CODES:
            raise WorldError(
                f"{f.where('family')}: unsupported family {family!r} "
                f"(supported: {', '.join(TAG_FAMILY_CODES)})"
            )
        tag_id = f.get("id", integer(ge=0))
        if tag_id >= TAG_FAMILY_CODES[family]:
            raise WorldError(
                f"{f.where('id')}: {family} has ids 0..{TAG_FAMILY_CODES[family] - 1}, got {tag_id}"
            )
        size = f.get("size", _POSITIVE)
        margin = f.get("margin", number(ge=0.0), size / 4.0)
        pose = _parse_marker_pose(f, size + 2.0 * margin)
        name = f.get("name", string, f"tag{tag_id}")
        post = f.get("post", boolean, True)
        return AprilTagMarker(name, family, tag_id, size, margin, pose, post)
    f = Fields(value, where, marker_fields | {"image", "width"})
    path, image = f.get("image", _image_file(base_dir))
    width = f.get("width", _POSITIVE)
    pose = _parse_marker_pose(f, width * image.shape[0] / image.shape[1])
    name = f.get("name", string, f"texture{index}")
    return TextureMarker(name, path, image, width, pose, f.get("post", boolean, True))


def _parse_lighting(value: Any, where: str) -> Lighting:
    f = Fields(value, where, {"gain", "ambient", "direction", "shadows"})
    direction = np.array(f.get("direction", vector(3), (-0.5, 0.3, 1.0)))
    if direction[2] <= 0.0:
        raise WorldError(f"{f.where('direction')}[2]: light must come from above (z > 0)")
    direction /= np.linalg.norm(direction)
    return Lighting(
        f.get("gain", number(ge=0.0), 1.0),
        f.get("ambient", number(ge=0.0, le=1.0), 0.6),
        (float(direction[0]), float(direction[1]), float(direction[2])),
        f.get("shadows", boolean, True),
    )


def _parse_noise(value: Any, where: str) -> Noise:
    f = Fields(value, where, {"sigma", "seed"})
    return Noise(f.get("sigma", number(ge=0.0), 0.0), f.get("seed", integer(ge=0), 0))


def _parse_robot(value: Any, where: str) -> RobotConfig:
    f = Fields(value, where, {"start", "max_v", "max_w", "delay_steps"})
    return RobotConfig(
        f.get("start", vector(3), (0.0, 0.0, 0.0)),
        f.get("max_v", _POSITIVE, 0.7),
        f.get("max_w", _POSITIVE, math.pi),
        f.get("delay_steps", integer(ge=0), 0),
    )


def _camera_fields(value: Any, transport: bool) -> Any:
    """The transport fields of a world's `camera` mapping (or all the others)."""
    if not isinstance(value, dict):
        return value  # Fields names the error
    return {k: v for k, v in value.items() if (k in _TRANSPORT_FIELDS) == transport}


def _parse_camera(value: Any, where: str) -> Camera:
    allowed = {"width", "height", "hfov_deg", "height_m", "pitch_deg", "x_offset_m", "distortion"}
    f = Fields(_camera_fields(value, transport=False), where, allowed)
    hfov = f.get("hfov_deg", number(gt=0.0, lt=180.0), math.degrees(Camera.hfov))
    pitch = f.get("pitch_deg", number(gt=-89.0, lt=89.0), math.degrees(Camera.pitch))
    return Camera(
        width=f.get("width", integer(ge=16), Camera.width),
        height=f.get("height", integer(ge=16), Camera.height),
        hfov=math.radians(hfov),
        height_m=f.get("height_m", _POSITIVE, Camera.height_m),
        pitch=math.radians(pitch),
        x_offset_m=f.get("x_offset_m", _ANY, Camera.x_offset_m),
        distortion=f.get("distortion", parse_distortion, PINHOLE),
    )


def parse_distortion(value: Any, where: str) -> tuple[float, float, float, float, float]:
    """A plumb_bob lens: [k1, k2, p1, p2, k3] or a name from camera.LENSES."""
    if isinstance(value, str):
        if value not in LENSES:
            raise WorldError(f"{where}: unknown lens {value!r} (known: {', '.join(LENSES)})")
        return LENSES[value]
    return vector(5, number())(value, where)


def _parse_world_document(data: Any, base_dir: Path, source: Path | None) -> World:
    base = base_dir
    sections = {"name", "background", "ground", "objects", "lighting", "noise", "robot", "camera"}
    top = Fields(data, "", sections | {"realism"})
    raw_objects = sequence(top.data.get("objects", []), "objects")
    objects = tuple(
        _parse_object(v, join_path("objects", i), base, i) for i, v in enumerate(raw_objects)
    )
    names = [o.name for o in objects]
    for i, name in enumerate(names):
        if name in names[:i]:
            raise WorldError(f"objects[{i}].name: duplicate object name {name!r}")
    noise = top.section("noise", _parse_noise)
    return World(
        name=top.get("name", string),
        background=top.get("background", bgr_colour, (200, 200, 200)),
        ground=top.get("ground", lambda v, w: _parse_ground(v, w, base)),
        objects=objects,
        lighting=top.section("lighting", _parse_lighting),
        noise=noise,
        robot=top.section("robot", _parse_robot),
        camera=top.section("camera", _parse_camera),
        camera_transport=top.section(
            "camera", lambda v, w: parse_camera_transport(_camera_fields(v, transport=True), w)
        ),
        source=source,
        # A world's ranges are drawn from its noise seed (a scenario's from the run's seed).
        realism=realism_from(top.section("realism", parse_realism), seed=noise.seed),
    )


def parse_world(data: Any, base_dir: Path | str = ".", source: Path | None = None) -> World:
    """Validate an already-parsed YAML document; image paths are relative to `base_dir`."""
    try:
        return _parse_world_document(data, Path(base_dir), source)
    except WorldError:
        raise
    except ValidationError as error:  # raised by a shared primitive: same message, our type
        raise WorldError(str(error)) from None


def resolve_world_path(name: str, base_dir: Path | str | None = None) -> Path:
    """A world file by path, or by name from the worlds/ folder (e.g. "course")."""
    candidates = [Path(name)]
    if base_dir is not None:
        candidates.append(Path(base_dir) / name)
    candidates += [WORLDS_DIR / name, WORLDS_DIR / f"{name}.yaml"]
    for candidate in candidates:
        if candidate.is_file():
            return candidate.resolve()
    raise WorldError(f"no world file {name!r} (looked in {', '.join(map(str, candidates))})")


def load_world(path: Path | str) -> World:
    """Load and validate a world YAML file; raises WorldError on any problem."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except OSError as exc:
        raise WorldError(f"{p}: cannot read world file: {exc.strerror}") from None
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise WorldError(f"{p}: invalid YAML: {exc}") from None
    return parse_world(data, p.parent, source=p)
