"""One node and one client script in a ROS graph of their own: the rostest pattern, for pytest.

The client is a script (usually the test file itself run with --client) that talks to the node
and prints its findings as JSON on its last line of output.
"""

from __future__ import annotations

import json
import os
import subprocess
from collections.abc import Iterator
from contextlib import contextmanager

from harness.run_scenario import free_port, stop, wait_for_port


@contextmanager
def private_master(sim_time: bool = False) -> Iterator[dict[str, str]]:
    """A roscore of its own on a free port; yields the environment that points at it."""
    port = free_port()
    env = dict(os.environ, ROS_MASTER_URI=f"http://127.0.0.1:{port}")
    master = subprocess.Popen(["roscore", "-p", str(port)], env=env, stdout=subprocess.DEVNULL)
    try:
        assert wait_for_port(port, 20.0, master), f"roscore on port {port} did not start"
        if sim_time:
            subprocess.run(["rosparam", "set", "/use_sim_time", "true"], env=env, check=True)
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
