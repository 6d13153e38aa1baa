"""The world a scenario plays in, as validated dataclasses: the floor and its lines, objects,
lighting, noise, the robot and its camera (harness.world_file loads them from a world YAML,
worlds/SCHEMA.md).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import rospkg

from harness.camera import Camera
from harness.realism import Realism
from harness.validation import (
    Colour,
    ValidationError,
)


def package_dir(name: str) -> Path:
    """Package `name` as `$(find name)` finds it in a devel or an install space; outside any ROS
    environment, its folder in the source tree."""
    try:
        return Path(rospkg.RosPack().get_path(name))
    except rospkg.ResourceNotFound:
        return Path(__file__).resolve().parents[3] / name


# The shipped worlds: the `worlds` package.
WORLDS_DIR = package_dir("worlds")


class WorldError(ValidationError):
    """A world file is malformed; the message starts with the offending field path."""


@dataclass(frozen=True)
class Line:
    """Painted floor line: `points` is its dense centreline (closing point not repeated)."""

    points: np.ndarray = field(repr=False, compare=False)
    width: float
    colour: Colour
    closed: bool


@dataclass(frozen=True)
class GroundTexture:
    """Image pasted onto the floor; `origin` is the world (x, y) of its lower-left corner."""

    path: Path
    image: np.ndarray = field(repr=False, compare=False)
    metres_per_pixel: float
    origin: tuple[float, float]


@dataclass(frozen=True)
class Ground:
    """Floor rectangle [origin, origin + size] rendered at `metres_per_pixel`."""

    size: tuple[float, float]
    origin: tuple[float, float]
    colour: Colour
    metres_per_pixel: float
    lines: tuple[Line, ...]
    texture: GroundTexture | None


@dataclass(frozen=True)
class Sphere:
    name: str
    colour: Colour
    radius: float
    position: tuple[float, float, float]


@dataclass(frozen=True)
class Box:
    """Box standing on the floor; size is (length along yaw, width, height)."""

    name: str
    colour: Colour
    size: tuple[float, float, float]
    pose: tuple[float, float, float]


@dataclass(frozen=True)
class AprilTagMarker:
    """Vertical AprilTag board; pose is (x, y, z of the centre, yaw of the facing normal)."""

    name: str
    family: str
    tag_id: int
    size: float  # edge of the black square, the tag size used by pose estimation
    margin: float  # white margin beyond the black square
    pose: tuple[float, float, float, float]
    post: bool

    @property
    def board_size(self) -> tuple[float, float]:
        edge = self.size + 2.0 * self.margin
        return edge, edge


@dataclass(frozen=True)
class TextureMarker:
    """Vertical picture board; its height follows the image aspect ratio."""

    name: str
    path: Path | None  # the image file; None for a generated picture (realism's posters)
    image: np.ndarray = field(repr=False, compare=False)
    width: float
    pose: tuple[float, float, float, float]
    post: bool

    @property
    def board_size(self) -> tuple[float, float]:
        h, w = self.image.shape[:2]
        return self.width, self.width * h / w


WorldObject = Sphere | Box | AprilTagMarker | TextureMarker


@dataclass(frozen=True)
class Lighting:
    """Global gain, ambient fraction and a unit vector pointing towards the light."""

    gain: float
    ambient: float
    direction: tuple[float, float, float]
    shadows: bool


@dataclass(frozen=True)
class Noise:
    sigma: float  # grey levels, Gaussian, per channel
    seed: int


@dataclass(frozen=True)
class RobotConfig:
    start: tuple[float, float, float]
    max_v: float
    max_w: float
    delay_steps: int


@dataclass(frozen=True)
class CameraTransport:
    """How the simulator publishes its frames: `raw` sensor_msgs/Image on camera/rgb/image_raw,
    or `compressed` JPEG sensor_msgs/CompressedImage on camera/rgb/image_raw/compressed."""

    name: str = "raw"
    jpeg_quality: int = 80


@dataclass(frozen=True)
class World:
    name: str
    background: Colour
    ground: Ground
    objects: tuple[WorldObject, ...]
    lighting: Lighting
    noise: Noise
    robot: RobotConfig
    camera: Camera
    camera_transport: CameraTransport = field(default_factory=CameraTransport)
    source: Path | None = None
    realism: Realism = field(default_factory=Realism)

    def centreline(self, index: int = 0) -> np.ndarray:
        """Dense centreline (Nx2, metres) of floor line `index`, as drawn in the texture."""
        lines = self.ground.lines
        if not 0 <= index < len(lines):
            raise WorldError(f"ground.lines[{index}]: world '{self.name}' has {len(lines)} lines")
        return lines[index].points
