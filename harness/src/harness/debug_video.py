"""The demo video's frame: the raw camera view beside the behaviour's debug view.

The behaviour publishes its own overlay (`~debug_image`: the follower's band, line pixels and
centroid) and a status message with `state`, `linear` and `angular` fields (the follower's
`~line`); this module keeps the latest of each and writes them into one side-by-side frame.
"""

from __future__ import annotations

import threading

import cv2
import numpy as np
import roslib.message
import rospy
from sensor_msgs.msg import Image

from follow_bot_msgs.ros_image import msg_to_bgr


def side_by_side(raw: np.ndarray, debug: np.ndarray | None, lines: list[str]) -> np.ndarray:
    """[raw | debug] with `lines` written on the debug half; a grey panel until debug arrives."""
    panel = np.full_like(raw, 64) if debug is None or debug.shape != raw.shape else debug.copy()
    for row, text in enumerate(lines):
        origin = (8, 22 + 22 * row)
        cv2.putText(panel, text, origin, cv2.FONT_HERSHEY_SIMPLEX, 0.6, (0, 0, 0), 3, cv2.LINE_AA)
        cv2.putText(panel, text, origin, cv2.FONT_HERSHEY_SIMPLEX, 0.6, (255, 255, 255), 1)
    return np.hstack([raw, panel])


class DebugView:
    """Subscribes to `<ns>/debug_image` and `<ns>/line`; `frame(raw)` is the video frame."""

    def __init__(self, ns: str):
        self._lock = threading.Lock()
        self._debug: np.ndarray | None = None
        self._status = None
        self._status_class = None
        rospy.Subscriber(f"{ns}/debug_image", Image, self._on_debug, queue_size=1)
        # Any message type with state, linear and angular fields: the harness does not depend
        # on the behaviour packages, so the status is decoded by the type it announces.
        rospy.Subscriber(f"{ns}/line", rospy.AnyMsg, self._on_status, queue_size=1)

    def _on_debug(self, msg: Image) -> None:
        image = msg_to_bgr(msg)
        with self._lock:
            self._debug = image

    def _on_status(self, msg: rospy.AnyMsg) -> None:
        status_class = self._status_class
        if status_class is None:
            status_class = roslib.message.get_message_class(msg._connection_header["type"])
            self._status_class = status_class
        status = status_class().deserialize(msg._buff)
        with self._lock:
            self._status = status

    def frame(self, raw: np.ndarray) -> np.ndarray:
        with self._lock:
            debug, status = self._debug, self._status
        lines: list[str] = []
        if status is not None:
            lines = [
                f"state: {status.state}",
                f"v = {status.linear:+.2f} m/s",
                f"w = {status.angular:+.2f} rad/s",
            ]
        return side_by_side(raw, debug, lines)
