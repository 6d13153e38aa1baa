"""Ctrl-C (SIGINT) and SIGTERM end every C++ node at any time: while roscpp waits for a master
that is not there (it retries without end) the process ends at once, killed by the signal; once
the node runs, it shuts down cleanly (its final stop goes out) and exits 0."""

import os
import signal
import time

import pytest

from harness.processes import WatchedProcess, free_port, private_master, stop

NODES = [
    ("follow_bot", "follower"),
    ("follow_bot", "beacon_chaser"),
    ("follow_bot", "parker"),
    ("follow_bot", "panorama"),
    ("image_converter", "image_converter"),
]
SIGNALS = [signal.SIGTERM, signal.SIGINT]
BOUND_S = 1.0  # from the signal to the end of the process


def ended_within(node: WatchedProcess, signum: int) -> float:
    """Sends `signum`; returns the seconds until the process ended (fails past BOUND_S)."""
    sent = time.monotonic()
    node.process.send_signal(signum)
    try:
        node.process.wait(BOUND_S)
    finally:
        stop(node.process)  # only if it is still running: SIGINT, then SIGKILL
    return time.monotonic() - sent


@pytest.mark.parametrize("signum", SIGNALS, ids=lambda s: signal.Signals(s).name)
@pytest.mark.parametrize("node", NODES, ids=lambda n: n[1])
def test_a_node_waiting_for_the_master_ends_on_a_signal(node, signum, record_property):
    # No master listens on this port: roscpp keeps retrying, saying so.
    env = dict(os.environ, ROS_MASTER_URI=f"http://127.0.0.1:{free_port()}")
    process = WatchedProcess(["rosrun", *node], env)
    assert process.wait_for("Failed to contact master", 30.0), process.output()
    time.sleep(1.0)  # well into the wait
    took = ended_within(process, signum)
    assert process.process.returncode == -signum, process.output()
    record_property("summary", f"{node[1]} without a master, {signum.name}: ended in {took:.3f} s")


@pytest.fixture(scope="module")
def master_env():
    with private_master() as env:
        yield env


@pytest.mark.parametrize("node", NODES, ids=lambda n: n[1])
def test_a_running_node_shuts_down_cleanly_on_sigterm(node, master_env, record_property):
    # The start-up's last step warns of ~params the node does not have: this one says it is done.
    args = ["rosrun", *node, f"__name:=sigterm_{node[1]}", "_started_probe:=1"]
    process = WatchedProcess(args, master_env)
    assert process.wait_for("~started_probe is not a parameter", 30.0), process.output()
    time.sleep(0.2)
    took = ended_within(process, signal.SIGTERM)
    assert process.process.returncode == 0, process.output()
    record_property("summary", f"{node[1]} running, SIGTERM: ended in {took:.3f} s")
