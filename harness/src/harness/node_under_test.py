"""One node and one client script in a ROS graph of their own: the rostest pattern, for pytest.

The client is a script (usually the test file itself run with --client) that talks to the node
and prints its findings as JSON on its last line of output.
"""

from __future__ import annotations

import json
import os
import subprocess
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager

from harness.run_scenario import MASTER_START_ATTEMPTS, start_master, stop, use_sim_time


@contextmanager
def private_master(sim_time: bool = False) -> Iterator[dict[str, str]]:
    """A ROS master of its own on a free port; yields the environment that points at it.

    rosmaster alone, as roscore starts it but without roslaunch and the rosout node (nodes publish
    /rosout all the same): ~0.45 s of CPU to start against roscore's ~1.6. A port another program
    takes between the probe and the master's bind is tried again with another."""
    env = dict(os.environ)
    started = start_master(
        ["rosmaster", "--core"], env,
        lambda command: subprocess.Popen(
            command, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT
        ),
    )  # fmt: skip
    if started is None:
        raise RuntimeError(f"no ROS master started in {MASTER_START_ATTEMPTS} attempts")
    master, _ = started
    try:
        if sim_time:
            use_sim_time(env)
        yield env
    finally:
        stop(master)


def run_with_client(
    node: list[str], client: list[str], timeout: float, sim_time: bool = False
) -> dict:
    """Starts `rosrun NODE...`, runs `client` to the end, checks the node outlived it and returns
    the client's last line of output as JSON."""
    with private_master(sim_time) as env:
        process = subprocess.Popen(
            ["rosrun", *node], env=env, stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT
        )
        try:
            done = subprocess.run(client, env=env, capture_output=True, text=True, timeout=timeout)
            assert process.poll() is None, f"{' '.join(node)} died (exit {process.returncode})"
        finally:
            stop(process)
    assert done.returncode == 0, done.stdout + done.stderr
    return json.loads(done.stdout.strip().splitlines()[-1])


class WatchedProcess:
    """A process whose output (stdout and stderr merged) is collected line by line while it runs,
    so a test can wait for what it says."""

    def __init__(self, args: list[str], env: dict[str, str]):
        self.process = subprocess.Popen(
            args, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True
        )
        self.lines: list[str] = []
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        for line in self.process.stdout:
            self.lines.append(line)

    def wait_for(self, text: str, timeout: float) -> bool:
        """Whether a line with `text` arrives within `timeout` s (False at once if it exits)."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if any(text in line for line in self.lines):
                return True
            if not self._reader.is_alive():
                return any(text in line for line in self.lines)
            time.sleep(0.05)
        return False

    def output(self) -> str:
        """Everything it said; after it has exited, all of it."""
        if self.process.poll() is not None:
            self._reader.join(5.0)
        return "".join(self.lines)
