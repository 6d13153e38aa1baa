"""Processes of a ROS graph of its own: a master on a free port (guarded against another program
taking the port first), nodes waited for, stopped together; one node and one client script in a
graph of their own, or a launch file and one client (the rostest pattern, for pytest: the client,
usually the test file itself run with --client, talks to the node and prints its findings as JSON
on its last line of output; tests/README.md).
"""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import threading
import time
import xmlrpc.client
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

MASTER_START_TIMEOUT = 20.0  # wall s
MASTER_START_ATTEMPTS = 3  # a port another program takes between our probe and roscore's bind

_ports_lock = threading.Lock()
_ports_handed_out: set[int] = set()
# Every process passed to `tracked`, until stop() has ended it: what stop_all() ends when
# this program is told to stop.
_live_lock = threading.Lock()
_live: set[subprocess.Popen] = set()


def tracked(process: subprocess.Popen) -> subprocess.Popen:
    """`process`, remembered until stop() ends it."""
    with _live_lock:
        _live.add(process)
    return process


def stop_all() -> None:
    """Stops every process `tracked` remembers (for a SIGTERM handler: the program's runs
    must not outlive it, as they would when it is killed)."""
    with _live_lock:
        processes = list(_live)
    stop(*processes)


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


def master_call(uri: str, method: str, *args: Any) -> tuple[int, str, Any]:
    """One ROS master API call by XML-RPC (caller id /run_scenario): (code, message, value)."""
    code, message, value = getattr(xmlrpc.client.ServerProxy(uri), method)("/run_scenario", *args)
    return int(code), str(message), value


def master_is_ours(port: int, process: subprocess.Popen) -> bool:
    """The master answering on `port` is `process` (a rosmaster) or the rosmaster it started (a
    roscore), not another run's: a free port can be taken by another process between the probe
    and the master's bind."""
    try:
        code, _, pid = master_call(f"http://127.0.0.1:{port}", "getPid")
        return code == 1 and process.pid in (pid, parent_pid(int(pid)))
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
    code, message, _ = master_call(env["ROS_MASTER_URI"], "setParam", "/use_sim_time", True)
    if code != 1:
        raise RuntimeError(f"could not set /use_sim_time: {message}")


def wait_for_node(port: int, node: str, timeout: float, process: subprocess.Popen) -> bool:
    """Whether `node` registers with the master on `port` within `timeout` (giving up once
    `process`, the one starting it, exits)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and process.poll() is None:
        if master_call(f"http://127.0.0.1:{port}", "lookupNode", node)[0] == 1:
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
    with _live_lock:
        _live.difference_update(p for p in processes if p is not None)


@contextmanager
def private_master(
    sim_time: bool = False, env: dict[str, str] | None = None, roscore: bool = False
) -> Iterator[dict[str, str]]:
    """A ROS master of its own on a free port; yields the environment (`env`, default this
    process's) pointing at it.

    rosmaster alone, as roscore starts it but without roslaunch and the rosout node (nodes publish
    /rosout all the same): ~0.45 s of CPU to start against roscore's ~1.6; `roscore`: the whole
    core, for a test that reads /rosout_agg or launches onto it. A port another program takes
    between the probe and the master's bind is tried again with another."""
    env = dict(os.environ if env is None else env)
    started = start_master(
        ["roscore"] if roscore else ["rosmaster", "--core"], env,
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
    return client_result(done)


def launch_with_client(
    launch: list[str], client: list[str], timeout: float, roscore: bool = False
) -> dict:
    """Starts `roslaunch LAUNCH...` (on the whole core with `roscore`), runs `client` to the end,
    stops the launch and returns the client's last line of output as JSON."""
    with private_master(roscore=roscore) as env:
        process = subprocess.Popen(
            ["roslaunch", *launch], env=env, stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT
        )
        try:
            done = subprocess.run(client, env=env, capture_output=True, text=True, timeout=timeout)
        finally:
            stop(process)
    return client_result(done)


def client_result(done: subprocess.CompletedProcess) -> dict:
    """A finished client's last line of output as JSON, once it has exited 0."""
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
        assert self.process.stdout is not None  # stdout=PIPE
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
