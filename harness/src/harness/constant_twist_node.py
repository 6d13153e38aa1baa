"""A scripted behaviour for harness tests: answers every camera frame with one fixed Twist and
its status (the lockstep reply, docs/behaviour_contract.md).

Parameters: ~v (m/s, default 0.2), ~w (rad/s, default 0.0). Being the cheapest possible
behaviour, it also measures the simulator's own lockstep overhead.
"""

import rospy
from geometry_msgs.msg import Twist
from sensor_msgs.msg import Image

from follow_bot_msgs.msg import BehaviourStatus
from harness.node_cli import parse_node_command_line


def main() -> None:
    parse_node_command_line(rospy.myargv()[1:], "constant_twist", __doc__)
    rospy.init_node("constant_twist")
    command = Twist()
    command.linear.x = float(rospy.get_param("~v", 0.2))
    command.angular.z = float(rospy.get_param("~w", 0.0))
    publisher = rospy.Publisher("cmd_vel", Twist, queue_size=1)
    status_publisher = rospy.Publisher("~status", BehaviourStatus, queue_size=10)

    def answer(frame: Image) -> None:
        publisher.publish(command)
        status = BehaviourStatus(state="driving", enabled=True, active=True, command_sent=True)
        status.header, status.command = frame.header, command
        status_publisher.publish(status)

    # buff_size above one 640x480 bgr8 frame, so a slow reader drops old frames, not new ones.
    rospy.Subscriber("camera/rgb/image_raw", Image, answer, queue_size=1, buff_size=2**24)
    rospy.spin()


if __name__ == "__main__":
    main()
