"""`roslaunch harness course.launch` as a person runs it, in real time (the default) and in
lockstep: Ctrl-C leaves the robot with a zero Twist as the last command on /cmd_vel. Every read
of the processes' output has a timeout (a process that prints nothing cannot hang the test)."""

import contextlib
import os
import queue
import signal
import subprocess
import threading
import time

import pytest

from harness.processes import private_master, stop

# A closed-loop check of a minute (the lecture launch, two robots), not a bad-input or fault
# test: `make test-full` plays it, so `make test` keeps within its 12 minutes.
pytestmark = pytest.mark.full

ZERO = [0.0] * 6  # linear x y z, angular x y z


class Lines:
    """A process's output lines, read on a thread of their own so that waits can time out."""

    def __init__(self, stream):
        self.lines: queue.Queue[str] = queue.Queue()
        self.seen: list[str] = []
        threading.Thread(target=self._read, args=(stream,), daemon=True).start()

    def _read(self, stream) -> None:
        for line in stream:
            self.lines.put(line.rstrip("\n"))

    def next(self, deadline: float) -> str | None:
        """The next line, or None when none came before `deadline` (monotonic s)."""
        try:
            line = self.lines.get(timeout=max(0.0, deadline - time.monotonic()))
        except queue.Empty:
            return None
        self.seen.append(line)
        return line

    def drain(self) -> list[str]:
        """Every line read so far (what is still queued included)."""
        while self.next(0.0) is not None:
            pass
        return self.seen


def twist_values(line: str) -> list[float] | None:
    """`rostopic echo -p` fields after %time, or None for its header line."""
    fields = line.strip().split(",")
    return None if fields[0] == "%time" else [float(v) for v in fields[1:]]


@pytest.mark.parametrize("lockstep", ["false", "true"])
def test_ctrl_c_ends_with_a_zero_twist(lockstep):
    launch = echo = None
    twists = output = None
    with (
        private_master(env=dict(os.environ, ROS_IP="127.0.0.1"), roscore=True) as env,
        contextlib.ExitStack() as cleanup,
    ):
        cleanup.callback(lambda: stop(launch, echo))
        echo = subprocess.Popen(
            ["rostopic", "echo", "-p", "/cmd_vel"],
            env=env, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
        )  # fmt: skip
        twists = Lines(echo.stdout)
        launch = subprocess.Popen(
            ["roslaunch", "harness", "course.launch", f"lockstep:={lockstep}"],
            env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
        )  # fmt: skip
        output = Lines(launch.stdout)
        # Drive until the follower commands a real speed (well past start-up).
        deadline = time.monotonic() + 90.0
        while True:
            line = twists.next(deadline)
            seen = f"{twists.seen[-3:]}, roslaunch: {output.drain()[-15:]}"
            assert line is not None, f"the follower never drove: {seen}"
            values = twist_values(line)
            if values and values[0] > 0.2:
                break
        time.sleep(2.0)  # driving on, whatever it does then
        launch.send_signal(signal.SIGINT)  # Ctrl-C
        launch.wait(30)
        # Wait for the follower's final zero: the newest line a zero, from what echo printed by
        # the exit on (a zero before it, a watchdog's, is followed by more commands).
        line = (twists.drain() or [""])[-1]
        deadline = time.monotonic() + 10.0
        while line is not None and twist_values(line) != ZERO:
            line = twists.next(deadline)
        assert line is not None, "no zero Twist after Ctrl-C"
    last = [line for line in twists.drain() if line and line[0] != "%"][-1]
    assert twist_values(last) == ZERO, last
    output.drain()
    assert not any("[sim-1] process has died" in line for line in output.seen)
