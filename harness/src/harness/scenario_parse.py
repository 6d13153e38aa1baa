"""One scenario run's fields, validated into a harness.scenario.Scenario; errors name the field.

Every run also gets the runner's own criteria (no non-finite command, none beyond the world
robot's limits, one reply per frame in lockstep).
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path
from typing import Any

from harness.realism import parse_realism
from harness.robot_preset import GENERIC, frame_rate, preset, robot_world
from harness.scenario import (
    REPLY_TIMEOUT_S,
    STOP_CONDITIONS,
    Behaviour,
    CameraMounting,
    Criterion,
    Scenario,
    ScenarioError,
    find_object,
    object_centre,
)
from harness.simulation import Perturbations
from harness.validation import (
    Fields,
    ValidationError,
    boolean,
    integer,
    mapping,
    number,
    sequence,
    string,
    vector,
)
from harness.world import Box, Sphere, World, WorldError
from harness.world_file import (
    load_world,
    parse_camera_transport,
    parse_distortion,
    resolve_world_path,
)


def _parse_camera_mounting(value: Any, where: str) -> CameraMounting:
    f = Fields(value, where, {"height_m", "pitch_deg", "x_offset_m"})
    return CameraMounting(
        height_m=f.get("height_m", number(gt=0.0), None),
        pitch_deg=f.get("pitch_deg", number(gt=-89.0, lt=89.0), None),
        x_offset_m=f.get("x_offset_m", number(), None),
    )


def _robot_name(value: Any, where: str) -> str:
    name = string(value, where)
    try:
        preset(name)
    except ValueError as error:
        raise ScenarioError(f"{where}: {error}") from None
    return name


def _world_file(value: Any, where: str, base: Path) -> Path:
    try:
        return resolve_world_path(string(value, where), base)
    except WorldError as error:
        raise ScenarioError(f"{where}: {error}") from None


def _parse_behaviour(value: Any, where: str) -> Behaviour:
    f = Fields(value, where, {"launch", "args"})
    launch = f.get("launch", string).split()
    if len(launch) != 2 or not launch[1].endswith(".launch"):
        raise ScenarioError(f"{f.where('launch')}: must be '<package> <file>.launch'")
    args = f.get("args", mapping, {})
    return Behaviour(launch[0], launch[1], {str(k): str(v) for k, v in args.items()})


def _parse_dropouts(value: Any, where: str) -> tuple[tuple[float, float], ...]:
    if not isinstance(value, list):
        raise ScenarioError(f"{where}: must be a list of [start, end] times")
    out = []
    for i, item in enumerate(value):
        start, end = vector(2, number(ge=0.0))(item, f"{where}[{i}]")
        if end <= start:
            raise ScenarioError(f"{where}[{i}]: end must be after start, got {item!r}")
        out.append((start, end))
    return tuple(out)


def _parse_gaps(value: Any, where: str) -> tuple[tuple[float, float], ...]:
    items = sequence(value, where)
    return tuple(vector(2, number(ge=0.0))(item, f"{where}[{i}]") for i, item in enumerate(items))


def _parse_hidden(value: Any, where: str) -> tuple[tuple[str, float, float], ...]:
    out = []
    for i, item in enumerate(sequence(value, where)):
        if not isinstance(item, list) or len(item) != 3:
            raise ScenarioError(f"{where}[{i}]: must be [object_name, start, end], got {item!r}")
        name = string(item[0], f"{where}[{i}][0]")
        start, end = vector(2, number(ge=0.0))(item[1:], f"{where}[{i}]")
        if end <= start:
            raise ScenarioError(f"{where}[{i}]: end must be after start, got {item!r}")
        out.append((name, start, end))
    return tuple(out)


def _parse_perturbations(value: Any, where: str) -> Perturbations:
    allowed = {
        "gain",
        "noise_sigma",
        "delay_steps",
        "dropout",
        "line_gap",
        "hide",
        "realism",
        "lens",
        "mounting_error",
    }
    f = Fields(value, where, allowed)
    delay = f.get("delay_steps", number(ge=0.0), None)
    if delay is not None and delay != int(delay):
        raise ScenarioError(f"{f.where('delay_steps')}: must be a whole number, got {delay!r}")
    return Perturbations(
        gain=f.get("gain", number(gt=0.0), None),
        noise_sigma=f.get("noise_sigma", number(ge=0.0), None),
        delay_steps=None if delay is None else int(delay),
        dropouts=f.get("dropout", _parse_dropouts, ()),
        line_gaps=f.get("line_gap", _parse_gaps, ()),
        hidden=f.get("hide", _parse_hidden, ()),
        realism=tuple(f.get("realism", parse_realism, {}).items()),
        lens=f.get("lens", parse_distortion, None),
        mounting_error=f.get("mounting_error", _parse_mounting_error, ()),
    )


def _parse_mounting_error(value: Any, where: str) -> tuple[tuple[str, float], ...]:
    f = Fields(value, where, {"y_offset_m", "yaw_deg"})
    error = {k: f.get(k, number(), None) for k in ("y_offset_m", "yaw_deg")}
    return tuple((k, v) for k, v in error.items() if v is not None)


def _parse_criteria(value: Any, where: str) -> tuple[Criterion, ...]:
    out = []
    for metric, rule in mapping(value, where).items():
        r = Fields(rule, f"{where}.{metric}", {"min", "max", "equals"})
        criterion = Criterion(
            str(metric),
            r.get("min", number(), None),
            r.get("max", number(), None),
            r.data.get("equals"),
        )
        if criterion.minimum is None and criterion.maximum is None and criterion.equals is None:
            raise ScenarioError(f"{r.path}: needs min, max or equals")
        out.append(criterion)
    return tuple(out)


def _parse_regression(value: Any, where: str) -> tuple[Criterion, ...]:
    """`regression: {metric: bound}`: the metric's magnitude at most `bound`, a second criterion
    beside the specification's (a family writes these from its `measured` values)."""
    return tuple(
        Criterion(str(metric), maximum=number(gt=0.0)(bound, f"{where}.{metric}"), absolute=True)
        for metric, bound in mapping(value, where).items()
    )


def _start_pose(value: Any, where: str, world_path: Path) -> tuple[float, float, float]:
    """[x, y, yaw], or {from, distance, off_deg, bearing_deg}: `distance` m from the centre of
    the marker or box `from`, `off_deg` counter-clockwise off its facing direction (its normal),
    with the object `bearing_deg` to the left of the heading (0: straight ahead)."""
    if not isinstance(value, dict):
        return vector(3)(value, where)
    f = Fields(value, where, {"from", "distance", "off_deg", "bearing_deg"})
    name = f.get("from", string)
    distance = f.get("distance", number(gt=0.0))
    off = math.radians(f.get("off_deg", number(), 0.0))
    bearing = math.radians(f.get("bearing_deg", number(), 0.0))
    obj = find_object(load_world(world_path), name, f.where("from"))
    if isinstance(obj, Sphere):
        raise ScenarioError(f"{f.where('from')}: {name!r} is a sphere, which faces no way")
    facing = obj.pose[2] if isinstance(obj, Box) else obj.pose[3]
    cx, cy = object_centre(obj)[:2]
    x = cx + distance * math.cos(facing + off)
    y = cy + distance * math.sin(facing + off)
    return (x, y, math.remainder(math.atan2(cy - y, cx - x) - bearing, math.tau))


# Relative slack of the acceleration bounds: a command limited to accel * dt over stamps rounded to
# the nanosecond measures up to ~2e-8 above accel over the simulator's exact step.
ACCEL_ROUNDING = 1e-6


def runner_criteria(
    world_path: Path, lockstep: bool, robot: str | None = None
) -> dict[str, Criterion]:
    """What every run must meet, whatever its file says: finite commands within the world
    robot's limits (with `robot`, the preset's speed and acceleration limits, which its launch
    gives the behaviour) and, in lockstep, exactly one reply (the behaviour's status) to every
    frame."""
    world = load_world(world_path)
    base = (robot_world(world, robot) if robot else world).robot
    rules = [
        Criterion("commands.non_finite", equals=0),
        Criterion("commands.max_abs_v", maximum=base.max_v),
        Criterion("commands.max_abs_w", maximum=base.max_w),
    ]
    limits = preset(robot).get("limits", {}) if robot not in (None, GENERIC) else {}
    for metric, limit in (("max_abs_dv_dt", "limit_linear_accel"),
                          ("max_abs_dw_dt", "limit_angular_accel")):  # fmt: skip
        if limit in limits:  # the limiter's dt is of whole-nanosecond stamps, the metric's not
            bound = limits[limit] * (1.0 + ACCEL_ROUNDING)
            rules.append(Criterion(f"commands.{metric}", maximum=bound))
    if lockstep:
        rules += [Criterion("replies.missing", equals=0), Criterion("replies.extra", equals=0)]
    return {c.metric: c for c in rules}


def parse_scenario(data: Any, base_dir: Path | str = ".", source: Path | None = None) -> Scenario:
    base = Path(base_dir)
    allowed = {
        "name", "world", "start", "behaviour", "driver", "rate_hz", "duration", "stop_when",
        "lockstep", "reply_timeout", "perturbations", "target", "watch", "goal", "standoff",
        "criteria", "regression", "seed", "camera_transport", "camera_mounting", "robot",
    }  # fmt: skip
    try:
        f = Fields(data, "", allowed)
        behaviour = f.get("behaviour", _parse_behaviour, None)
        driver = f.get("driver", lambda v, w: Fields(v, w, {"constant"}), None)
        constant = driver.get("constant", vector(2)) if driver else None
        if (behaviour is None) == (constant is None):
            raise ScenarioError("behaviour: give exactly one of 'behaviour' or 'driver'")
        stop_when = f.get("stop_when", string, "duration")
        if stop_when not in STOP_CONDITIONS:
            raise ScenarioError(f"stop_when: must be one of {', '.join(STOP_CONDITIONS)}")
        world_path = f.get("world", lambda v, w: _world_file(v, w, base))
        lockstep = f.get("lockstep", boolean, True)
        robot = f.get("robot", _robot_name, None)
        criteria = runner_criteria(world_path, lockstep, robot)
        criteria.update((c.metric, c) for c in f.get("criteria", _parse_criteria, ()))
        regression = f.get("regression", _parse_regression, ())
        name = f.get("name", string, source.stem if source else "scenario")
        duration = f.get("duration", number(gt=0.0))
        seed = f.get("seed", integer(ge=0), None)
        for c in criteria.values():
            # still_since = still from then to the end: a bound at the end says only that the
            # last command was zero, so it must fall strictly before the end.
            if c.metric.split(".")[-1] == "still_since" and not (
                c.maximum is not None and c.maximum < duration
            ):
                raise ScenarioError(
                    f"criteria.{c.metric}: needs a max before the end (duration {duration:g} s)"
                )
        return Scenario(
            name=name,
            world_path=world_path,
            start=f.get("start", lambda v, w: _start_pose(v, w, world_path), None),
            behaviour=behaviour,
            constant_command=constant,
            rate_hz=f.get(
                "rate_hz", number(gt=0.0, le=1000.0), (robot and frame_rate(robot)) or 30.0
            ),
            duration=duration,
            stop_when=stop_when,
            lockstep=lockstep,
            reply_timeout=f.get("reply_timeout", number(gt=0.0), REPLY_TIMEOUT_S),
            perturbations=replace(
                f.section("perturbations", _parse_perturbations), noise_seed=seed
            ),
            target=f.get("target", string, None),
            watch=f.get("watch", string, None),
            goal=f.get("goal", string, None),
            standoff=f.get("standoff", number(gt=0.0), 0.5),
            criteria=(*criteria.values(), *regression),
            seed=seed,
            camera_transport=f.get("camera_transport", parse_camera_transport, None),
            camera_mounting=f.section("camera_mounting", _parse_camera_mounting),
            robot=robot,
            source=source,
            spec={**data, "name": name, "world": str(world_path)},
        )
    except (ValidationError, WorldError) as error:
        where = f"{source}: " if source else ""
        raise ScenarioError(f"{where}{error}") from None


def scenario_world(scenario: Scenario) -> World:
    """The world the run plays: the scenario's world file, with the robot preset's camera and
    limits, its camera moved to the scenario's `camera_mounting` (the simulator's camera, the
    robot description and the node's mounting all come from this one)."""
    world = load_world(scenario.world_path)
    if scenario.robot:
        world = robot_world(world, scenario.robot)
    return replace(world, camera=scenario.camera_mounting.apply(world.camera))
