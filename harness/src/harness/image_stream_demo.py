"""Foundation demo: feeds the ImageConverter a generated stream and saves what it publishes.

Publishes moving colour-gradient frames on camera/rgb/image_raw, waits for the annotated frames
on /image_converter/output, writes the last one to ~out/image_converter_demo.png, and reports
whether the lecture's red circle is where it belongs.
"""

import os

import cv2
import numpy as np
import rospy
from sensor_msgs.msg import Image

from follow_bot_msgs.ros_image import bgr_to_msg, msg_to_bgr
from harness.node_cli import parse_node_command_line

WIDTH, HEIGHT = 640, 480


def gradient_frame(k: int) -> np.ndarray:
    """A smooth BGR gradient that drifts with the frame index k."""
    x = np.linspace(0.0, 1.0, WIDTH, dtype=np.float32)[None, :]
    y = np.linspace(0.0, 1.0, HEIGHT, dtype=np.float32)[:, None]
    phase = 0.05 * k
    frame = np.empty((HEIGHT, WIDTH, 3), dtype=np.uint8)
    frame[..., 0] = 127.5 * (1 + np.sin(2 * np.pi * (x + phase)))
    frame[..., 1] = 127.5 * (1 + np.sin(2 * np.pi * (y - phase)))
    frame[..., 2] = 60.0 + 40.0 * np.sin(phase)
    return frame


def main() -> None:
    parse_node_command_line(rospy.myargv()[1:], "image_stream_demo", __doc__)
    rospy.init_node("image_stream_demo")
    out_dir = rospy.get_param("~out", "out")
    frames = int(rospy.get_param("~frames", 30))
    os.makedirs(out_dir, exist_ok=True)

    received: list[Image] = []
    rospy.Subscriber("image_converter/output", Image, received.append, queue_size=frames)
    publisher = rospy.Publisher("camera/rgb/image_raw", Image, queue_size=1)

    deadline = rospy.Time.now() + rospy.Duration(30.0)
    rate = rospy.Rate(20)
    sent = 0
    while len(received) < frames and not rospy.is_shutdown() and rospy.Time.now() < deadline:
        if publisher.get_num_connections() > 0:
            publisher.publish(bgr_to_msg(gradient_frame(sent), rospy.Time.now(), "camera"))
            sent += 1
        rate.sleep()
    if not received:
        rospy.logfatal("no annotated frame arrived from /image_converter/output")
        raise SystemExit(1)

    annotated = msg_to_bgr(received[-1])
    path = os.path.join(out_dir, "image_converter_demo.png")
    cv2.imwrite(path, annotated)
    ring_pixel = annotated[HEIGHT // 2, WIDTH // 2 + 25]
    print(
        f"image_converter demo: sent {sent} frames, received {len(received)} annotated; "
        f"circle pixel BGR={tuple(int(v) for v in ring_pixel)} "
        f"({'red: ok' if tuple(ring_pixel) == (0, 0, 255) else 'NOT red'}); wrote {path}"
    )
    rospy.signal_shutdown("demo finished")


if __name__ == "__main__":
    main()
