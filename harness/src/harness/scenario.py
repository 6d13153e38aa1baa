"""Scenarios: what to run, what to disturb, what must hold (worlds/SCHEMA.md).

A scenario names a world, the behaviour to launch (or a built-in scripted driver), a duration
and stop condition, perturbations and pass criteria over the metrics of
harness.evaluation.metrics(). harness.scenario_parse validates one run's fields into a Scenario;
harness.scenario_file expands a family file into its runs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from harness.camera import Camera
from harness.simulation import Perturbations
from harness.validation import (
    ValidationError,
)
from harness.world import Box, CameraTransport, Sphere, World

STOP_CONDITIONS = ("duration", "lap_complete", "still")


# `stop_when: still` waits at least this long without motion: longer than a behaviour's hold
# while its target is briefly lost (the parker holds 2 s, then searches), so a pause is not an end.
STILL_STOP_S = 3.0


# A family's `measured` values bound each member at this multiple of its own measurement (or the
# family's stated noise floor, if larger), beside the specification's bounds.
MEASURED_FACTOR = 3.0

# Wall seconds a lockstep simulator waits for the behaviour's answer to a frame before it counts
# a miss (every lockstep run must have none). Generous: a run's result must not depend on the
# machine's load, and 2 s was exceeded by a sign parker's search on 2 cores running a suite and
# a sweep at once. Only a behaviour that does not answer costs the wait.
REPLY_TIMEOUT_S = 10.0


class ScenarioError(ValidationError):
    """A scenario file that cannot be run; the message names the offending field."""


@dataclass(frozen=True)
class Behaviour:
    package: str
    launch_file: str
    args: dict[str, str]


@dataclass(frozen=True)
class Criterion:
    metric: str  # dotted path into the metrics, e.g. "cross_track.rms" or "dropouts.0.stop_delay"
    minimum: float | None = None
    maximum: float | None = None
    equals: Any = None
    absolute: bool = False  # the bounds hold the value's magnitude (an error either way)

    def check(self, metrics: dict) -> tuple[Any, bool]:
        value: Any = metrics
        for key in self.metric.split("."):
            if isinstance(value, dict):
                value = value.get(key)
            elif isinstance(value, list) and key.isdigit() and int(key) < len(value):
                value = value[int(key)]
            else:
                value = None
        if self.equals is not None:
            return value, value == self.equals
        if not isinstance(value, int | float) or isinstance(value, bool):
            return value, False  # a metric that is absent or None never passes a bound
        bounded = abs(value) if self.absolute else value
        ok = math.isfinite(bounded)
        ok &= self.minimum is None or bounded >= self.minimum
        ok &= self.maximum is None or bounded <= self.maximum
        return value, bool(ok)

    def margin(self, value: Any) -> float | None:
        """How far inside its bounds `value` is, as a fraction of their scale (half the range
        between min and max, or the one bound's size): 1 = far in, 0 = on a bound, < 0 outside;
        an `equals` rule gives 1 or -1; None when there is no finite value to bound."""
        if self.equals is not None:
            return 1.0 if value == self.equals else -1.0
        if isinstance(value, bool) or not isinstance(value, int | float):
            return None
        if not math.isfinite(value):
            return None
        value = abs(value) if self.absolute else value
        if self.minimum is not None and self.maximum is not None:
            scale = (self.maximum - self.minimum) / 2.0
        else:
            bound = self.minimum if self.maximum is None else self.maximum
            assert bound is not None  # a criterion has at least one bound
            scale = abs(bound) or 1.0
        room = [value - self.minimum] if self.minimum is not None else []
        room += [self.maximum - value] if self.maximum is not None else []
        return min(room) / scale

    def describe(self) -> str:
        if self.equals is not None:
            return f"== {self.equals!r}"
        parts = []
        if self.minimum is not None:
            parts.append(f">= {self.minimum:g}")
        if self.maximum is not None:
            parts.append(f"<= {self.maximum:g}")
        return ("|value| " if self.absolute else "") + " and ".join(parts)


@dataclass(frozen=True)
class CameraMounting:
    """Where a scenario mounts the world's camera on the robot; None keeps the world's."""

    height_m: float | None = None  # optical centre above the floor
    pitch_deg: float | None = None  # tilt of the optical axis, positive looks down
    x_offset_m: float | None = None  # optical centre forward of the base origin

    def apply(self, camera: Camera) -> Camera:
        return replace(
            camera,
            height_m=camera.height_m if self.height_m is None else self.height_m,
            pitch=camera.pitch if self.pitch_deg is None else math.radians(self.pitch_deg),
            x_offset_m=camera.x_offset_m if self.x_offset_m is None else self.x_offset_m,
        )


@dataclass(frozen=True)
class Scenario:
    name: str
    world_path: Path
    start: tuple[float, float, float] | None
    behaviour: Behaviour | None
    constant_command: tuple[float, float] | None  # scripted driver when there is no behaviour
    rate_hz: float
    duration: float
    stop_when: str
    lockstep: bool
    reply_timeout: float  # wall seconds to wait for the behaviour's command in lockstep
    perturbations: Perturbations
    target: str | None  # object name for stop distance and bearing
    watch: str | None  # object whose coming into view must stop the robot (e.g. the red ball)
    goal: str | None  # marker name to park in front of
    standoff: float
    criteria: tuple[Criterion, ...]
    seed: int | None = None  # seeds the pixel noise (None: the world's noise seed)
    camera_transport: CameraTransport | None = None  # None: the world's
    camera_mounting: CameraMounting = field(default_factory=CameraMounting)  # over the world's
    robot: str | None = None  # a robot preset whose camera and limits replace the world's
    source: Path | None = None
    spec: dict = field(default_factory=dict, compare=False)  # the run's own fields, as parsed
    parameters: dict = field(default_factory=dict, compare=False)  # a sweep member's draws

    @property
    def spec_criteria(self) -> tuple[Criterion, ...]:
        """The criteria but the member's own bounds from its measured values (`regression`)."""
        return tuple(c for c in self.criteria if not c.absolute)

    @property
    def still_stop_s(self) -> float:
        """How long every command must have been zero before `stop_when: still` ends the run:
        as long as the criteria's still_since bounds demand at the end of the full `duration`
        (a bound of 22 s in a 25 s run: the last 3 s), so the early end judges the stop as the
        whole run would, and never less than STILL_STOP_S."""
        bounds = [
            c.maximum for c in self.criteria
            if c.metric.split(".")[-1] == "still_since" and c.maximum is not None
        ]  # fmt: skip
        return max([STILL_STOP_S, *(self.duration - bound for bound in bounds)])


def find_object(world: World, name: str, field: str):
    """The world's object called `name`; a ScenarioError naming `field` when there is none."""
    for obj in world.objects:
        if obj.name == name:
            return obj
    names = ", ".join(o.name for o in world.objects) or "none"
    raise ScenarioError(f"{field}: world '{world.name}' has no object {name!r} (objects: {names})")


def object_centre(obj) -> np.ndarray:
    """World [x, y, z] of an object's centre (a box's pose has no z: it stands on the floor)."""
    if isinstance(obj, Sphere):
        return np.asarray(obj.position, dtype=float)
    if isinstance(obj, Box):
        return np.array([obj.pose[0], obj.pose[1], obj.size[2] / 2.0])
    return np.asarray(obj.pose[:3], dtype=float)  # markers: [x, y, z, yaw]
