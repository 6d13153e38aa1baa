"""`roslaunch follow_bot course.launch` as a person runs it, in real time (the default) and in
lockstep: Ctrl-C leaves the robot with a zero Twist as the last command on /cmd_vel."""

import os
import signal
import subprocess
import time

import pytest

from harness.run_scenario import free_port, stop, wait_for_port


@pytest.mark.parametrize("lockstep", ["false", "true"])
def test_ctrl_c_ends_with_a_zero_twist(lockstep):
    port = free_port()
    env = dict(os.environ, ROS_MASTER_URI=f"http://127.0.0.1:{port}", ROS_IP="127.0.0.1")
    roscore = subprocess.Popen(
        ["roscore", "-p", str(port)], env=env, stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT
    )
    launch = echo = None
    try:
        assert wait_for_port(port, 20.0)
        echo = subprocess.Popen(
            ["rostopic", "echo", "-p", "/cmd_vel"],
            env=env, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
        )  # fmt: skip
        launch = subprocess.Popen(
            ["roslaunch", "follow_bot", "course.launch", f"lockstep:={lockstep}"],
            env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
        )  # fmt: skip
        # Drive until the follower commands a real speed (well past start-up).
        deadline = time.monotonic() + 90.0
        while True:
            line = echo.stdout.readline()
            assert line and time.monotonic() < deadline, "the follower never drove"
            fields = line.strip().split(",")
            if fields[0] != "%time" and float(fields[1]) > 0.2:
                break
        time.sleep(2.0)
        launch.send_signal(signal.SIGINT)  # Ctrl-C
        launch.wait(30)
        time.sleep(1.0)
    finally:
        stop(launch)
        stop(echo)
        stop(roscore)
    last = [line for line in echo.stdout.read().splitlines() if line and line[0] != "%"][-1]
    # %time, linear x y z, angular x y z
    assert [float(v) for v in last.split(",")[1:]] == [0.0] * 6, last
    assert "[sim-1] process has died" not in launch.stdout.read()
