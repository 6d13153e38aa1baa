"""Harness benchmarks for `make bench`: renderer frames per second per world (one core), and
lockstep steps per second against the scripted constant-Twist node."""

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import cv2

from harness.render import bench_render
from harness.world import WORLDS_DIR
from harness.world_file import load_world

LOCKSTEP_SCENARIO = WORLDS_DIR / "scenarios" / "bench_lockstep.yaml"


def main() -> int:
    cv2.setNumThreads(1)
    print("renderer, 640x480, one thread (goal >= 300 fps)")
    for path in sorted(WORLDS_DIR.glob("*.yaml")):  # every shipped world
        fps = bench_render(load_world(path), 300)
        print(f"  {path.stem:<16} {fps:7.0f} fps")
    with tempfile.TemporaryDirectory() as out:
        started = time.monotonic()
        subprocess.run(
            ["rosrun", "harness", "run_scenario", str(LOCKSTEP_SCENARIO), "--out", out],
            check=True,
            stdout=subprocess.DEVNULL,
            env=dict(os.environ),
        )
        total = time.monotonic() - started
        result = json.loads((Path(out) / "bench_lockstep" / "result.json").read_text())
    sim, wall = result["metrics"]["sim_time"], result["metrics"]["loop_wall_time"]
    steps = result["metrics"]["steps"]
    print("lockstep with the constant-Twist node (goal: 60 s of sim time in <= 12 s wall)")
    # wall = the stepping loop alone; start-up (roscore, launch) is reported separately.
    print(f"  {sim:.0f} s sim in {wall:.1f} s wall ({total:.1f} s with start-up): "
          f"{steps / wall:.0f} steps/s, {sim / wall:.1f}x real time")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
