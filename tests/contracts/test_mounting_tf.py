"""The camera's mounting from tf: a behaviour node (the C++ follower, and the Python lab node
line_follower.py by the same rules, follow_bot.mounting) started without a robot description
holds still and says which transform it waits for, drives as soon as the transform appears (with
the mounting tf gives), falls back to its mounting ~params after ~mounting_timeout (said once,
loudly), and needs no tf at all with ~camera_mounting params.

Each case starts a roscore and the node (named follower), then plays line frames from a child
process (this file with --client CASE NODE, tests/README.md) in lockstep on its ~status
(harness.testing.Lockstep), listening to /rosout and, when the case says so, publishing the
robot's static tf itself.
"""

from __future__ import annotations

import json
import math
import sys
import threading
import time

import pytest

from harness.processes import run_with_client
from harness.testing import Lockstep, probe_frame

WAITING = "waiting for camera mounting"
# The mounting the client's static tf gives (not the ~params' default 0.30 m, 20 deg, 0 m).
TF_HEIGHT, TF_PITCH_DEG, TF_X_OFFSET = 0.35, 15.0, 0.05
BASE_LINK_HEIGHT = 0.0102  # base_footprint -> base_link, as harness/robot_description.py
WAIT_MESSAGE = (
    "waiting for the camera mounting: no transform base_link <- 'camera_rgb_optical_frame' in tf"
)


def quaternion_rpy(roll: float, pitch: float, yaw: float) -> tuple[float, float, float, float]:
    """A URDF origin's rpy (fixed axes x, then y, then z) as (x, y, z, w)."""
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return (sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy, cr * cp * cy + sr * sp * sy)  # fmt: skip


def quaternion_product(a, b):
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    )


def publish_robot_tf():
    """base_footprint -> base_link -> camera_rgb_optical_frame: a camera TF_HEIGHT above the
    floor, TF_X_OFFSET ahead, pitched TF_PITCH_DEG down, its optical frame per REP 103."""
    import rospy
    import tf2_ros
    from geometry_msgs.msg import TransformStamped

    def transform(parent, child, xyz, q):
        t = TransformStamped()
        t.header.stamp = rospy.Time.now()
        t.header.frame_id, t.child_frame_id = parent, child
        t.transform.translation.x, t.transform.translation.y, t.transform.translation.z = xyz
        r = t.transform.rotation
        r.x, r.y, r.z, r.w = q
        return t

    optical = quaternion_product(
        quaternion_rpy(0.0, math.radians(TF_PITCH_DEG), 0.0),
        quaternion_rpy(-math.pi / 2, 0.0, -math.pi / 2),
    )
    broadcaster = tf2_ros.StaticTransformBroadcaster()
    broadcaster.sendTransform([
        transform("base_footprint", "base_link", (0.0, 0.0, BASE_LINK_HEIGHT), (0, 0, 0, 1)),
        transform("base_link", "camera_rgb_optical_frame",
                  (TF_X_OFFSET, 0.0, TF_HEIGHT - BASE_LINK_HEIGHT), optical),
    ])  # fmt: skip
    return broadcaster


def client(case: str, node: str) -> dict:
    import rospy
    from rosgraph_msgs.msg import Log

    rospy.init_node("mounting_client", anonymous=True, disable_signals=True)
    lock = threading.Lock()
    logs: list[tuple[int, str]] = []

    def on_log(msg) -> None:
        if msg.name == "/follower":
            with lock:
                logs.append((msg.level, msg.msg))

    rosout = rospy.Subscriber("/rosout", Log, on_log)
    steps = Lockstep("follower", reads_camera_info=node == "follower")
    line = probe_frame("line")
    out: dict = {}
    if case == "tf_appears":
        for _ in range(75):  # 2.5 s of frames at the wall rate: the wait message repeats
            steps.frame(line, wall_rate=True)
        out["before_tf"] = len(steps.statuses)
        keep = publish_robot_tf()  # noqa: F841 (the latched publisher must live)
        for _ in range(60):
            steps.frame(line, wall_rate=True)
            if any(linear > 0.0 for _, linear, _ in steps.twists):
                break
    else:  # fallback after ~mounting_timeout 1 s, or params from the start
        for _ in range(75):
            steps.frame(line, wall_rate=True)
    time.sleep(0.5)  # the last log lines
    rosout.unregister()
    with lock:
        out["logs"] = logs[:]
    out.update(steps.summary())
    return out


NODES = {
    "follower": ["follow_bot", "follower"],
    "line_follower.py": ["follow_bot", "line_follower.py", "__name:=follower"],
}
CASE_PARAMS = {
    "tf_appears": ["_mode:=pd", "_mounting_timeout:=60"],
    "fallback": ["_mode:=pd", "_mounting_timeout:=1", "_camera_height:=0.25"],
    "params": ["_mode:=pd", "_camera_mounting:=params"],
}
node = pytest.mark.parametrize("node", NODES)


def play(node: str, case: str) -> dict:
    command = NODES[node] + CASE_PARAMS[case]
    client = [sys.executable, __file__, "--client", case, node]
    result = run_with_client(command, client, timeout=180)
    print(node, case, json.dumps(result)[:2000])
    return result


def drives(result: dict) -> bool:
    return any(linear > 0.0 for _, linear, _ in result["twists"])


def states(result: dict) -> list[str]:
    return [status[4] for status in result["statuses"]]


def messages(result: dict, words: str) -> list[str]:
    return [text for _, text in result["logs"] if words in text]


@node
def test_without_tf_it_holds_still_and_drives_once_tf_appears(node):
    result = play(node, "tf_appears")
    before = result["before_tf"]
    waiting = result["statuses"][:before]
    assert all(s[0] is False and s[1] is False for s in waiting), waiting[:3]
    assert set(states(result)[:before]) == {WAITING}
    # Quiet until the mounting is known (an idle node that never steered sends nothing, not even
    # a zero), then it drives: pd on a centred line.
    assert drives(result), "never drove after the transform appeared"
    first_active = next(i for i, s in enumerate(result["statuses"]) if s[1])
    assert first_active >= before
    # Throttled: 2.5 s of 30 Hz frames give one message per 2 s, not one per frame.
    waits = messages(result, WAIT_MESSAGE)
    assert 1 <= len(waits) <= 3, waits
    assert "holding still" in waits[0] and "~mounting_timeout 60 s" in waits[0], waits[0]
    mounted = messages(result, "camera mounting from tf")
    assert mounted == [
        "/follower: camera mounting from tf (base_link <- camera_rgb_optical_frame): height "
        "0.350 m, pitch "
        "15.0 deg down, x offset 0.050 m"
    ], result["logs"]
    # The latched transform reaches the node within a few frames; it is never lost again.
    known = states(result).index(next(s for s in states(result) if s != WAITING))
    assert before <= known <= before + 10, known
    assert WAITING not in states(result)[known:]


@node
def test_after_the_timeout_it_falls_back_to_the_params_once(node):
    result = play(node, "fallback")
    warnings = [(level, text) for level, text in result["logs"] if "falling back" in text]
    assert warnings == [
        (4, "/follower: no camera mounting from tf (base_link <- 'camera_rgb_optical_frame') "
            "within ~mounting_timeout 1 s: falling back to the mounting ~params: height 0.250 m, "
            "pitch 20.0 deg down, x offset 0.000 m"),
    ], result["logs"]  # fmt: skip
    seen = states(result)
    assert seen[0] == WAITING
    fell_back = seen.index(next(s for s in seen if s != WAITING))
    assert 20 <= fell_back <= 45, fell_back  # about 1 s of 30 Hz frames
    assert WAITING not in seen[fell_back:]
    assert drives(result)


@node
def test_with_params_no_tf_is_needed(node):
    result = play(node, "params")
    assert WAITING not in states(result)
    assert drives(result)
    assert messages(result, "camera mounting from") == [
        "/follower: camera mounting from ~params (~camera_mounting params): height 0.300 m, "
        "pitch 20.0 deg down, x offset 0.000 m"
    ]
    assert not messages(result, "waiting for the camera mounting")


if __name__ == "__main__" and sys.argv[1:2] == ["--client"]:
    print(json.dumps(client(sys.argv[2], sys.argv[3]), default=float))
