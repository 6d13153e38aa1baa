#!/usr/bin/env python3
"""Lab 5 step 3 in Python: a flag per colour, raised when its largest contour is big enough.

camera/rgb/image_raw (bgr8) in; ~flags out (std_msgs/String, JSON per frame: for red, green and
blue the flag, the largest contour's area in px^2 and its centroid), ~image: the frame with each
flagged colour's largest contour drawn in white (~show true: in a window too). The contours are
follow_bot.core.ColourBlobDetector's; the flag is its min_area rule.
"""

import json

import numpy as np
import rospy
from std_msgs.msg import String

from follow_bot import core, lab

lab.start("colour_flags", __doc__, {
    "min_area": "px^2 a colour's largest contour needs for its flag",
    "show": "also show the picture in a window (false)",
})  # fmt: skip
# The worksheet's flag is colour and area only: any shape.
params = {"min_area": core.ColourBlobConfig().min_area}
detector = core.ColourBlobDetector(
    lab.configured(core.ColourBlobConfig, params, roundness_tolerance=0.0)
)
flags = rospy.Publisher("~flags", String, queue_size=1)
display = lab.Display("colour flags")


def on_frame(header, bgr):
    result = detector.detect(bgr)
    flags.publish(json.dumps({
        blob.name: {"flag": blob.found, "area": blob.area, "centroid": blob.centroid}
        for blob in result.colours
    }))  # fmt: skip
    picture = np.array(bgr)
    for blob in result.colours:
        if blob.found:  # the contour itself, in white
            picture[blob.contour[:, 1], blob.contour[:, 0]] = 255
    display.show(header, picture)


lab.subscribe_frames(on_frame)
rospy.spin()
