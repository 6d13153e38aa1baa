"""Scenario files (worlds/scenarios/*.yaml): what to run, what to disturb, what must hold.

A scenario names a world, the behaviour to launch (or a built-in scripted driver), a duration
and stop condition, perturbations and pass criteria over the metrics of `metrics()`. A family
file holds many: a `base` run and a `matrix` whose cartesian product of field values (or a list
of such products) gives one named run each, or a `sweep` that draws N runs from distributions
over the same fields (harness.sweep), each with a seed of its own. Every run also gets the
runner's own criteria (no non-finite command, none beyond the world robot's limits, one reply
per frame in lockstep). Schema in worlds/SCHEMA.md. Everything is validated on load; errors
name the field.
"""

from __future__ import annotations

import copy
import itertools
import math
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from harness import scoring
from harness.camera import Camera
from harness.realism import drawn, parse_realism
from harness.robot_preset import GENERIC, frame_rate, preset, robot_world
from harness.simulation import Perturbations, run_lens, run_seed
from harness.sweep import draw, member_name, parse_sweep
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
from harness.world import Box, CameraTransport, Sphere, World, WorldError
from harness.world_file import (
    load_world,
    parse_camera_transport,
    parse_distortion,
    resolve_world_path,
)

STOP_CONDITIONS = ("duration", "lap_complete", "still")
# `stop_when: still` waits at least this long without motion: longer than a behaviour's hold
# while its target is briefly lost (the parker holds 2 s, then searches), so a pause is not an end.
STILL_STOP_S = 3.0
# A family's `measured` values bound each member at this multiple of its own measurement (or the
# family's stated noise floor, if larger), beside the specification's bounds.
MEASURED_FACTOR = 3.0


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


def _parse_camera_mounting(value: Any, where: str) -> CameraMounting:
    f = Fields(value, where, {"height_m", "pitch_deg", "x_offset_m"})
    return CameraMounting(
        height_m=f.get("height_m", number(gt=0.0), None),
        pitch_deg=f.get("pitch_deg", number(gt=-89.0, lt=89.0), None),
        x_offset_m=f.get("x_offset_m", number(), None),
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
            reply_timeout=f.get("reply_timeout", number(gt=0.0), 2.0),
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


def merged(under: dict, over: dict) -> dict:
    """`under` with `over` laid on top: mappings merge key by key, anything else is replaced."""
    out = copy.deepcopy(under)
    for key, value in over.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = merged(out[key], value)
        else:
            out[key] = copy.deepcopy(value)
    return out


def _axis(path: str, values: Any, labels: dict, where: str) -> list[tuple[str, Any]]:
    """One matrix axis as (label, value) pairs: labelled values ({label: value}), or a list
    labelled by the file's `labels.<path>` format (fields of a mapping value by name)."""
    if isinstance(values, dict):
        return [(str(label), value) for label, value in values.items()]
    items = sequence(values, where, min_len=1)
    if path not in labels:
        raise ScenarioError(f"{where}: give its values labels ({{label: value}}) or labels.{path}")
    fmt = string(labels[path], f"labels.{path}")
    try:
        return [(fmt.format(**v) if isinstance(v, dict) else fmt.format(v), v) for v in items]
    except (KeyError, IndexError, ValueError) as error:
        raise ScenarioError(f"labels.{path}: {fmt!r} does not fit the values: {error}") from None


def set_field(run: dict, path: str, value: Any, where: str) -> dict:
    """`run` with the field at dotted `path` set to `value`; the path `variant` lays a mapping of
    fields over the run instead (mappings merge key by key)."""
    if path == "variant":
        return merged(run, mapping(value, f"{where}.variant"))
    *parents, leaf = path.split(".")
    node = run
    for key in parents:
        node = node.setdefault(key, {})
        if not isinstance(node, dict):
            raise ScenarioError(f"{where}.{path}: {key!r} is not a mapping in the base")
    node[leaf] = copy.deepcopy(value)
    return run


def _sweep(base: dict, section: Any, family: str) -> list[tuple[dict, dict]]:
    """A sweep's members: the base with each varied field drawn, its own `seed` and name."""
    sweep = parse_sweep(section)
    runs = []
    for index in range(sweep.runs):
        seed, values = draw(sweep, index)
        run = copy.deepcopy(base)
        for path, value in values.items():
            run = set_field(run, path, value, "sweep.vary")
        runs.append(({**run, "name": member_name(family, index, seed), "seed": seed}, values))
    return runs


def _read_yaml(p: Path) -> Any:
    try:
        return yaml.safe_load(p.read_text(encoding="utf-8"))
    except OSError as error:
        raise ScenarioError(f"{p}: cannot read scenario file: {error.strerror}") from None
    except yaml.YAMLError as error:
        raise ScenarioError(f"{p}: not valid YAML: {error}") from None


def expand(data: Any, family: str, base_dir: Path = Path(".")) -> list[tuple[dict, dict]]:
    """A file's runs as plain scenario mappings, each with the values its sweep drew (empty for
    matrix runs). Matrix runs are named `<family>/<label>_<label>…`, sweep members
    `<family>/<index>_seed<seed>`. `extends: FILE` (relative to `base_dir`) starts from that
    family file's `base`. A file without `matrix` or `sweep` is one run as written."""
    if not (isinstance(data, dict) and ("matrix" in data or "sweep" in data)):
        return [(data, {})]
    f = Fields(data, "", {"base", "matrix", "labels", "sweep", "extends", "measured"})
    base = f.get("base", mapping, {})
    if f.has("extends"):
        parent = _read_yaml(base_dir / f.get("extends", string))
        inherited = parent.get("base", {}) if isinstance(parent, dict) else {}
        base = merged(mapping(inherited, f"extends: {data['extends']}: base"), base)
    if "sweep" in data:
        if "matrix" in data or "labels" in data:
            raise ScenarioError("sweep: a file holds a matrix or a sweep, not both")
        if "measured" in data:
            raise ScenarioError("measured: bounds a matrix's members; a sweep is judged by rate")
        return _sweep(base, data["sweep"], family)
    labels = f.get("labels", mapping, {})
    blocks = f.data["matrix"]
    blocks = [blocks] if isinstance(blocks, dict) else sequence(blocks, "matrix", min_len=1)
    runs: dict[str, dict] = {}
    for i, block in enumerate(blocks):
        where = f"matrix[{i}]" if len(blocks) > 1 else "matrix"
        axes = [(path, _axis(str(path), values, labels, f"{where}.{path}"))
                for path, values in mapping(block, where).items()]  # fmt: skip
        for combination in itertools.product(*(values for _, values in axes)):
            run = copy.deepcopy(base)
            for (path, _), (_, value) in zip(axes, combination, strict=True):
                run = set_field(run, str(path), value, where)
            name = f"{family}/" + "_".join(label for label, _ in combination)
            if name in runs:
                raise ScenarioError(f"{where}: two runs are named {name!r}")
            runs[name] = {**run, "name": name}
    if f.has("measured"):
        _bound_by_measurement(runs, f.data["measured"], family)
    return [(run, {}) for run in runs.values()]


def _bound_by_measurement(runs: dict[str, dict], section: Any, family: str) -> None:
    """Lays each member's `regression` bounds from the family's `measured: {floor, runs}`:
    MEASURED_FACTOR times the member's measured magnitude of each metric, never below the
    metric's stated noise floor."""
    f = Fields(section, "measured", {"floor", "runs"})
    floors = {
        str(metric): number(gt=0.0)(v, f"measured.floor.{metric}")
        for metric, v in f.get("floor", mapping).items()
    }
    for label, values in f.get("runs", mapping).items():
        where = f"measured.runs.{label}"
        run = runs.get(f"{family}/{label}")
        if run is None:
            raise ScenarioError(f"{where}: the family has no run {family}/{label}")
        bounds = {}
        for metric, measured in mapping(values, where).items():
            if metric not in floors:
                raise ScenarioError(f"{where}.{metric}: measured.floor gives this metric no floor")
            value = number()(measured, f"{where}.{metric}")
            bounds[str(metric)] = max(MEASURED_FACTOR * abs(value), floors[metric])
        run["regression"] = {**run.get("regression", {}), **bounds}


def load_scenarios(path: Path | str) -> list[Scenario]:
    """Every run a scenario file holds (one for a plain file, the matrix's for a family)."""
    p = Path(path)
    data = _read_yaml(p)
    try:
        runs = expand(data, p.stem, p.parent)
    except ValidationError as error:
        raise ScenarioError(f"{p}: {error}") from None
    scenarios = [parse_scenario(run, p.parent, p.resolve()) for run, _ in runs]
    return [
        replace(s, parameters={**parameters, **realism_draws(s)})
        for s, (_, parameters) in zip(scenarios, runs, strict=True)
    ]


def realism_draws(scenario: Scenario) -> dict[str, Any]:
    """The values a run drew for the realism options its file gives as ranges, by field path
    (`realism.shadow_depth`), reported beside a sweep's own draws."""
    options = dict(scenario.perturbations.realism)
    if not any(isinstance(v, tuple) for v in options.values()):
        return {}
    seed = scenario.seed  # a sweep member's; else the world's noise seed, as the run's
    if seed is None:
        seed = run_seed(load_world(scenario.world_path), scenario.perturbations)
    values = drawn(options, seed)
    return {f"realism.{k}": values[k] for k, v in options.items() if isinstance(v, tuple)}


def load_scenario(path: Path | str) -> Scenario:
    """The one run of a plain scenario file."""
    scenarios = load_scenarios(path)
    if len(scenarios) != 1:
        raise ScenarioError(f"{path}: holds {len(scenarios)} runs; pick one by name")
    return scenarios[0]


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
