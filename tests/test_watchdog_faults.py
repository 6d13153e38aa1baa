"""Fault tests for every behaviour node under sim time (/clock published by the test):

- frames stop while /clock runs: one zero Twist within 0.2 s, nothing after;
- /clock jumps back 100 s: the node keeps answering, and the watchdog still stops it;
- /clock and frames stop together (the simulator died): one zero Twist within 0.3 s of wall
  time (the steady-clock watchdog), nothing after.

The ROS client runs in a child process (this file with --client), so the test process never
initialises rospy and every node gets a master of its own.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time

import pytest

from harness.fuzz import NODES, camera_info_msg, probe_frame
from harness.run_scenario import free_port, stop, wait_for_port

RATE_HZ = 30.0
BEHAVIOURS = ["follower", "beacon_follow", "parker_tag"]


def client(key: str) -> None:
    import rospy
    from geometry_msgs.msg import Twist
    from rosgraph_msgs.msg import Clock
    from sensor_msgs.msg import CameraInfo, Image

    rospy.init_node("fault_client", disable_signals=True)
    clock_pub = rospy.Publisher("/clock", Clock, queue_size=1, tcp_nodelay=True)
    image_pub = rospy.Publisher("/camera/rgb/image_raw", Image, queue_size=1, tcp_nodelay=True)
    info_pub = rospy.Publisher("/camera/rgb/camera_info", CameraInfo, queue_size=1)
    sim_time = [1000.0]  # the next /clock value
    published = [0.0]  # the last /clock value sent: a Twist's arrival time on the sim clock
    last_frame = {"wall": 0.0, "sim": 0.0}
    twists: list[tuple[float, float, float, float]] = []  # (wall, sim, linear, angular)
    rospy.Subscriber(
        "/cmd_vel", Twist,
        lambda m: twists.append((time.monotonic(), published[0], m.linear.x, m.angular.z)),
        tcp_nodelay=True,
    )  # fmt: skip

    def tick(frame: bool) -> None:
        clock = Clock()
        clock.clock = rospy.Time.from_sec(sim_time[0])
        clock_pub.publish(clock)
        published[0] = sim_time[0]
        if frame:
            msg = probe_frame(NODES[key].probe)
            msg.header.stamp = clock.clock
            image_pub.publish(msg)
            last_frame.update(wall=time.monotonic(), sim=sim_time[0])
        info_pub.publish(camera_info_msg())
        time.sleep(1.0 / RATE_HZ)
        sim_time[0] += 1.0 / RATE_HZ

    deadline = time.monotonic() + 30
    while image_pub.get_num_connections() == 0 and time.monotonic() < deadline:
        time.sleep(0.05)

    sent = [0]

    def run(seconds: float, frames: bool, clock: bool = True) -> tuple[float, list]:
        """Ticks for `seconds` of wall time; returns the wall start and the Twists in it."""
        time.sleep(0.05)  # the answer to the last frame of the previous phase
        start = len(twists)
        sent[0] = 0
        t0 = time.monotonic()
        while time.monotonic() - t0 < seconds:
            if clock:
                tick(frames)
                sent[0] += frames
            else:
                time.sleep(1.0 / RATE_HZ)
        return t0, twists[start:]

    def outage(clock: bool) -> dict:
        """Frames stop (and /clock with them unless `clock`): the stop's delay after the last
        frame, in sim time while the clock runs, else in wall time."""
        since = dict(last_frame)
        _, during = run(1.2, frames=False, clock=clock)
        zeros = [(t, sim) for t, sim, v, w in during if v == 0.0 and w == 0.0]
        delay = None
        if zeros:
            delay = zeros[0][1] - since["sim"] if clock else zeros[0][0] - since["wall"]
        return {
            "twists": len(during),
            "zeros": len(zeros),
            "stop_after_s": delay,
            "moving": sum(1 for _, _, v, w in during if v != 0.0 or w != 0.0),
        }

    result = {}
    _, driving = run(1.5, frames=True)
    result["driving_twists"], result["driving_frames"] = len(driving), sent[0]
    result["frames_stop"] = outage(clock=True)
    sim_time[0] -= 100.0  # /clock jumps back
    _, after_jump = run(1.0, frames=True)
    result["after_jump_twists"] = len(after_jump)
    result["after_jump_frames"] = sent[0]
    result["after_jump_stop"] = outage(clock=True)
    run(1.0, frames=True)
    result["clock_and_frames_stop"] = outage(clock=False)
    print(json.dumps(result))


@pytest.fixture(scope="module", params=BEHAVIOURS)
def faults(request) -> tuple[str, dict]:
    key = request.param
    spec = NODES[key]
    port = free_port()
    env = dict(os.environ, ROS_MASTER_URI=f"http://127.0.0.1:{port}")
    master = subprocess.Popen(["roscore", "-p", str(port)], env=env, stdout=subprocess.DEVNULL)
    node = None
    try:
        assert wait_for_port(port, 20.0)
        subprocess.run(["rosparam", "set", "/use_sim_time", "true"], env=env, check=True)
        params = [f"_{k}:={v}" for k, v in spec.params.items()]
        node = subprocess.Popen(
            ["rosrun", spec.package, spec.executable, *params], env=env,
            stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT,
        )  # fmt: skip
        done = subprocess.run(
            [sys.executable, __file__, "--client", key],
            env=env, capture_output=True, text=True, timeout=120,
        )  # fmt: skip
        assert node.poll() is None, f"{key} died (exit {node.returncode})"
    finally:
        stop(node)
        stop(master)
    assert done.returncode == 0, done.stdout + done.stderr
    return key, json.loads(done.stdout.strip().splitlines()[-1])


def test_answers_while_frames_flow(faults):
    key, r = faults
    assert r["driving_twists"] >= 0.9 * r["driving_frames"], r


@pytest.mark.parametrize("phase", ["frames_stop", "after_jump_stop"])
def test_frames_stop_one_zero_within_0_2_s_and_nothing_after(faults, phase):
    key, r = faults
    o = r[phase]
    assert o["zeros"] == 1 and o["twists"] == 1, o
    # The clock moves in 1/30 s ticks: 0.2 s is the sixth tick after the last frame.
    assert o["stop_after_s"] <= 0.2 + 1e-6, o


def test_clock_jump_back_keeps_answering(faults):
    key, r = faults
    assert r["after_jump_twists"] >= 0.9 * r["after_jump_frames"], r


def test_clock_and_frames_stop_together_stop_within_0_3_s_wall(faults):
    key, r = faults
    o = r["clock_and_frames_stop"]
    assert o["zeros"] == 1 and o["twists"] == 1, o
    assert o["stop_after_s"] <= 0.3, o


if __name__ == "__main__" and sys.argv[1:2] == ["--client"]:
    client(sys.argv[2])
