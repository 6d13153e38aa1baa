"""Unicycle robot (TurtleBot-2-like) integrated exactly for piecewise-constant commands."""

from __future__ import annotations

import math
from collections import deque

from harness.geometry import wrap_angle

Pose = tuple[float, float, float]

# Below this |w| the arc formula loses precision; use the straight-line limit instead.
STRAIGHT_EPS = 1e-9


def integrate_unicycle(pose: Pose, v: float, w: float, dt: float) -> Pose:
    """Pose after driving at constant (v, w) for dt seconds: an exact circular arc.

    Exact integration keeps the simulated path independent of the control rate.
    """
    x, y, yaw = pose
    new_yaw = yaw + w * dt
    if abs(w) < STRAIGHT_EPS:
        return x + v * dt * math.cos(yaw), y + v * dt * math.sin(yaw), float(wrap_angle(new_yaw))
    r = v / w
    return (
        x + r * (math.sin(new_yaw) - math.sin(yaw)),
        y - r * (math.cos(new_yaw) - math.cos(yaw)),
        float(wrap_angle(new_yaw)),
    )


def clamp_command(v: float, w: float, max_v: float, max_w: float) -> tuple[float, float]:
    """Saturate a command to the robot limits; a non-finite component becomes 0 (stop),
    as a real base would reject it. Scoring counts such commands separately."""
    v = min(max(v, -max_v), max_v) if math.isfinite(v) else 0.0
    w = min(max(w, -max_w), max_w) if math.isfinite(w) else 0.0
    return v, w


class Robot:
    """Unicycle with velocity limits and an optional actuation delay of whole steps.

    With delay_steps = n, the command given at step k is applied during step k + n;
    until then the robot executes the (initially zero) commands queued before it.
    """

    def __init__(
        self,
        pose: Pose = (0.0, 0.0, 0.0),
        *,
        max_v: float = 0.7,
        max_w: float = math.pi,
        delay_steps: int = 0,
    ):
        if max_v <= 0.0 or max_w <= 0.0:
            raise ValueError(f"robot limits must be > 0, got max_v={max_v}, max_w={max_w}")
        if delay_steps < 0:
            raise ValueError(f"delay_steps must be >= 0, got {delay_steps}")
        self.pose: Pose = (float(pose[0]), float(pose[1]), float(wrap_angle(pose[2])))
        self.max_v, self.max_w = max_v, max_w
        self._queue: deque[tuple[float, float]] = deque([(0.0, 0.0)] * delay_steps)
        self.applied: tuple[float, float] = (0.0, 0.0)  # command used in the last step

    def step(self, v: float, w: float, dt: float) -> Pose:
        """Queue command (v, w), apply the one due now for dt seconds, return the new pose."""
        if dt < 0.0:
            raise ValueError(f"dt must be >= 0, got {dt}")
        self._queue.append(clamp_command(v, w, self.max_v, self.max_w))
        self.applied = self._queue.popleft()
        self.pose = integrate_unicycle(self.pose, *self.applied, dt)
        return self.pose
