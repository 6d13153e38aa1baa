"""run_scenario --scheduler: each run a task on a Dask distributed cluster.

A task plays its run on a worker exactly as run_scenario plays it locally (its own roscore,
ROS_HOME and log folder), in a temporary folder it sends back as a gzipped tar; the client
unpacks it under --out. Workers need this workspace built, its devel space sourced and the
harness venv's Python (the one that runs `dask-worker`). The task function lives here, in an
importable module, so Dask sends it by name rather than by value.
"""

from __future__ import annotations

import io
import sys
import tarfile
import tempfile
from dataclasses import replace
from pathlib import Path

from distributed import Client
from distributed import as_completed as tasks_completed
from tqdm import tqdm

from harness.runs import describe, error_entry, play
from harness.scenario import Scenario
from harness.scenario_parse import parse_scenario
from harness.world import WORLDS_DIR


def portable_spec(scenario: Scenario) -> dict:
    """The run's fields with a shipped world by name, so a worker whose checkout lives at
    another path finds it in its own worlds folder."""
    world = scenario.world_path
    in_shipped = world.parent == WORLDS_DIR.resolve() and world.suffix == ".yaml"
    return dict(scenario.spec, world=world.stem if in_shipped else str(world))


def play_packed(
    spec: dict, parameters: dict, source: str | None, video: bool
) -> tuple[dict, bytes]:
    """A Dask task: one run played on the worker as `play` plays it here (its own ROS graph) in
    a temporary folder; its result and that folder as a gzipped tar."""
    scenario = parse_scenario(spec, source=Path(source) if source else None)
    scenario = replace(scenario, parameters=parameters)
    with tempfile.TemporaryDirectory(prefix="run_scenario_") as tmp:
        result = play(scenario, Path(tmp), video)
        packed = io.BytesIO()
        with tarfile.open(fileobj=packed, mode="w:gz") as tar:
            run_dir = Path(tmp) / scenario.name
            if run_dir.is_dir():
                # Without symbolic links (roslaunch's log/latest): only what the run wrote.
                tar.add(run_dir, arcname=".", filter=lambda m: None if m.issym() else m)
    return result, packed.getvalue()


def unpack(data: bytes, folder: Path) -> None:
    """A worker's run folder into `folder`: regular files and folders inside it only."""
    with tarfile.open(fileobj=io.BytesIO(data), mode="r:gz") as tar:
        members = tar.getmembers()
        for member in members:
            inside = not member.name.startswith("/") and ".." not in Path(member.name).parts
            if not (inside and (member.isfile() or member.isdir())):
                raise RuntimeError(f"a worker sent an unsafe archive entry {member.name!r}")
        folder.mkdir(parents=True, exist_ok=True)
        tar.extractall(folder, members=members)


def run_on_cluster(scenarios: list[Scenario], out: Path, scheduler: str, video: bool) -> list[dict]:
    """run_all on a Dask cluster: one task per run (play_packed), each run's folder unpacked
    under `out` as it comes back; a task that dies (a lost worker) is an error entry."""
    results: list[dict | None] = [None] * len(scenarios)
    with (
        Client(scheduler) as client,  # connect timeout: Dask's distributed.comm.timeouts.connect
        tqdm(total=len(scenarios), unit="run", file=sys.stderr) as progress,
    ):
        futures = {}
        for i, s in enumerate(scenarios):
            source = s.source and str(s.source)
            task = client.submit(play_packed, portable_spec(s), s.parameters, source, video,
                                 pure=False)  # fmt: skip
            futures[task] = i
        for future in tasks_completed(futures):
            scenario = scenarios[futures[future]]
            try:
                result, packed = future.result()
                unpack(packed, out / scenario.name)
            except Exception as error:  # whatever the task or the cluster raised, as an error
                result = error_entry(scenario, f"Dask task failed: {error!r}")
            results[futures[future]] = result
            progress.write("\n".join(describe(result)))
            progress.update()
    return [r for r in results if r is not None]  # every one, each future having finished
