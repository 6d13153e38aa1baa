"""Prints the ROS clock (/clock, in s) once per wall second until stopped: the simulated time that
run_scenario's progress line shows while a single run plays."""

import time

import rospy
from rosgraph_msgs.msg import Clock


def main() -> None:
    rospy.init_node("sim_clock", anonymous=True)
    latest: list[float] = []
    rospy.Subscriber("/clock", Clock, lambda msg: latest.append(msg.clock.to_sec()), queue_size=1)
    while not rospy.is_shutdown():
        time.sleep(1.0)
        if latest:
            print(f"{latest[-1]:.3f}", flush=True)
            latest.clear()


if __name__ == "__main__":
    main()
