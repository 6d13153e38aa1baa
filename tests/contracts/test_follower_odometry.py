"""The follower's path mode carries its line memory by the base's odometry by default (every real
base lags its commands); where no odometry arrives it steers on by the commands sent and says so
once, after a second of frames, not on every frame.

The ROS client runs in a child process (this file with --client, tests/README.md): it sends
camera_info and line frames for 2.5 s of stamps, at 20 Hz."""

import json
import subprocess
import sys
import time

from harness.processes import WatchedProcess, private_master
from harness.testing import NODES, pinhole_info, probe_frame

WARNING = "~use_odom: no odometry on"
SECONDS = 2.5


def client() -> None:
    import rospy
    from geometry_msgs.msg import Twist
    from sensor_msgs.msg import CameraInfo, Image

    rospy.init_node("odometry_client", disable_signals=True)
    image_pub = rospy.Publisher("/camera/rgb/image_raw", Image, queue_size=1, tcp_nodelay=True)
    info_pub = rospy.Publisher("/camera/rgb/camera_info", CameraInfo, queue_size=1, latch=True)
    twists: list[Twist] = []
    rospy.Subscriber("/cmd_vel", Twist, twists.append)
    info_pub.publish(pinhole_info())
    deadline = time.monotonic() + 30
    while image_pub.get_num_connections() == 0 and time.monotonic() < deadline:
        time.sleep(0.05)
    time.sleep(0.5)
    frame = probe_frame(NODES["follower"].probe)
    stamp = 1000.0
    for _ in range(int(SECONDS * 20)):
        stamp += 0.05
        frame.header.stamp = rospy.Time.from_sec(stamp)
        image_pub.publish(frame)
        time.sleep(0.05)
    time.sleep(0.5)
    print(json.dumps({"twists": len(twists), "driving": sum(t.linear.x > 0 for t in twists)}))


def test_without_odometry_path_mode_steers_by_the_commands_and_says_so_once():
    spec = NODES["follower"]
    # The default ~use_odom and ~mode (path); a wall watchdog above the client's frame period.
    node = ["rosrun", *spec.rosrun_args("_wall_watchdog_timeout:=2.0")]
    with private_master() as env:
        follower = WatchedProcess(node, env)
        try:
            done = subprocess.run(
                [sys.executable, __file__, "--client"], env=env, capture_output=True, text=True,
                timeout=60,
            )  # fmt: skip
            assert done.returncode == 0, done.stdout + done.stderr
            result = json.loads(done.stdout.strip().splitlines()[-1])
            assert follower.wait_for(WARNING, 5.0), follower.output()
        finally:
            follower.process.terminate()
            follower.process.wait(10)
    output = follower.output()
    assert output.count(WARNING) == 1, output
    assert "/odom after 1 s of frames" in output, output
    # It kept steering along the line on the commands it sent.
    assert result["driving"] >= 0.8 * SECONDS * 20, result


if __name__ == "__main__" and sys.argv[1:2] == ["--client"]:
    client()
