#!/usr/bin/env python3
"""Lab 5 step 4 in Python: follow the green ball, stop at once while red is in view.

camera/rgb/image_raw (bgr8) in; cmd_vel out while driving (one zero on stopping); ~status per
frame. The largest blob of each colour (follow_bot.core.ColourBlobDetector) steers the C++
BeaconController, the beacon_chaser node's own code; ~mode approach is the lecture's
Exercise 10 with the default camera (640x480, 60 deg, 0.3 m up, pitched 20 deg down).
"""

import rospy

from follow_bot import core, lab

# Searching and approaching steer; the states that stand still are idle (as beacon_chaser).
STEERING = {core.BeaconState.searching, core.BeaconState.approaching}

lab.start("follow_green_stop_red", __doc__, {
    "mode": "follow_green_stop_red (default) or approach",
    "close_area": "follow mode: hold once the green blob covers this many px^2",
    **lab.COMMAND_HELP,
})  # fmt: skip
defaults = core.BeaconControllerConfig()
params = {"mode": "follow_green_stop_red", "close_area": defaults.close_area}
controller = core.BeaconController(lab.configured(core.BeaconControllerConfig, params))
# Lab 5's detector is colour and area only (beacon_chaser adds the shape and size gates).
detector = core.ColourBlobDetector(core.ColourBlobConfig(roundness_tolerance=0.0))
output = lab.CommandOutput()


def on_frame(header, bgr):
    desired = controller.update(detector.detect(bgr), header.stamp.to_sec())
    output.send(header, desired, controller.state in STEERING, controller.state.name)


lab.subscribe_frames(on_frame)
rospy.spin()
