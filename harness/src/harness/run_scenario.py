"""`rosrun harness run_scenario SCENARIO.yaml [...] [--out DIR] [--video]`

Plays each scenario on a ROS master of its own (a free port, so runs never share topics):
roscore, the behaviour's launch file (or the scripted constant-Twist driver), then the simulator
in lockstep. Afterwards it scores the recorded run and writes DIR/<scenario>/result.json (all
metrics and each criterion), run.png (floor map with the driven path) and, with --video,
camera.mp4. Exits 1 when a criterion fails, 2 when a scenario cannot be run.
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from harness.plot import plot_run
from harness.scenario import (
    Scenario,
    ScenarioError,
    check,
    find_object,
    load_scenario,
    metrics,
)
from harness.world import WorldError, load_world

MASTER_START_TIMEOUT = 20.0  # wall s
# Wall-clock allowance on top of the scenario's sim duration (start-up, slow machines).
RUN_TIMEOUT_FLOOR = 120.0


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_for_port(port: int, timeout: float) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        with socket.socket() as s:
            if s.connect_ex(("127.0.0.1", port)) == 0:
                return True
        time.sleep(0.05)
    return False


def stop(process: subprocess.Popen | None, timeout: float = 10.0) -> None:
    """SIGINT (what roslaunch and rospy shut down cleanly on), then harder."""
    if process is None or process.poll() is not None:
        return
    process.send_signal(signal.SIGINT)
    try:
        process.wait(timeout)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait()


def behaviour_command(scenario: Scenario) -> list[str]:
    if scenario.behaviour is None:
        v, w = scenario.constant_command
        return ["rosrun", "harness", "constant_twist", f"_v:={v}", f"_w:={w}"]
    b = scenario.behaviour
    return ["roslaunch", "--wait", b.package, b.launch_file] + [
        f"{k}:={v}" for k, v in b.args.items()
    ]


def run_one(scenario: Scenario, out: Path, video: bool) -> dict:
    """Runs one scenario end to end; returns the result written to result.json."""
    out.mkdir(parents=True, exist_ok=True)
    world = load_world(scenario.world_path)
    port = free_port()
    env = dict(os.environ, ROS_MASTER_URI=f"http://127.0.0.1:{port}", ROS_IP="127.0.0.1")
    record = out / "record.npz"
    record.unlink(missing_ok=True)
    processes: list[subprocess.Popen] = []
    started = time.monotonic()
    with open(out / "ros.log", "w") as log:

        def start(command: list[str]) -> subprocess.Popen:
            log.write(f"$ {' '.join(command)}\n")
            log.flush()
            process = subprocess.Popen(command, env=env, stdout=log, stderr=subprocess.STDOUT)
            processes.append(process)
            return process

        try:
            start(["roscore", "-p", str(port)])
            if not wait_for_port(port, MASTER_START_TIMEOUT):
                raise RuntimeError(f"roscore did not start on port {port} (see {out}/ros.log)")
            subprocess.run(["rosparam", "set", "/use_sim_time", "true"], env=env, check=True)
            start(behaviour_command(scenario))
            sim_command = [
                "rosrun", "harness", "sim", f"_scenario:={scenario.source}", f"_record:={record}",
            ]  # fmt: skip
            if video:
                sim_command.append(f"_video:={out / 'camera.mp4'}")
            sim = start(sim_command)
            sim.wait(timeout=RUN_TIMEOUT_FLOOR + 20.0 * scenario.duration)
        finally:
            for process in reversed(processes):
                stop(process)
    wall = time.monotonic() - started
    if not record.is_file():
        raise RuntimeError(f"the simulator wrote no record (see {out}/ros.log)")
    run = dict(np.load(record))
    values = metrics(scenario, world, run)
    values["wall_time"] = wall
    rows = check(scenario, values)
    result = {
        "scenario": scenario.name,
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
    return result


def headline(values: dict) -> dict:
    """The few numbers worth a plot title and a summary row."""
    picks = {
        "lap_time": values.get("lap", {}).get("lap_time"),
        "xte_rms_cm": 100 * values["cross_track"]["rms"] if "cross_track" in values else None,
        "xte_max_cm": 100 * values["cross_track"]["max"] if "cross_track" in values else None,
        "stop_dist": values.get("target", {}).get("final_distance"),
        "park_err_cm": 100 * values["parking"]["position_error"] if "parking" in values else None,
        "missed": values["commands"]["missed_replies"],
        "sim_s": values["sim_time"],
        "wall_s": values.get("wall_time"),
    }
    return {k: v for k, v in picks.items() if v is not None}


def format_value(value) -> str:
    return f"{value:.4g}" if isinstance(value, float) else str(value)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scenarios", nargs="+", type=Path, help="scenario YAML files")
    parser.add_argument("--out", type=Path, default=Path("out/scenarios"), help="output folder")
    parser.add_argument("--video", action="store_true", help="also write camera.mp4")
    args = parser.parse_args(argv)

    try:
        scenarios = [load_scenario(p) for p in args.scenarios]
    except (ScenarioError, WorldError) as error:
        print(f"run_scenario: {error}", file=sys.stderr)
        return 2
    summary = []
    status = 0
    for index, scenario in enumerate(scenarios, 1):
        print(f"[{index}/{len(scenarios)}] {scenario.name} ...", flush=True)
        try:
            result = run_one(scenario, args.out / scenario.name, args.video)
        except (RuntimeError, subprocess.SubprocessError, ScenarioError, WorldError) as error:
            print(f"  ERROR {error}", flush=True)
            summary.append((scenario.name, "ERROR", str(error)))
            status = max(status, 2)
            continue
        verdict = "PASS" if result["passed"] else "FAIL"
        for row in result["criteria"]:
            mark = "ok  " if row["passed"] else "FAIL"
            print(f"  {mark} {row['metric']} = {format_value(row['value'])} ({row['rule']})")
        numbers = ", ".join(
            f"{k}={format_value(v)}" for k, v in headline(result["metrics"]).items()
        )
        print(f"  {verdict} {numbers}", flush=True)
        summary.append((scenario.name, verdict, numbers))
        if not result["passed"]:
            status = max(status, 1)
    width = max(len(name) for name, _, _ in summary)
    print("\nsummary")
    for name, verdict, numbers in summary:
        print(f"  {name:<{width}}  {verdict:<5}  {numbers}")
    print(f"results in {args.out}")
    return status


if __name__ == "__main__":
    sys.exit(main())
