#!/usr/bin/env python3
"""Lab 5 step 3 in Python: the camera feed with red, green and blue filtered out of it at once.

camera/rgb/image_raw (bgr8) in; ~image out: the frame where any of the three colours is (the
union of the detector's cleaned-up HSV masks), black elsewhere; ~show true also opens a window.
The masks are follow_bot.core.ColourBlobDetector's (its default red, green and blue).
"""

import numpy as np
import rospy

from follow_bot import core, lab

lab.start("three_colours", __doc__, {
    "sensitivity": "hue half-width of every colour (OpenCV hue)",
    "show": "also show the picture in a window (false)",
})  # fmt: skip
colours = core.ColourBlobConfig().colours
for spec in colours:
    spec.sensitivity = rospy.get_param("~sensitivity", spec.sensitivity)
detector = core.ColourBlobDetector(lab.configured(core.ColourBlobConfig, {}, colours=colours))
display = lab.Display("red, green and blue")


def on_frame(header, bgr):
    mask = np.zeros(bgr.shape[:2], bool)
    for spec in colours:
        mask |= detector.mask(bgr, spec.name) > 0
    display.show(header, np.where(mask[..., None], bgr, 0).astype(np.uint8))


lab.subscribe_frames(on_frame)
rospy.spin()
