"""Unicycle robot (TurtleBot-2-like) integrated exactly for piecewise-constant commands."""

from __future__ import annotations

import math
from collections import deque

from harness.geometry import wrap_angle

Pose = tuple[float, float, float]

# Below this |w| the arc formula loses precision; use the straight-line limit instead.
STRAIGHT_EPS = 1e-9
LAG_SUBSTEP_S = 0.005  # the motor lag's integration step: well under its 0.1 s time constants


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
    """Unicycle with velocity limits, an optional actuation delay and an optional motor lag.

    With delay_steps = n, the command given at step k is applied during step k + n;
    until then the robot executes the (initially zero) commands queued before it. A further
    `delay_fraction` f of a step (0 <= f < 1) makes it act f of a step later still: the first
    f of each step runs the command before. With `lag` tau > 0 the base's velocity follows the
    command due as a first-order system, dv/dt = (command - v) / tau.
    """

    def __init__(
        self,
        pose: Pose = (0.0, 0.0, 0.0),
        *,
        max_v: float = 0.7,
        max_w: float = math.pi,
        delay_steps: int = 0,
        delay_fraction: float = 0.0,
        lag: float = 0.0,
    ):
        if max_v <= 0.0 or max_w <= 0.0:
            raise ValueError(f"robot limits must be > 0, got max_v={max_v}, max_w={max_w}")
        if delay_steps < 0:
            raise ValueError(f"delay_steps must be >= 0, got {delay_steps}")
        if not 0.0 <= delay_fraction < 1.0:
            raise ValueError(f"delay_fraction must be in [0, 1), got {delay_fraction}")
        if lag < 0.0:
            raise ValueError(f"lag must be >= 0, got {lag}")
        self.pose: Pose = (float(pose[0]), float(pose[1]), float(wrap_angle(pose[2])))
        self.max_v, self.max_w = max_v, max_w
        self.delay_fraction, self.lag = delay_fraction, lag
        queued = delay_steps + (1 if delay_fraction else 0)
        self._queue: deque[tuple[float, float]] = deque([(0.0, 0.0)] * queued)
        # The base's velocity at the end of the last step: the command used in it, or with a
        # lag the velocity the motors had reached.
        self.applied: tuple[float, float] = (0.0, 0.0)

    def step(self, v: float, w: float, dt: float) -> Pose:
        """Queue command (v, w), apply the one due now for dt seconds, return the new pose."""
        if dt < 0.0:
            raise ValueError(f"dt must be >= 0, got {dt}")
        self._queue.append(clamp_command(v, w, self.max_v, self.max_w))
        if not (self.delay_fraction or self.lag):
            self.applied = self._queue.popleft()
            self.pose = integrate_unicycle(self.pose, *self.applied, dt)
            return self.pose
        pieces = []
        if self.delay_fraction:
            pieces.append((self._queue.popleft(), self.delay_fraction * dt))
            pieces.append((self._queue[0], (1.0 - self.delay_fraction) * dt))
        else:
            pieces.append((self._queue.popleft(), dt))
        for command, duration in pieces:
            self._drive(command, duration)
        return self.pose

    def _drive(self, command: tuple[float, float], duration: float) -> None:
        """Drive for `duration` s towards `command` (through the lag, in sub-steps of at most
        LAG_SUBSTEP_S, each an arc at the sub-step's mean velocity)."""
        if not self.lag:
            self.applied = command
            self.pose = integrate_unicycle(self.pose, *command, duration)
            return
        steps = max(1, math.ceil(duration / LAG_SUBSTEP_S))
        h = duration / steps
        decay = math.exp(-h / self.lag)
        mean_weight = self.lag / h * (1.0 - decay) if h > 0.0 else 1.0
        for _ in range(steps):
            start = self.applied
            (v0, w0), (v, w) = start, command
            self.pose = integrate_unicycle(
                self.pose, v + (v0 - v) * mean_weight, w + (w0 - w) * mean_weight, h
            )
            self.applied = (v + (v0 - v) * decay, w + (w0 - w) * decay)
