"""A played run's metrics (cross-track error, lap, stops, parking, commands) and its verdict
against the scenario's criteria.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

import numpy as np

from harness import scoring
from harness.scenario import Scenario, find_object, object_centre
from harness.simulation import run_lens
from harness.world import World


def _stop_in_window(run: dict[str, np.ndarray], start: float, end: float) -> dict:
    """How long after `start` the commands reached zero, and how many steps before `end` after
    that still moved (a dropout, or a marker hidden from view)."""
    t = run["t"]
    stop = scoring.time_to_stop(t, run["v"], run["w"], start)
    during = (t >= (stop["t_stop"] if stop["t_stop"] is not None else end)) & (t < end)
    moving = (np.abs(run["v"]) > 0) | (np.abs(run["w"]) > 0)
    stop["moving_after_stop"] = int(np.count_nonzero(during & moving))
    return stop


def metrics(scenario: Scenario, world: World, run: dict[str, np.ndarray]) -> dict:
    """Every metric the scenario's world and settings make meaningful, JSON-ready."""
    t = run["t"]
    path = np.column_stack([run["x"], run["y"], run["yaw"]])
    frame_steps = run["frame"]
    out: dict[str, Any] = {
        "steps": int(len(t)),
        "sim_time": float(t[-1] + 1.0 / scenario.rate_hz) if len(t) else 0.0,
        "final_pose": [float(v) for v in path[-1]] if len(t) else None,
        "loop_wall_time": float(run["loop_wall"]) if "loop_wall" in run else None,
        "commands": scoring.command_stats(t, run["v"], run["w"], int(run["missed"].sum())),
        "replies": {
            "frames": int(frame_steps.sum()),
            "extra": int(np.maximum(run["replies"][frame_steps] - 1, 0).sum()),
            "missing": int(run["missed"].sum()),
        },
    }
    if world.ground.lines and len(t):
        centreline = world.centreline()
        out["cross_track"] = scoring.cross_track(path, centreline)
        # Progress counts only while on the line: within the run's own cross-track bound.
        bounds = [c.maximum for c in scenario.criteria if c.metric == "cross_track.max"]
        on_line = bounds[0] if bounds and bounds[0] is not None else scoring.LAP_MAX_OFFSET
        out["lap"] = scoring.lap_stats(t, path, centreline, max_offset=on_line)
        out["lap"]["complete"] = out["lap"]["laps"] >= 1
    if scenario.target and len(t):
        obj = find_object(world, scenario.target, "target")
        out["target"] = scoring.stop_distance(path, obj)
        out["target"]["still_since"] = scoring.still_since(t, run["v"], run["w"])
        centre = object_centre(obj)[:2]
        bearing = math.atan2(centre[1] - path[-1, 1], centre[0] - path[-1, 0]) - path[-1, 2]
        out["target"]["bearing_deg"] = abs(math.degrees(math.remainder(bearing, math.tau)))
    if scenario.goal and len(t):
        marker = find_object(world, scenario.goal, "goal")
        x, y, _, yaw = marker.pose
        err = scoring.parking_error(path[-1], (x, y, yaw), scenario.standoff)
        err["heading_error_deg"] = math.degrees(err["heading_error"])
        err["still_since"] = scoring.still_since(t, run["v"], run["w"])
        out["parking"] = err
    if scenario.watch and len(t):
        lens = run_lens(world, scenario.perturbations)
        out["watch"] = stop_on_sight(world, find_object(world, scenario.watch, "watch"), run, lens)
    dropouts = []
    for start, end in scenario.perturbations.dropouts:
        stop = _stop_in_window(run, start, end)
        t_stop = stop["t_stop"]
        after_stop_step = (t > t_stop) & (t < end) if t_stop is not None else np.zeros_like(t, bool)
        stop["commands_after_stop"] = int(run["commands"][after_stop_step].sum())
        dropouts.append(stop)
    if dropouts:
        out["dropouts"] = dropouts
        delays = [d["stop_delay"] for d in dropouts]
        out["dropout_stop_delay_max"] = None if None in delays else max(delays)
    hidden = [
        {"object": name, **_stop_in_window(run, start, end)}
        for name, start, end in scenario.perturbations.hidden
    ]
    if hidden:
        out["hidden"] = hidden
    return out


def stop_on_sight(world: World, obj, run: dict[str, np.ndarray], lens=None) -> dict:
    """When part of `obj` first comes into the camera's view, how long until a zero command, and
    how many later steps with it in view still had a non-zero command. Spheres count as in view
    once their silhouette (centre +- projected radius) overlaps the image; others by centre.
    `lens`: the run's lens instead of the world's (a barrel lens sees wider than its pinhole)."""
    centre = object_centre(obj)
    radius = getattr(obj, "radius", 0.0)
    cam = world.camera if lens is None else replace(world.camera, distortion=lens)
    in_view = np.zeros(len(run["t"]), dtype=bool)
    for k, pose in enumerate(zip(run["x"], run["y"], run["yaw"], strict=True)):
        uv, depth = cam.project(centre[None, :], pose)
        if depth[0] <= 0:
            continue
        u, v = cam.distort_pixels(uv)[0] if cam.distorted else uv[0]
        margin = cam.fx * radius / depth[0]
        in_view[k] = -margin <= u < cam.width + margin and -margin <= v < cam.height + margin
    seen = np.nonzero(in_view)[0]
    if not len(seen):
        return {
            "first_in_view": None,
            "stop_delay": None,
            "steps_in_view": 0,
            "moving_in_view_after_stop": 0,
        }
    t, v, w = run["t"], run["v"], run["w"]
    stop = scoring.time_to_stop(t, v, w, float(t[seen[0]]))
    after = in_view & (t > (stop["t_stop"] if stop["t_stop"] is not None else t[-1]))
    moving = (np.abs(v) > 0) | (np.abs(w) > 0)
    return {
        "first_in_view": float(t[seen[0]]),
        "stop_delay": stop["stop_delay"],
        "steps_in_view": int(in_view.sum()),
        "moving_in_view_after_stop": int(np.count_nonzero(after & moving)),
    }


def check(scenario: Scenario, values: dict) -> list[dict]:
    """One row per criterion: metric, value, rule, passed."""
    rows = []
    for criterion in scenario.criteria:
        value, ok = criterion.check(values)
        rows.append(
            {
                "metric": criterion.metric,
                "value": value,
                "rule": criterion.describe(),
                "passed": ok,
                "margin": criterion.margin(value),
            }
        )
    return rows
