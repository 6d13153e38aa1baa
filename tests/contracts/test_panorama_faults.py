"""Panorama node faults: frames stop during a capture. The frame watchdog (CommandOutput, wall
time too, so it holds with /clock stopped) sends one zero Twist within 0.2 s; the capture's
lost-frame rule (~frame_timeout, 1 s) then ends the call, which answers that the frames stopped
and sends nothing more; /diagnostics says so with the dropped frames counted.

The ROS client runs in a child process (this file with --client, tests/README.md)."""

from __future__ import annotations

import json
import sys
import threading
import time

import pytest

from harness.processes import run_with_client
from harness.testing import image_msg, odom_msg, pinhole_info, probe_frame

FRAME_TIMEOUT_S = 1.0  # the node's ~frame_timeout default (follow_bot/doc/panorama.md)
STOP_WITHIN_S = 0.2  # the safety contract: a zero Twist within 0.2 s when frames stop


def client() -> None:
    import rospy
    from diagnostic_msgs.msg import DiagnosticArray
    from geometry_msgs.msg import Twist
    from nav_msgs.msg import Odometry
    from sensor_msgs.msg import CameraInfo, Image
    from std_srvs.srv import Trigger

    rospy.init_node("panorama_fault_client", disable_signals=True)
    image_pub = rospy.Publisher("/camera/rgb/image_raw", Image, queue_size=1, tcp_nodelay=True)
    info_pub = rospy.Publisher("/camera/rgb/camera_info", CameraInfo, queue_size=1, latch=True)
    odom_pub = rospy.Publisher("/odom", Odometry, queue_size=1, latch=True)
    twists: list[tuple[float, float]] = []  # (wall, angular)
    commands = rospy.Subscriber(
        "/cmd_vel", Twist, lambda m: twists.append((time.monotonic(), m.angular.z))
    )
    statuses: list[dict] = []  # the panorama's own status (captures)
    behaviour: list[dict] = []  # CommandOutput's (frames, watchdog)

    def on_diagnostics(array):
        for s in array.status:
            status = {"level": s.level, "message": s.message}
            status.update({kv.key: kv.value for kv in s.values})
            if s.name.endswith(": panorama"):
                statuses.append(status)
            elif s.name.endswith(": behaviour"):
                behaviour.append(status)

    rospy.Subscriber("/diagnostics", DiagnosticArray, on_diagnostics)
    info_pub.publish(pinhole_info())
    odom_pub.publish(odom_msg(0.0))
    rospy.wait_for_service("/panorama/capture", timeout=30)
    deadline = time.monotonic() + 30
    while (
        image_pub.get_num_connections() == 0 or commands.get_num_connections() == 0
    ) and time.monotonic() < deadline:
        time.sleep(0.05)
    frame = probe_frame("idle")
    for _ in range(2):  # dropped: an odd mono16 step
        image_pub.publish(image_msg(8, 4, "mono16", 17, bytes(68), (1000, 0)))
        time.sleep(0.05)

    def send_frame():
        frame.header.stamp = rospy.Time.now()  # the limiter ramps by the time between stamps
        image_pub.publish(frame)
        time.sleep(1 / 30)

    for _ in range(10):
        send_frame()
    reply = {}

    def call():
        answer = rospy.ServiceProxy("/panorama/capture", Trigger)()
        reply.update(success=answer.success, message=answer.message, at=time.monotonic())

    threading.Thread(target=call, daemon=True).start()
    for _ in range(30):  # one second of turning toward the left end
        send_frame()
    last_frame = time.monotonic()
    turning = [w for t, w in twists if t < last_frame]
    time.sleep(FRAME_TIMEOUT_S + 1.5)
    after = [(t - last_frame, w) for t, w in twists if t > last_frame + 0.1]
    failed = [s for s in statuses if s["level"] == 2]
    print(
        json.dumps(
            {
                "max_turn": max(turning, default=0.0),
                "answers_before": len(turning),
                "after": after,
                "reply": reply,
                "reply_after_s": reply.get("at", 0) - last_frame,
                "diagnostics_failed": failed[-1] if failed else None,
                "diagnostics_behaviour": behaviour[-1] if behaviour else None,
            }
        )
    )


@pytest.fixture(scope="module")
def result() -> dict:
    out = run_with_client(
        ["follow_bot", "panorama", "_camera_mounting:=params"],  # no robot description here
        [sys.executable, __file__, "--client"],
        timeout=120,
    )
    print(out)
    return out


def test_frames_stop_during_a_capture_one_zero_twist_within_0_2_s(result):
    assert result["max_turn"] > 0.1, result  # it was turning toward the left end
    zeros = [(t, w) for t, w in result["after"] if w == 0.0]
    assert len(result["after"]) == 1 and len(zeros) == 1, result
    assert zeros[0][0] <= STOP_WITHIN_S, result


def test_the_capture_call_says_the_frames_stopped(result):
    assert result["reply"]["success"] is False, result
    assert result["reply"]["message"] == "camera frames stopped during the capture", result
    assert result["reply_after_s"] <= FRAME_TIMEOUT_S + 0.3, result


def test_diagnostics_report_the_failed_capture_and_the_dropped_frames(result):
    failed = result["diagnostics_failed"]
    assert failed is not None, result
    assert failed["message"] == "last capture failed: camera frames stopped during the capture"
    assert failed["captures stopped for lost frames or time"] == "1", failed
    frames = result["diagnostics_behaviour"]
    assert frames["dropped_bad_size"] == "2", frames  # the odd mono16 steps, no other drop
    others = ("dropped_bad_encoding", "dropped_bad_stamp", "dropped_error")
    assert all(frames[k] == "0" for k in others), frames
    assert frames["watchdog stops"] == "1", frames
    assert int(frames["frames_accepted"]) >= 40, frames


if __name__ == "__main__" and sys.argv[1:2] == ["--client"]:
    client()
