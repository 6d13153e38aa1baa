"""run_scenario --scheduler: the runs as tasks on a Dask cluster equal a serial run.

A local Dask scheduler and two workers (`dask scheduler`, `dask worker`, one task at a time
each) on loopback, with free ports; each task plays its run in a ROS graph of its own on the
worker and sends the run's folder back. Lockstep makes every metric and every recorded step
identical to the serial run's.
"""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from harness.processes import free_port
from harness.report import without_wall_clock
from harness.testing import REPO

# Infrastructure checks of a minute or more each: `make test-full` plays them, so `make test`
# keeps within its 12 minutes with every bad-input, fault and scenario-family test.
pytestmark = pytest.mark.full

SCENARIOS = REPO / "worlds" / "scenarios"
RUNS = ("constant_arc", "drive_parking")  # short lockstep runs with the scripted driver
DASK_BIN = Path(sys.executable).parent  # the venv's `dask` command line


@pytest.fixture
def scheduler(tmp_path):
    """The address of a scheduler with two workers connected."""
    from distributed import Client

    port = free_port()
    address = f"tcp://127.0.0.1:{port}"
    commands = [["scheduler", "--port", str(port)]] + [
        ["worker", address, "--nthreads", "1", "--local-directory", str(tmp_path / f"worker{i}")]
        for i in range(2)
    ]
    processes = [
        subprocess.Popen(
            [DASK_BIN / "dask", *command, "--host", "127.0.0.1", "--no-dashboard"],
            cwd=tmp_path,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )  # fmt: skip
        for command in commands
    ]
    try:
        with Client(address, timeout="60s") as client:
            client.wait_for_workers(2, timeout=60)
        yield address
    finally:
        for process in reversed(processes):
            process.terminate()
        for process in processes:
            try:
                process.wait(timeout=30)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait()


def play(out: Path, *options: str) -> dict:
    files = [str(SCENARIOS / f"{name}.yaml") for name in RUNS]
    done = subprocess.run(
        ["rosrun", "harness", "run_scenario", *files, "--out", str(out), *options],
        timeout=600,
        stdout=subprocess.DEVNULL,
    )
    assert done.returncode == 0
    return json.loads((out / "summary.json").read_text())


def replayable(summary: dict) -> dict:
    """The summary's runs and overall figures, without the wall-clock metrics."""
    runs = [{**run, "metrics": without_wall_clock(run["metrics"])} for run in summary["runs"]]
    return {"runs": runs, "overall": summary["overall"]}


def test_cluster_runs_equal_serial_runs(scheduler, tmp_path):
    serial = play(tmp_path / "serial")
    cluster = play(tmp_path / "cluster", f"--scheduler={scheduler}")
    assert [run["name"] for run in cluster["runs"]] == list(RUNS)
    assert cluster["overall"]["passed"] == 2 and cluster["overall"]["success_rate"] == 1.0
    assert replayable(cluster) == replayable(serial)
    for name in RUNS:
        folder = tmp_path / "cluster" / name  # the worker's artefacts, gathered back
        assert json.loads((folder / "result.json").read_text())["passed"] is True
        assert (folder / "run.png").stat().st_size > 10_000
        assert "roscore" in (folder / "ros.log").read_text()
        serial_record = np.load(tmp_path / "serial" / name / "record.npz")
        cluster_record = np.load(folder / "record.npz")
        for key in set(serial_record.files) - {"loop_wall"}:
            np.testing.assert_array_equal(serial_record[key], cluster_record[key], err_msg=key)
    assert len(np.load(tmp_path / "cluster" / "constant_arc" / "record.npz")["t"]) == 120


def test_an_unreachable_scheduler_is_a_clear_error(tmp_path):
    done = subprocess.run(
        ["rosrun", "harness", "run_scenario", str(SCENARIOS / "constant_arc.yaml"),
         "--out", str(tmp_path), f"--scheduler=tcp://127.0.0.1:{free_port()}"],
        timeout=120, capture_output=True, text=True,
        env=dict(os.environ, DASK_DISTRIBUTED__COMM__TIMEOUTS__CONNECT="3s"),
    )  # fmt: skip
    assert done.returncode == 2
    assert "run_scenario: scheduler tcp://127.0.0.1:" in done.stderr
