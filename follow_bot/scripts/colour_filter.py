#!/usr/bin/env python3
"""Lab 5 steps 1-2 in Python: the camera feed with one colour filtered out of it.

camera/rgb/image_raw (bgr8) in; ~image out: the frame where the colour is (the detector's
cleaned-up HSV mask of it), black elsewhere (cv2.bitwise_and(frame, frame, mask=mask) of the
worksheet); ~show true also opens a window. The mask is follow_bot.core.ColourBlobDetector's.
"""

import numpy as np
import rospy

from follow_bot import core, lab

lab.start("colour_filter", __doc__, {
    "colour": "red, green (default) or blue", "sensitivity": "hue half-width (OpenCV hue)",
    "show": "also show the picture in a window (false)",
})  # fmt: skip
name = rospy.get_param("~colour", "green")
spec = core.parse_colour_name(name)
if spec is None:
    rospy.logfatal(f"~colour must be red, green or blue, got '{name}'")
    raise SystemExit(2)
spec.sensitivity = rospy.get_param("~sensitivity", spec.sensitivity)
detector = core.ColourBlobDetector(lab.configured(core.ColourBlobConfig, {}, colours=[spec]))
display = lab.Display(f"{name} filtered")


def on_frame(header, bgr):
    display.show(header, np.where(detector.mask(bgr, name)[..., None] > 0, bgr, 0).astype(np.uint8))


lab.subscribe_frames(on_frame)
rospy.spin()
