#!/usr/bin/env python3
"""The Visual Servoing project's line follower in Python: crop a band of rows, HSV threshold,
the band's moments, P control on the centroid's offset, and turn around to find the line when it
is lost.

camera/rgb/image_raw (bgr8) and camera/rgb/camera_info in; cmd_vel out while following or
searching (one zero on giving up); ~status per frame. The crop, HSV and moments are
follow_bot.core.LineDetector, the control a follow_bot.core steering law (the follower's code):
~mode pd with ~kd 0 (the default) is P control with the lost-line search; lecture and path (the
remembered line, needs camera_info) are the follower's other laws.
"""

import rospy
from sensor_msgs.msg import CameraInfo

from follow_bot import core, lab

lab.start("line_follower", __doc__, {
    "mode": "steering law: pd (default; with kd 0, P control), lecture or path",
    "max_linear": "top speed, m/s (0.3)", "kp": "rad/s per unit of normalised error (1.5)",
    "kd": "rad/s per unit of error per s (0: P control)",
    "band_distance": "crop: the rows showing the floor this far ahead, m (0.46; the lecture's "
                     "3/4 of the height on the default mounting)",
    "watchdog_timeout": "s without a frame before one zero Twist, at least "
                        f"({core.WATCHDOG_TIMEOUT}; a slower camera: 3 frame periods)",
    "expected_frame_rate": "the camera's rate, Hz: the watchdog's until measured (0: unknown)",
    "camera_height": "optical centre above the floor, m (default: the C++ nodes' one)",
    "camera_pitch_deg": "camera pitch, deg, down positive (default: the C++ nodes' one)",
    "camera_x_offset": "optical centre forward of base_link, m (default: the C++ nodes' one)",
})  # fmt: skip
defaults = core.SteeringConfig()
pd = lab.configured(core.PdConfig, {"kp": defaults.pd.kp, "kd": 0.0})
params = {"mode": "pd", "max_linear": defaults.max_linear}
config = lab.configured(core.SteeringConfig, params, pd=pd)
distance = core.LineDetectorConfig().band.distance_m
band = lab.configured(core.BandConfig, {"distance_m": distance}, prefix="band_")
detector_config = lab.configured(core.LineDetectorConfig, {}, band=band)
# The band is placed for the camera: the default one until camera_info arrives.
detector = core.LineDetector(detector_config)
placed = False  # for the camera_info's camera
law = core.make_steering_law(config)  # path: pd until camera_info gives the intrinsics
output = lab.CommandOutput()
applied = core.Twist2D()
camera = []  # the intrinsics and mounting, once camera_info arrives


def on_camera_info(info):
    try:
        camera[:] = [lab.camera_geometry(info)]
    except ValueError as error:  # e.g. all zeros: path keeps steering as pd
        rospy.logwarn_throttle(5.0, f"camera_info unusable: {error}")


def on_frame(header, bgr):
    global applied, detector, law, placed
    if camera and not placed:
        detector, placed = core.LineDetector(detector_config, camera[0]), True
    if config.mode == core.SteeringMode.path and camera and not isinstance(law, core.PathLaw):
        law = core.make_steering_law(config, camera[0])
    desired = law.step(detector.detect(bgr), header.stamp.to_sec(), applied)
    applied = output.send(header, desired, law.state != core.LineState.gave_up, law.state.name)


rospy.Subscriber("camera/rgb/camera_info", CameraInfo, on_camera_info, queue_size=1)
lab.subscribe_frames(on_frame)
rospy.spin()
