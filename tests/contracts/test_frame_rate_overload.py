"""The parker fed frames faster than it can answer them, with frames that cost real work: a tag
at 4x its frame rate (120 Hz), a sign at 700 Hz (a tracked sign frame costs only ~5 ms; at
240 Hz it still answered 95 %). The input queue of one drops stale frames, so the latency from
sending a frame to its pose stays bounded and does not grow, the poses come in frame order, and
the node answers all through the flood.

The ROS client runs in a child process (this file with --client, tests/README.md)."""

from __future__ import annotations

import json
import statistics
import sys
import time

import pytest

from harness.processes import run_with_client
from harness.testing import NODES, pinhole_info, probe_frame

RATE_HZ = {"parker_tag": 120.0, "parker_sign": 700.0}
SECONDS = 3.0


def client(key: str) -> None:
    import rospy
    from geometry_msgs.msg import PoseStamped
    from sensor_msgs.msg import CameraInfo, Image

    rospy.init_node("overload_client", disable_signals=True)
    image_pub = rospy.Publisher("/camera/rgb/image_raw", Image, queue_size=1, tcp_nodelay=True)
    info_pub = rospy.Publisher("/camera/rgb/camera_info", CameraInfo, queue_size=1, latch=True)
    sent: dict[float, float] = {}  # stamp -> wall time sent
    poses: list[tuple[float, float]] = []  # (stamp, wall time received)
    rospy.Subscriber(
        "/parker/target_pose", PoseStamped,
        lambda m: poses.append((m.header.stamp.to_sec(), time.monotonic())), tcp_nodelay=True,
    )  # fmt: skip
    info_pub.publish(pinhole_info())
    deadline = time.monotonic() + 30
    while image_pub.get_num_connections() == 0 and time.monotonic() < deadline:
        time.sleep(0.05)
    time.sleep(0.5)
    frame = probe_frame(NODES[key].probe)
    start = time.monotonic()
    stamp = 1000.0
    rate_hz = RATE_HZ[key]
    while time.monotonic() - start < SECONDS:
        stamp += 1.0 / rate_hz
        frame.header.stamp = rospy.Time.from_sec(stamp)
        sent[round(stamp, 6)] = time.monotonic()
        image_pub.publish(frame)
        time.sleep(max(0.0, start + len(sent) / rate_hz - time.monotonic()))
    time.sleep(1.0)
    latencies = [(wall - sent[round(s, 6)], wall - start) for s, wall in poses]
    first = [lat for lat, at in latencies if at < 1.0]
    last = [lat for lat, at in latencies if at >= SECONDS - 1.0]
    stamps = [s for s, _ in poses]
    print(
        json.dumps(
            {
                "sent": len(sent),
                "answered": len(poses),
                "max_latency_s": max(lat for lat, _ in latencies),
                "median_latency_first_s": statistics.median(first),
                "median_latency_last_s": statistics.median(last),
                "in_order": stamps == sorted(stamps),
                "answered_each_second": [
                    sum(second <= at - start < second + 1 for _, at in poses)
                    for second in range(int(SECONDS))
                ],
            }
        )
    )


@pytest.fixture(scope="module", params=["parker_tag", "parker_sign"])
def overload(request) -> tuple[str, dict]:
    key = request.param
    client = [sys.executable, __file__, "--client", key]
    result = run_with_client(NODES[key].rosrun_args(), client, timeout=120)
    print(key, result)
    return key, result


def test_latency_bounded_and_not_growing(overload):
    # Measured on an idle machine: tag 3 ms median (70 ms worst), sign ~0.1 s; on the shared
    # 2-core build machine at load 20 the sign's worst was 0.7 s. A queue that kept stale
    # frames would grow by 3 s x (frame rate - answers per second) frame times instead.
    key, r = overload
    assert r["max_latency_s"] <= 1.0, r
    assert r["median_latency_last_s"] <= r["median_latency_first_s"] + 0.1, r


def test_poses_in_frame_order_and_answered_all_through(overload):
    # How many frames of the flood the node answers depends on the CPU the sender and the
    # machine's load leave it (the sign: 139-784 of ~2000 on the 2-core build machine, 9 % at
    # load 7), so the count is held only to what a node that stalls or falls silent would fail:
    # answers in every second of the flood.
    key, r = overload
    assert r["in_order"], r
    assert min(r["answered_each_second"]) >= 5, r


if __name__ == "__main__" and sys.argv[1:2] == ["--client"]:
    client(sys.argv[2])
