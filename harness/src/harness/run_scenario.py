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
import os
import signal
import sys
from pathlib import Path

from harness.contact_sheet import DEFAULT_FRAMES
from harness.processes import stop_all
from harness.report import headline_text, write_summary
from harness.runs import run_all
from harness.scenario import ScenarioError
from harness.scenario_file import load_scenarios
from harness.world import WorldError


def stop_runs_on_sigterm() -> None:
    """SIGTERM (a `timeout`, a CI job cancelled, `kill`) stops every run's ROS graph before the
    program ends, as Ctrl-C does through the terminal's process group: killed alone, it would
    leave each run's roscore, simulator and behaviour running."""

    def handler(signum: int, _frame: object) -> None:
        stop_all()
        os._exit(128 + signum)  # the worker threads' runs are over: nothing to wait for

    signal.signal(signal.SIGTERM, handler)


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
        stop_runs_on_sigterm()
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
