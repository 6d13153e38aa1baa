"""One simulated run, free of ROS: render the frame for step k, apply the command, record.

The rospy node (sim_node.py) only moves frames and commands between this class and topics, so
the same stepping is unit-tested without a roscore.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from harness.geometry import polyline_length
from harness.realism import Realism, barrel_distortion, realism_from, rng_for
from harness.render import Renderer
from harness.robot import Robot
from harness.scoring import progress
from harness.world import World


@dataclass(frozen=True)
class Perturbations:
    """What a scenario does to the world and the sensor, on top of the world file."""

    gain: float | None = None  # lighting gain; None keeps the world's
    noise_sigma: float | None = None  # grey levels; None keeps the world's
    noise_seed: int | None = None  # the pixel noise's RNG seed; None keeps the world's
    delay_steps: int | None = None  # actuation delay in steps; None keeps the world's
    dropouts: tuple[tuple[float, float], ...] = ()  # [start, end) sim times without frames
    # Unpainted stretches of floor line 0: (arc length from its first point, length), metres.
    line_gaps: tuple[tuple[float, float], ...] = ()
    # Objects left out of the frames: (object name, start, end), [start, end) sim times.
    hidden: tuple[tuple[str, float, float], ...] = ()
    # Realism options laid over the world's (harness.realism; `profile` already expanded).
    realism: tuple[tuple[str, Any], ...] = ()
    # The camera's plumb_bob lens (k1, k2, p1, p2, k3) instead of the world's; None keeps it.
    lens: tuple[float, float, float, float, float] | None = None
    # The camera rendered this far off its described mounting (Camera.y_offset_error_m,
    # Camera.yaw_error in degrees): a mounting error the robot description does not tell.
    mounting_error: tuple[tuple[str, float], ...] = ()


def with_line_gaps(world: World, gaps: tuple[tuple[float, float], ...]) -> World:
    """The world with stretches of line 0 left unpainted. Scoring keeps the original world:
    the robot is still judged against the whole centreline."""
    if not gaps:
        return world
    line = world.ground.lines[0]
    points = line.points
    closed_points = np.vstack([points, points[:1]]) if line.closed else points
    arc = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(closed_points, axis=0).T))])
    arc = arc[: len(points)]
    keep = np.ones(len(points), dtype=bool)
    for start, length in gaps:
        keep &= ~((arc >= start) & (arc <= start + length))
    # Open the loop just after a gap so every kept run is one contiguous polyline piece.
    first_kept_after_gap = int(np.argmax(~keep[:-1] & keep[1:])) + 1 if not keep.all() else 0
    order = np.roll(np.arange(len(points)), -first_kept_after_gap)
    runs = np.split(order, np.nonzero(~keep[order])[0])
    pieces = [run[keep[run]] for run in runs if keep[run].sum() >= 2]
    lines = tuple(replace(line, points=points[piece], closed=False) for piece in pieces)
    ground = replace(world.ground, lines=lines + world.ground.lines[1:])
    return replace(world, ground=ground)


def run_seed(world: World, perturbations: Perturbations) -> int:
    """The run's seed: the scenario's, else the world's noise seed."""
    p = perturbations
    return world.noise.seed if p.noise_seed is None else p.noise_seed


def run_realism(world: World, perturbations: Perturbations) -> Realism:
    """The run's realism: the scenario's options over the world's, ranges drawn from its seed."""
    options = dict(perturbations.realism)
    return realism_from(options, world.realism, run_seed(world, perturbations))


def run_lens(world: World, perturbations: Perturbations):
    """The run's plumb_bob lens when it replaces the world's: the scenario's `lens`, else the
    realism's barrel lens; None keeps the world camera's."""
    if perturbations.lens is not None:
        return perturbations.lens
    barrel = run_realism(world, perturbations).barrel
    return barrel_distortion(barrel) if barrel else None


@dataclass
class Record:
    """Per-step log. Commands are as received (before the robot's own clamp), so a NaN or an
    over-limit command a node sent stays visible to scoring."""

    t: list[float] = field(default_factory=list)
    pose: list[tuple[float, float, float]] = field(default_factory=list)
    v: list[float] = field(default_factory=list)
    w: list[float] = field(default_factory=list)
    frame: list[bool] = field(default_factory=list)  # a camera frame was published this step
    replies: list[int] = field(default_factory=list)  # behaviour statuses received this step
    # /cmd_vel messages this step (lockstep frame steps: as the status reports them)
    commands: list[int] = field(default_factory=list)
    missed: list[bool] = field(default_factory=list)  # lockstep: no reply to this step's frame

    def arrays(self) -> dict[str, np.ndarray]:
        pose = np.asarray(self.pose, dtype=float).reshape(-1, 3)
        return {
            "t": np.asarray(self.t, dtype=float),
            "x": pose[:, 0],
            "y": pose[:, 1],
            "yaw": pose[:, 2],
            "v": np.asarray(self.v, dtype=float),
            "w": np.asarray(self.w, dtype=float),
            "frame": np.asarray(self.frame, dtype=bool),
            "replies": np.asarray(self.replies, dtype=int),
            "commands": np.asarray(self.commands, dtype=int),
            "missed": np.asarray(self.missed, dtype=bool),
        }


class LapTracker:
    """Progress along a closed line, updated a chunk at a time so a lap can end a run early."""

    def __init__(self, centreline: np.ndarray):
        self.centreline = centreline
        self.loop_length = polyline_length(centreline, True)
        self.progress = 0.0
        self._last: tuple[float, float] | None = None

    def add(self, xy: np.ndarray) -> float:
        points = xy if self._last is None else np.vstack([self._last, xy])
        if len(points) >= 2:
            self.progress += float(progress(points, self.centreline, True)[-1])
        self._last = (float(xy[-1, 0]), float(xy[-1, 1]))
        return self.progress

    @property
    def lap_complete(self) -> bool:
        return abs(self.progress) >= self.loop_length


class Simulation:
    """Steps a world at a fixed frame rate: frame(k) -> command -> step()."""

    def __init__(
        self,
        world: World,
        *,
        rate_hz: float = 30.0,
        start: tuple[float, float, float] | None = None,
        perturbations: Perturbations | None = None,
    ):
        if not (math.isfinite(rate_hz) and rate_hz > 0.0):
            raise ValueError(f"rate_hz must be > 0, got {rate_hz}")
        self.world = world
        self.dt = 1.0 / rate_hz
        self.perturbations = perturbations or Perturbations()
        p = self.perturbations
        painted = with_line_gaps(world, p.line_gaps)
        self.seed = run_seed(world, p)
        realism = run_realism(world, p)
        lens = run_lens(world, p)
        camera = world.camera if lens is None else replace(world.camera, distortion=lens)
        error = dict(p.mounting_error)
        camera = replace(
            camera,
            y_offset_error_m=error.get("y_offset_m", 0.0),
            yaw_error=math.radians(error.get("yaw_deg", 0.0)),
        )
        self.renderer = Renderer(
            painted,
            camera,
            gain=p.gain,
            noise_sigma=p.noise_sigma,
            seed=p.noise_seed,
            realism=realism,
            rate_hz=rate_hz,
            starts=((start[0], start[1]),) if start else (),
        )
        delay = world.robot.delay_steps if p.delay_steps is None else p.delay_steps
        # The realism's delay in seconds adds whole steps and a fraction of one.
        delay_in_steps = delay + realism.actuation_delay / self.dt
        whole = math.floor(delay_in_steps + 1e-9)
        self.robot = Robot(
            start or world.robot.start,
            max_v=world.robot.max_v,
            max_w=world.robot.max_w,
            delay_steps=whole,
            delay_fraction=max(0.0, delay_in_steps - whole) if realism.actuation_delay else 0.0,
            lag=realism.motor_lag,
        )
        self.frame_drop = realism.frame_drop
        names = {obj.name for obj in world.objects}
        for name, _, _ in p.hidden:
            if name not in names:
                raise ValueError(f"perturbations.hide: no object named {name!r} in the world")
        self.step_index = 0
        self.record = Record()

    @property
    def time(self) -> float:
        return self.step_index * self.dt

    @property
    def pose(self) -> tuple[float, float, float]:
        return self.robot.pose

    def frames_flowing(self) -> bool:
        """False while a camera dropout covers the current time, or when the realism drops
        this step's frame (drawn from the run's seed and the step)."""
        t = self.time
        if any(start <= t < end for start, end in self.perturbations.dropouts):
            return False
        return not (
            self.frame_drop and rng_for(self.seed, 10, self.step_index).uniform() < self.frame_drop
        )

    def hidden_now(self) -> set[str]:
        """Names of the objects a `hide` perturbation leaves out of the current frame."""
        t = self.time
        return {name for name, start, end in self.perturbations.hidden if start <= t < end}

    def render(self) -> np.ndarray:
        """The camera frame at the current step (noise keyed by the step, so reruns match)."""
        return self.renderer.render(
            self.pose, frame=self.step_index, hidden=self.hidden_now(), motion=self.robot.applied
        )

    def step(
        self,
        command: tuple[float, float],
        *,
        frame: bool,
        replies: int,
        missed: bool,
        commands: int | None = None,
    ):
        """Log the step that is ending, then move the robot by `command` over one period."""
        v, w = command
        self.record.t.append(self.time)
        self.record.pose.append(self.pose)
        self.record.v.append(v)
        self.record.w.append(w)
        self.record.frame.append(frame)
        self.record.replies.append(replies)
        self.record.commands.append(replies if commands is None else commands)
        self.record.missed.append(missed)
        # The robot's own controller ignores a non-finite command rather than integrating NaN.
        safe = (v, w) if math.isfinite(v) and math.isfinite(w) else (0.0, 0.0)
        self.robot.step(*safe, self.dt)
        self.step_index += 1
