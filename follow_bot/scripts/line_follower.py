#!/usr/bin/env python3
"""The Visual Servoing project's line follower in Python: crop a band of rows, HSV threshold,
the band's moments, P control on the centroid's offset, and turn around to find the line when it
is lost.

camera/rgb/image_raw (bgr8) and camera/rgb/camera_info in; cmd_vel out while following or
searching (one zero on giving up); ~status per frame. The camera's mounting comes from tf, as
for the C++ nodes (follow_bot.mounting: ~camera_mounting, ~base_frame, ~mounting_timeout, the
mounting ~params). The crop, HSV and moments are
follow_bot.core.LineDetector, the control a follow_bot.core steering law (the follower's code):
~mode pd with ~kd 0 (the default) is P control with the lost-line search; lecture and path (the
remembered line, needs camera_info) are the follower's other laws.
"""

import rospy
from sensor_msgs.msg import CameraInfo

from follow_bot import core, lab, mounting

lab.start("line_follower", __doc__, {
    "mode": "steering law: pd (default; with kd 0, P control), lecture or path",
    "max_linear": "top speed, m/s (0.3)", "kp": "rad/s per unit of normalised error (1.5)",
    "kd": "rad/s per unit of error per s (0: P control)",
    "band_distance": "crop: the rows showing the floor this far ahead, m (0.46; the lecture's "
                     "3/4 of the height on the default mounting)",
    **lab.COMMAND_HELP,
    **mounting.HELP,
})  # fmt: skip
defaults = core.SteeringConfig()
pd = lab.configured(core.PdConfig, {"kp": defaults.pd.kp, "kd": 0.0})
params = {"mode": "pd", "max_linear": defaults.max_linear}
config = lab.configured(core.SteeringConfig, params, pd=pd)
distance = core.LineDetectorConfig().band.distance_m
band = lab.configured(core.BandConfig, {"distance_m": distance}, prefix="band_")
detector_config = lab.configured(core.LineDetectorConfig, {}, band=band)
output = lab.CommandOutput()
camera_mounting = mounting.CameraMounting()
intrinsics = [core.CameraGeometry()]  # the default until camera_info arrives
has_camera_info = False
# Built for the camera in use (placed = its intrinsics and mounting), again when it changes.
detector, law, placed = None, None, None
applied = core.Twist2D()


def on_camera_info(info):
    global has_camera_info
    try:
        intrinsics[:] = [lab.camera_intrinsics(info)]
        has_camera_info = True
    except ValueError as error:  # e.g. all zeros: path keeps steering as pd
        rospy.logwarn_throttle(5.0, f"camera_info unusable: {error}")


def same_camera(a, b):
    return core.same_intrinsics(a, b) and core.same_mounting(a, b)


def on_frame(header, bgr):
    global applied, detector, law, placed
    camera = camera_mounting.update(header.frame_id, intrinsics[0])
    if camera is None:  # holding still until the mounting is known
        applied = output.send(header, core.Twist2D(), False, core.WAITING_FOR_MOUNTING)
        return
    if placed is None or not same_camera(camera, placed):
        detector = core.LineDetector(detector_config, camera)
        if law is None or config.mode == core.SteeringMode.path:  # the others have no camera
            # path needs the intrinsics: pd until camera_info gives them
            law = core.make_steering_law(config, camera if has_camera_info else None)
        placed = camera
    desired = law.step(detector.detect(bgr), header.stamp.to_sec(), applied)
    applied = output.send(header, desired, law.state != core.LineState.gave_up, law.state.name)


rospy.Subscriber("camera/rgb/camera_info", CameraInfo, on_camera_info, queue_size=1)
lab.subscribe_frames(on_frame)
rospy.spin()
