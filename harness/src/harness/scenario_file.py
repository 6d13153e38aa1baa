"""Scenario files (worlds/scenarios/*.yaml, worlds/sweeps/*.yaml): a `base` run and a `matrix`
whose cartesian product of field values (or a list of such products) gives one named run each,
or a `sweep` that draws N runs from distributions over the same fields (harness.sweep), each
with a seed of its own; `measured` bounds each member by its own measured value.
"""

from __future__ import annotations

import copy
import itertools
from dataclasses import replace
from pathlib import Path
from typing import Any

import yaml

from harness.realism import drawn
from harness.scenario import MEASURED_FACTOR, Scenario, ScenarioError
from harness.scenario_parse import parse_scenario
from harness.simulation import run_seed
from harness.sweep import draw, member_name, parse_sweep
from harness.validation import (
    Fields,
    ValidationError,
    mapping,
    number,
    sequence,
    string,
)
from harness.world_file import (
    load_world,
)


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
