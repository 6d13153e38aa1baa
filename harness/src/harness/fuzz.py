"""Seeded fuzzer for the camera nodes: malformed and random frames, CameraInfo and odometry.

Starts a roscore of its own (a free port) and every node under test as its own process, sends
each node a seeded storm (or the named crash cases), then checks per node that the original
process is still alive, that a valid frame afterwards gets the right answer, that every
Twist it ever published was finite and within the limits, and that the node's own counters on
/diagnostics (frames accepted, dropped by reason; camera_infos accepted and dropped) match, per
reason, what the fuzzer knows it sent (count_errors). Prints one line of counts per node, the
counters as counted/expected, and a JSON summary; exits 1 when any node fails.

    rosrun harness fuzz --messages 10000 --seed 1          # the storm, every node
    rosrun harness fuzz --cases          # the known killers, each on fresh nodes
    rosrun harness fuzz --nodes parker_tag parker_sign --messages 500
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

from harness.fuzz_cases import (
    CAMERA_INFO_OUTCOMES,
    COMPRESSED_CASES,
    FRAME_OUTCOMES,
    Storm,
    crash_cases,
)
from harness.fuzz_driver import PROCESSED_TIMEOUT_S, FuzzedNode
from harness.processes import private_master
from harness.testing import NODES


class Dispatch:
    """A subscriber callback that can be pointed at the nodes of each run in turn."""

    def __init__(self):
        self.callback = lambda msg: None

    def __call__(self, msg):
        self.callback(msg)


def run(keys, messages, seed, cases, log_dir: Path, pause: float) -> list[dict]:
    log_dir.mkdir(parents=True, exist_ok=True)
    with private_master() as env:
        env.pop("ROS_NAMESPACE", None)
        os.environ.update(ROS_MASTER_URI=env["ROS_MASTER_URI"])
        import rospy

        rospy.init_node("fuzzer", anonymous=True, disable_signals=True)
        try:
            return run_batches(keys, messages, seed, cases, log_dir, pause, env)
        finally:
            rospy.signal_shutdown("fuzzing done")


def run_batches(keys, messages, seed, cases, log_dir: Path, pause: float, env: dict) -> list[dict]:
    """The storm (or each crash case) on fresh copies of the nodes, under a running master."""
    import rospy
    from diagnostic_msgs.msg import DiagnosticArray

    results = []
    diagnostics = Dispatch()
    rospy.Subscriber("/diagnostics", DiagnosticArray, diagnostics, queue_size=100)
    batches = [(case, msgs) for case, msgs in crash_cases().items()] if cases else [("storm", None)]
    for run_index, (case, case_msgs) in enumerate(batches):
        compressed = case in COMPRESSED_CASES
        nodes = [FuzzedNode(k, NODES[k], env, log_dir / case, run_index, compressed) for k in keys]
        by_status = {node.diagnostics_name(): node for node in nodes}
        diagnostics.callback = lambda array, nodes=by_status: [
            nodes[s.name].on_diagnostics({kv.key: kv.value for kv in s.values})
            for s in array.status
            if s.name in nodes
        ]
        for node in nodes:
            if not node.wait_connected(30.0):
                raise RuntimeError(f"{node.key} did not start (see {node.log.name})")
        for node in nodes:
            node.prepare()
        if case_msgs is not None:
            for msg in case_msgs:
                for node in nodes:
                    node.send(msg)  # a case's camera_info: its fate not predicted
                time.sleep(0.1)
                for node in nodes:
                    node.keep_capturing()
        else:
            storm_all(nodes, messages, seed, pause)
        time.sleep(0.3)
        # A capture aborts after ~frame_timeout (1 s) without frames: probe it first.
        for node in sorted(nodes, key=lambda n: not n.spec.capturing):
            result = node.finish()
            result["case"] = case
            results.append(result)
    return results


def storm_all(nodes, messages: int, seed: int, pause: float):
    """Each node gets its own seeded storm, interleaved so they run side by side."""
    storms = {node.key: Storm(seed + i) for i, node in enumerate(nodes)}
    for _ in range(messages):
        for node in nodes:
            storm = storms[node.key]
            r = storm.rng.random()
            if r < 0.15:
                info, usable = storm.camera_info()
                node.send(info, usable)
            elif r < 0.2:
                # A capture must stay running: its yaw only ever garbage, never another heading.
                node.send(storm.odom(random_yaw=not node.spec.capturing))
            else:
                node.send(storm.image())
        for node in nodes:
            node.wait_processed(PROCESSED_TIMEOUT_S)
        # Valid frames cost real work; give the slowest node time to take the next message.
        time.sleep(pause)


def print_table(results: list[dict]) -> None:
    head = f"{'case':<18}{'node':<20}{'messages':>9}{'crashes':>8}{'non-finite':>11}"
    print(head + f"{'over-limit':>11}{'twists':>8}  probe")
    for r in results:
        print(
            f"{r['case']:<18}{r['node']:<20}{r['messages']:>9}{r['crashes']:>8}"
            f"{r['non_finite']:>11}{r['over_limit']:>11}{r['twists']:>8}  {r['probe']}"
        )
    counted = [r for r in results if r["expected"] is not None]
    if not counted:
        return
    # The nodes' own counters, each as counted/expected; received: frames and camera_infos.
    short = {"frames_accepted": "accepted", "camera_info_accepted": "info ok"}
    short |= {k: k.removeprefix("dropped_") for k in FRAME_OUTCOMES + CAMERA_INFO_OUTCOMES[1:]}
    keys = FRAME_OUTCOMES + CAMERA_INFO_OUTCOMES
    print(f"\n{'case':<18}{'node':<20}{'received':>11}" + "".join(f"{short[k]:>16}" for k in keys))
    for r in counted:
        got, want = r["counts"], r["expected"]
        received = f"{sum(got.values())}/{sum(want.values())}"
        cells = "".join(
            f"{got.get(k, 0)}/{want[k]}".rjust(16) if k in want else f"{'-':>16}" for k in keys
        )
        errors = "; ".join(r["count_errors"])
        print(f"{r['case']:<18}{r['node']:<20}{received:>11}{cells}  {errors}")


def failed(result: dict) -> bool:
    return bool(
        result["crashes"] or result["non_finite"] or result["over_limit"] or result["count_errors"]
    ) or (result["probe"] != "ok")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--nodes", nargs="+", choices=list(NODES), default=list(NODES))
    parser.add_argument("--messages", type=int, default=10000, help="messages per node")
    parser.add_argument("--seed", type=int, default=12)
    parser.add_argument("--cases", action="store_true", help="the known crash cases instead")
    parser.add_argument("--pause", type=float, default=0.002, help="wall s between rounds")
    parser.add_argument("--logs", type=Path, default=Path("/tmp/follow_bot_fuzz"))
    parser.add_argument("--json", type=Path, help="write the results here")
    args = parser.parse_args(argv)
    results = run(args.nodes, args.messages, args.seed, args.cases, args.logs, args.pause)
    print_table(results)
    if args.json:
        args.json.write_text(json.dumps(results, indent=1))
    return 1 if any(failed(r) for r in results) else 0


if __name__ == "__main__":
    sys.exit(main())
