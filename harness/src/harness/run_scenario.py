"""`rosrun harness run_scenario SCENARIO.yaml [...] [--jobs N | --scheduler tcp://HOST:PORT]
[--out DIR] [--video] [--contact-sheet [N]] [--markers]`

Plays each scenario in a ROS graph of its own: its own roscore on a free port, its own ROS_HOME
and log folder, the behaviour's launch file (or the scripted constant-Twist driver), then the
simulator in lockstep; with --jobs N, N scenarios at a time on this machine; with --scheduler,
each run is a task on that Dask cluster (played the same way on a worker, in a temporary
folder sent back and unpacked under DIR). Afterwards it scores each recorded
run and writes DIR/<scenario>/result.json (all metrics and each criterion), run.png (floor map
with the driven path), with --video camera.mp4, and with --contact-sheet contact_sheet.png (N
frames of the camera video with the behaviour's debug overlay, in a grid), with --markers
markers.json (the behaviour's ~markers, harness.marker_record) and markers.png (some of them
placed by the true pose over the floor, harness.marker_map); DIR/summary.json and
DIR/report.md add up all runs (success rate with its 95 % Wilson interval). Exits 1 when a
criterion fails, 2 when a scenario cannot be run.
"""

from __future__ import annotations

import argparse
import fnmatch
import json
import math
import os
import signal
import socket
import subprocess
import sys
import threading
import time
import xmlrpc.client
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor, as_completed
from pathlib import Path
from xml.etree import ElementTree

import numpy as np
import roslaunch.rlutil
import yaml
from tqdm import tqdm

from harness.camera import Camera
from harness.contact_sheet import DEFAULT_FRAMES, write_contact_sheet
from harness.marker_map import load_frames, plot_markers
from harness.node_cli import BEHAVIOUR_GONE
from harness.plot import plot_run
from harness.report import format_value, headline, headline_text, write_summary
from harness.scenario import (
    Scenario,
    ScenarioError,
    check,
    find_object,
    load_scenarios,
    metrics,
    scenario_world,
)
from harness.world import WorldError

MASTER_START_TIMEOUT = 20.0  # wall s
MASTER_START_ATTEMPTS = 3  # a port another program takes between our probe and roscore's bind
# Wall-clock allowance on top of the scenario's sim duration (start-up, slow machines).
RUN_TIMEOUT_FLOOR = 120.0
# A single run's progress in a log (stderr not a terminal): a line per this share of its duration.
PROGRESS_LOG_STEP = 0.1

_ports_lock = threading.Lock()
_ports_handed_out: set[int] = set()


def free_port() -> int:
    """A port the OS calls free and that no other run of this process was given."""
    while True:
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            port = s.getsockname()[1]
        with _ports_lock:
            if port not in _ports_handed_out:
                _ports_handed_out.add(port)
                return port


def wait_for_port(port: int, timeout: float, process: subprocess.Popen | None = None) -> bool:
    """Whether something listens on `port` within `timeout` (giving up once `process` exits)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and (process is None or process.poll() is None):
        with socket.socket() as s:
            if s.connect_ex(("127.0.0.1", port)) == 0:
                return True
        time.sleep(0.05)
    return False


def parent_pid(pid: int) -> int:
    with open(f"/proc/{pid}/stat") as stat:
        return int(stat.read().rsplit(")", 1)[1].split()[1])


def master_is_ours(port: int, process: subprocess.Popen) -> bool:
    """The master answering on `port` is `process` (a rosmaster) or the rosmaster it started (a
    roscore), not another run's: a free port can be taken by another process between the probe
    and the master's bind."""
    try:
        code, _, pid = xmlrpc.client.ServerProxy(f"http://127.0.0.1:{port}").getPid("/run_scenario")
        return code == 1 and process.pid in (pid, parent_pid(pid))
    except (OSError, xmlrpc.client.Error, ValueError, IndexError):
        return False


def start_master(
    command: list[str], env: dict[str, str], popen: Callable[[list[str]], subprocess.Popen]
) -> tuple[subprocess.Popen, int] | None:
    """`command` (roscore, or rosmaster --core) started by `popen` with -p on a free port, and
    that port; `env`'s ROS_MASTER_URI points at it. A port another program takes between the
    probe and the master's bind is tried again with another; None when every attempt failed."""
    for _ in range(MASTER_START_ATTEMPTS):
        port = free_port()
        env["ROS_MASTER_URI"] = f"http://127.0.0.1:{port}"
        master = popen([*command, "-p", str(port)])
        if wait_for_port(port, MASTER_START_TIMEOUT, master) and master_is_ours(port, master):
            return master, port
        stop(master)
    return None


def use_sim_time(env: dict[str, str]) -> None:
    """Sets /use_sim_time on the master `env` points at, by XML-RPC (no rosparam process)."""
    code, message, _ = xmlrpc.client.ServerProxy(env["ROS_MASTER_URI"]).setParam(
        "/run_scenario", "/use_sim_time", True
    )
    if code != 1:
        raise RuntimeError(f"could not set /use_sim_time: {message}")


def wait_for_node(port: int, node: str, timeout: float, process: subprocess.Popen) -> bool:
    """Whether `node` registers with the master on `port` within `timeout` (giving up once
    `process`, the one starting it, exits)."""
    master = xmlrpc.client.ServerProxy(f"http://127.0.0.1:{port}")
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and process.poll() is None:
        if master.lookupNode("/run_scenario", node)[0] == 1:
            return True
        time.sleep(0.1)
    return False


def stop(*processes: subprocess.Popen | None, timeout: float = 10.0) -> None:
    """SIGINT (what roslaunch and rospy shut down cleanly on) to all of them at once, so their
    shut-downs overlap; then harder for any still running after `timeout`."""
    running = [p for p in processes if p is not None and p.poll() is None]
    for process in running:
        process.send_signal(signal.SIGINT)
    deadline = time.monotonic() + timeout
    for process in running:
        try:
            process.wait(max(0.0, deadline - time.monotonic()))
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()


def declared_args(package: str, launch_file: str) -> set[str]:
    """The names of the args a launch file declares at its top level."""
    path = roslaunch.rlutil.resolve_launch_arguments([package, launch_file])[0]
    return {arg.get("name") for arg in ElementTree.parse(path).getroot().findall("arg")}


def behaviour_command(scenario: Scenario) -> list[str]:
    if scenario.behaviour is None:
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
            process = subprocess.Popen(command, env=env, stdout=log, stderr=subprocess.STDOUT)
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


def play(
    scenario: Scenario,
    out: Path,
    video: bool,
    progress: bool = False,
    sheet: int = 0,
    markers: bool = False,
) -> dict:
    """run_one's result, or an error entry when the scenario could not be run."""
    try:
        return run_one(scenario, out / scenario.name, video, progress, sheet, markers)
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
            pool.submit(play, s, out, video, jobs == 1, sheet, markers): i
            for i, s in enumerate(scenarios)
        }
        for future in as_completed(futures):
            result = results[futures[future]] = future.result()
            progress.write("\n".join(describe(result)))
            progress.update()
    return results


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "scenarios", nargs="+", type=Path, help="scenario YAML files (plain, matrices or sweeps)"
    )
    parser.add_argument(
        "--select",
        action="append",
        metavar="PATTERN",
        help="only the runs whose name matches this shell pattern (repeatable), "
        "e.g. 'parker_tag/d2_off20_b60' or 'follower/gain*'",
    )
    parser.add_argument("--out", type=Path, default=Path("out/scenarios"), help="output folder")
    parser.add_argument("--video", action="store_true", help="also write camera.mp4")
    parser.add_argument(
        "--contact-sheet",
        type=int,
        nargs="?",
        const=DEFAULT_FRAMES,
        default=0,
        metavar="N",
        help=f"also write contact_sheet.png: N frames (default {DEFAULT_FRAMES}) of the camera "
        "video with the behaviour's debug overlay, in a grid (records the video)",
    )
    parser.add_argument(
        "--markers",
        action="store_true",
        help="also record the behaviour's ~markers (markers.json) and draw them over the floor "
        "(markers.png)",
    )
    parser.add_argument(
        "--jobs", type=int, default=1, help="scenarios run at once, each in its own ROS graph"
    )
    parser.add_argument(
        "--scheduler",
        metavar="tcp://HOST:PORT",
        help="run each scenario as a task on this Dask scheduler's workers instead (each worker "
        "needs this workspace built and sourced; --jobs does not apply)",
    )
    args = parser.parse_args(argv)
    if args.jobs < 1:
        parser.error(f"--jobs must be at least 1, got {args.jobs}")
    if args.contact_sheet < 0:
        parser.error(f"--contact-sheet must be at least 1 frame, got {args.contact_sheet}")

    try:
        scenarios = [s for p in args.scenarios for s in load_scenarios(p)]
    except (ScenarioError, WorldError) as error:
        print(f"run_scenario: {error}", file=sys.stderr)
        return 2
    if args.select:
        scenarios = [
            s for s in scenarios if any(fnmatch.fnmatchcase(s.name, p) for p in args.select)
        ]
        if not scenarios:
            print(f"run_scenario: no run matches {' or '.join(args.select)}", file=sys.stderr)
            return 2
    if args.scheduler:
        from harness.cluster import run_on_cluster  # Dask only when asked for

        try:
            results = run_on_cluster(scenarios, args.out, args.scheduler, args.video)
        except OSError as error:  # no scheduler at that address (distributed's timeouts too)
            print(f"run_scenario: scheduler {args.scheduler}: {error}", file=sys.stderr)
            return 2
    else:
        results = run_all(
            scenarios, args.out, args.video, args.jobs, args.contact_sheet, args.markers
        )
    summary = write_summary(args.out, results)
    width = max(len(r["scenario"]) for r in results)
    print("\nsummary")
    for result in results:
        verdict = "ERROR" if "error" in result else "PASS" if result["passed"] else "FAIL"
        print(f"  {result['scenario']:<{width}}  {verdict:<5}  {headline_text(result)}")
    overall = summary["overall"]
    low, high = overall["success_interval_95"]
    print(
        f"{overall['passed']}/{overall['runs']} passed ({overall['errors']} could not run), "
        f"success rate {overall['success_rate']:.3f} (95 % Wilson interval {low:.3f}-{high:.3f})"
    )
    print(f"results in {args.out} (summary.json, report.md)")
    if overall["errors"]:
        return 2
    return 0 if overall["passed"] == overall["runs"] else 1


if __name__ == "__main__":
    sys.exit(main())
