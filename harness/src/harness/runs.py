"""Playing scenarios: each run in a ROS graph of its own (a master on a free port, its own ROS_HOME
and log folder, the behaviour's launch file or the scripted constant-Twist driver, the robot
description, then the simulator in lockstep), scored into its result; many at a time on this
machine. run_scenario is the command line over it; cluster plays the same runs on Dask workers.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import threading
import time
from concurrent.futures import ThreadPoolExecutor, as_completed
from pathlib import Path
from typing import Any
from xml.etree import ElementTree

import numpy as np
import roslaunch.rlutil
import yaml
from tqdm import tqdm

from harness.camera import Camera
from harness.contact_sheet import write_contact_sheet
from harness.evaluation import check, metrics
from harness.marker_map import load_frames, plot_markers
from harness.node_cli import BEHAVIOUR_GONE
from harness.plot import plot_run
from harness.processes import start_master, stop, tracked, use_sim_time, wait_for_node
from harness.report import format_value, headline, headline_text
from harness.scenario import Scenario, ScenarioError, find_object
from harness.scenario_parse import scenario_world
from harness.world import WorldError

# Wall-clock allowance on top of the scenario's sim duration (start-up, slow machines).
RUN_TIMEOUT_FLOOR = 120.0
# A single run's progress in a log (stderr not a terminal): a line per this share of its duration.
PROGRESS_LOG_STEP = 0.1


def declared_args(package: str, launch_file: str) -> set[str]:
    """The names of the args a launch file declares at its top level."""
    path = roslaunch.rlutil.resolve_launch_arguments([package, launch_file])[0]
    return {arg.get("name", "") for arg in ElementTree.parse(path).getroot().findall("arg")}


def behaviour_command(scenario: Scenario) -> list[str]:
    if scenario.behaviour is None:
        assert scenario.constant_command is not None  # the scripted driver's
        v, w = scenario.constant_command
        return ["rosrun", "harness", "constant_twist", f"_v:={v}", f"_w:={w}"]
    b = scenario.behaviour
    # The run's robot description comes from its world (description_command), not the launch's:
    # the node under test finds its camera's mounting in tf, as on a robot, never in ~params.
    args = {"robot_description": "false", **b.args}
    if scenario.robot:  # the launch file sets the robot's topics, transport and limits
        args.setdefault("robot", scenario.robot)
    if scenario.lockstep and "wall_watchdog_timeout" in declared_args(b.package, b.launch_file):
        # The simulator holds /clock while it renders a step, which on a loaded machine can take
        # longer than the behaviours' wall-clock watchdog (0.15 s): a slow step is not a dead
        # simulator. Lockstep allows reply_timeout of wall time per step, both ways.
        args.setdefault("wall_watchdog_timeout", str(scenario.reply_timeout))
    launch = ["roslaunch", "--wait", b.package, b.launch_file]
    return launch + [f"{k}:={v}" for k, v in args.items()]


def description_command(camera: Camera) -> list[str]:
    """robot_state_publisher with the URDF of the run's camera mounting (robot_description.launch's
    arguments): tf as on the robot, the only place the node under test learns its mounting."""
    mounting = {
        "camera_height": camera.height_m,
        "camera_pitch_deg": round(math.degrees(camera.pitch), 9),
        "camera_x_offset": camera.x_offset_m,
        "camera_frame": camera.frame_id,
    }
    launch = ["roslaunch", "--wait", "follow_bot", "robot_description.launch"]
    return launch + [f"{k}:={v}" for k, v in mounting.items()]


def show_progress(scenario: Scenario, env: dict, processes: list[subprocess.Popen]) -> None:
    """A progress line over the run's sim time (sim_clock reads /clock each wall second) until
    the reader stops: a bar on a terminal, a line every PROGRESS_LOG_STEP of the duration in a log.
    """
    reader = subprocess.Popen(
        [sys.executable, "-m", "harness.sim_clock"],
        env=env, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
    )  # fmt: skip
    processes.append(reader)  # stopped with the run's other processes

    def follow() -> None:
        tty = sys.stderr.isatty()
        with tqdm(
            total=scenario.duration, desc=scenario.name, file=sys.stderr, leave=False,
            disable=not tty, bar_format="{desc}: {n:.1f}/{total:.0f} sim s {percentage:3.0f}% {bar}"
        ) as bar:  # fmt: skip
            logged = 0.0
            assert reader.stdout is not None  # stdout=PIPE
            for line in reader.stdout:
                sim_time = float(line)
                bar.update(sim_time - bar.n)
                if not tty and sim_time >= logged + PROGRESS_LOG_STEP * scenario.duration:
                    logged = sim_time
                    tqdm.write(f"{scenario.name}: {sim_time:.1f} of {scenario.duration:.0f} sim s",
                               file=sys.stderr)  # fmt: skip

    threading.Thread(target=follow, daemon=True).start()


def run_one(
    scenario: Scenario,
    out: Path,
    video: bool,
    progress: bool = False,
    sheet: int = 0,
    markers: bool = False,
) -> dict:
    """Runs one scenario end to end in a ROS graph of its own; returns the result written to
    result.json. `progress`: show the run's sim time on stderr while it plays; `sheet` > 0: also
    a contact sheet of that many frames (from the camera video, recorded for it); `markers`: also
    record the behaviour's ~markers and draw them."""
    out.mkdir(parents=True, exist_ok=True)
    world = scenario_world(scenario)  # with the scenario's camera mounting
    ros_home = out / "ros_home"
    env = dict(os.environ, ROS_IP="127.0.0.1", ROS_HOME=str(ros_home))
    # numpy's OpenBLAS threads spin between calls; on the simulator's small matrices they buy
    # nothing and cost CPU the run's other processes need (harsh frames: 50 -> 36 ms of CPU).
    env.setdefault("OPENBLAS_NUM_THREADS", "1")
    env["ROS_LOG_DIR"] = str(ros_home / "log")
    record = out / "record.npz"
    record.unlink(missing_ok=True)
    spec = out / "scenario.yaml"  # the run as the simulator plays it (one member of a matrix)
    spec.write_text(yaml.safe_dump(scenario.spec, sort_keys=False))
    processes: list[subprocess.Popen] = []
    started = time.monotonic()
    with open(out / "ros.log", "w") as log:

        def start(command: list[str]) -> subprocess.Popen:
            log.write(f"$ {' '.join(command)}\n")
            log.flush()
            process = tracked(
                subprocess.Popen(command, env=env, stdout=log, stderr=subprocess.STDOUT)
            )
            processes.append(process)
            return process

        roscore = None
        try:
            started_master = start_master(["roscore"], env, start)
            if started_master is None:
                raise RuntimeError(f"roscore did not start (see {out}/ros.log)")
            roscore, port = started_master
            use_sim_time(env)
            # The description's start-up (roslaunch, the URDF script) done before the run's:
            # its load must not slow the first lockstep frames.
            description = start(description_command(world.camera))
            if not wait_for_node(port, "/robot_state_publisher", 60.0, description):
                raise RuntimeError(f"robot_state_publisher did not start (see {out}/ros.log)")
            start(behaviour_command(scenario))
            if markers:  # before the simulator: it misses the first frames at most
                recorder = start([sys.executable, "-m", "harness.marker_record",
                                  f"_out:={out / 'markers.json'}"])  # fmt: skip
                if not wait_for_node(port, "/marker_record", 60.0, recorder):
                    raise RuntimeError(f"marker_record did not start (see {out}/ros.log)")
            sim_command = [
                "rosrun", "harness", "sim", f"_scenario:={spec}", f"_record:={record}",
            ]  # fmt: skip
            if video or sheet:
                sim_command.append(f"_video:={out / 'camera.mp4'}")
            sim = start(sim_command)
            if progress:
                show_progress(scenario, env, processes)
            sim.wait(timeout=RUN_TIMEOUT_FLOOR + 20.0 * scenario.duration)
            if sim.returncode == BEHAVIOUR_GONE:
                raise RuntimeError(f"the behaviour under test is not running (see {out}/ros.log)")
        finally:
            # The nodes first, together; the master last, so they unregister from it.
            stop(*(p for p in processes if p is not roscore))
            stop(roscore)
    wall = time.monotonic() - started
    if not record.is_file():
        raise RuntimeError(f"the simulator wrote no record (see {out}/ros.log)")
    run = dict(np.load(record))
    values = metrics(scenario, world, run)
    values["wall_time"] = wall
    rows = check(scenario, values)
    result = {
        "scenario": scenario.name,
        "seed": scenario.seed,
        "parameters": scenario.parameters,
        "source": str(scenario.source),
        "world": world.name,
        "passed": all(r["passed"] for r in rows),
        "criteria": rows,
        "metrics": values,
    }
    (out / "result.json").write_text(json.dumps(result, indent=2, default=float))
    goal = None
    if scenario.goal:
        x, y, _, yaw = find_object(world, scenario.goal, "goal").pose
        goal = (x, y, yaw)
    path = np.column_stack([run["x"], run["y"], run["yaw"]])
    plot_run(out / "run.png", world, path, goal=goal, metrics=headline(values), title=scenario.name)
    if markers:
        frames = load_frames(out / "markers.json")
        plot_markers(out / "markers.png", world, run, frames, f"{scenario.name}: ~markers")
    if sheet:
        try:
            write_contact_sheet(
                out / "camera.mp4", out / "contact_sheet.png", scenario.rate_hz, sheet
            )
        except ValueError as error:
            raise RuntimeError(str(error)) from None
    return result


def play(scenario: Scenario, out: Path, video: bool, **options: Any) -> dict:
    """run_one's result (in out/<scenario name>; `options`: run_one's progress, sheet and
    markers), or an error entry when the scenario could not be run."""
    try:
        return run_one(scenario, out / scenario.name, video, **options)
    except (RuntimeError, subprocess.SubprocessError, ScenarioError, WorldError) as error:
        return error_entry(scenario, str(error))


def error_entry(scenario: Scenario, message: str) -> dict:
    """The result of a run that could not be played."""
    return {
        "scenario": scenario.name,
        "seed": scenario.seed,
        "parameters": scenario.parameters,
        "source": str(scenario.source),
        "passed": False,
        "error": message,
    }


def describe(result: dict) -> list[str]:
    """The lines printed for one finished run."""
    if "error" in result:
        return [f"{result['scenario']}: ERROR {result['error']}"]
    lines = [f"{result['scenario']}:"]
    for row in result["criteria"]:
        mark = "ok  " if row["passed"] else "FAIL"
        lines.append(f"  {mark} {row['metric']} = {format_value(row['value'])} ({row['rule']})")
    lines.append(f"  {'PASS' if result['passed'] else 'FAIL'} {headline_text(result)}")
    return lines


def run_all(
    scenarios: list[Scenario],
    out: Path,
    video: bool = False,
    jobs: int = 1,
    sheet: int = 0,
    markers: bool = False,
) -> list[dict]:
    """Every scenario's result (in the given order), `jobs` at a time, with a progress bar."""
    results: list[dict | None] = [None] * len(scenarios)
    with (
        ThreadPoolExecutor(max_workers=jobs) as pool,
        tqdm(total=len(scenarios), unit="run", file=sys.stderr) as progress,
    ):
        # One run at a time: its sim time too.
        futures = {
            pool.submit(play, s, out, video, progress=jobs == 1, sheet=sheet, markers=markers): i
            for i, s in enumerate(scenarios)
        }
        for future in as_completed(futures):
            result = results[futures[future]] = future.result()
            progress.write("\n".join(describe(result)))
            progress.update()
    return [r for r in results if r is not None]  # every one, each future having finished
