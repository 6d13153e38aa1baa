"""What every lab-style rospy node (follow_bot/scripts) shares: start-up, ~params checked by the
C++ validate(), camera frames as numpy arrays, and the behaviour contract for cmd_vel.

The contract (docs/behaviour_contract.md), as follow_bot_common::CommandOutput keeps it for the C++
nodes: commands pass the VelocityLimiter (the ~limit_* params); while the behaviour is active
one Twist per frame, on becoming idle the limiter's ramp down to one zero and then nothing; one
~status per frame (the lockstep simulator waits for it); no frame for ~watchdog_timeout of ROS
time (or 3 frame periods of a slower camera, ~expected_frame_rate's until measured:
core.FrameWatchdog): one zero; on shutdown a last zero.
"""

import argparse
import sys
import time

import rospy
from geometry_msgs.msg import Twist
from sensor_msgs.msg import Image

from follow_bot import core
from follow_bot_msgs.msg import BehaviourStatus
from follow_bot_msgs.ros_image import msg_to_bgr

IMAGE = "camera/rgb/image_raw"  # relative: a namespace or a remap moves it


def start(name, doc, params):
    """Parses --help (the module doc and the ~params, `{name: help}`), then inits the node."""
    parser = argparse.ArgumentParser(
        description=doc, formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="private parameters:\n" + "\n".join(f"  ~{p:<20} {h}" for p, h in params.items()),
    )  # fmt: skip
    parser.parse_args(rospy.myargv(sys.argv)[1:])
    rospy.init_node(name)


def fatal(message):
    """A start-up error: logged as fatal, then exit 2."""
    rospy.logfatal(message)
    sys.exit(2)


def configured(make, params, prefix="", **fixed):
    """make(**fields, **fixed), each of `params` ({field: default}) from the ~param prefix+field
    when set; a bad value stops the node (exit 2) with the C++ validate() message."""
    names = {field: "~" + prefix + field for field in params}
    fields = {field: rospy.get_param(names[field], default) for field, default in params.items()}
    try:
        return make(**fields, **fixed)
    except (ValueError, TypeError) as error:
        which = f" ({', '.join(names.values())})" if names else ""
        fatal(f"invalid parameter{which}: {error}")


def camera_intrinsics(info):
    """core.CameraGeometry of a CameraInfo's K, with the default mounting (follow_bot.mounting
    gives the real one). Raises ValueError for unusable intrinsics."""
    fx, _, cx, _, fy, cy = info.K[:6]
    return core.CameraGeometry(fx=fx, fy=fy, cx=cx, cy=cy)


def subscribe_frames(callback):
    """callback(header, bgr) for each camera frame (HxWx3 uint8 view of the message), queue 1."""

    def unpack(msg):
        try:
            frame = msg_to_bgr(msg)
        except ValueError as error:  # a frame the lab nodes cannot read: dropped, said once a while
            rospy.logerr_throttle(5.0, f"frame dropped: {error}")
            return
        callback(msg.header, frame)

    return rospy.Subscriber(IMAGE, Image, unpack, queue_size=1, buff_size=2**24)


_DEFAULT_LIMITS = core.VelocityLimiterConfig()
# The ~params CommandOutput reads (follow_bot_common/cfg/CommandOutput.cfg, as the C++ nodes),
# for the driving nodes' --help.
COMMAND_HELP = {
    **{param: f"hard limit, {getattr(_DEFAULT_LIMITS, field):g} (cfg/CommandOutput.cfg of "
              "follow_bot_common)" for field, param, _ in _DEFAULT_LIMITS.CFG_FIELDS},
    "watchdog_timeout": "s without a frame before one zero Twist, at least "
                        f"({core.WATCHDOG_TIMEOUT}; a slower camera: 3 frame periods)",
    "expected_frame_rate": "the camera's rate, Hz: the watchdog's until measured (0: unknown)",
}  # fmt: skip


def limits(allow_reverse):
    """core.VelocityLimiterConfig of the ~limit_* params (unset: the default); a bad value stops
    the node (exit 2) naming the param."""
    config = core.VelocityLimiterConfig(allow_reverse=allow_reverse)
    for field, param, _ in config.CFG_FIELDS:
        value = rospy.get_param("~" + param, getattr(config, field))
        try:
            setattr(config, field, value)
        except TypeError:
            fatal(f"~{param} must be a number, got {value!r}")
        if error := config.validate():
            fatal(f"~{param}: {error}")
    return config


class CommandOutput:
    """cmd_vel (relative) and ~status by the behaviour contract; see the module doc."""

    def __init__(self, allow_reverse=False):
        self.limiter = core.VelocityLimiter(limits(allow_reverse))
        timeout = rospy.get_param("~watchdog_timeout", core.WATCHDOG_TIMEOUT)
        rate = rospy.get_param("~expected_frame_rate", core.EXPECTED_FRAME_RATE)
        if not rate >= 0.0:
            fatal(f"~expected_frame_rate must be >= 0 (0: unknown), got {rate}")
        try:
            self.watchdog = core.FrameWatchdog(timeout, 1.0 / rate if rate else 0.0)
        except ValueError as error:
            fatal(f"~watchdog_timeout: {error}")
        self.cmd_vel = rospy.Publisher("cmd_vel", Twist, queue_size=1)
        self.status = rospy.Publisher("~status", BehaviourStatus, queue_size=10)
        self.quiet = True  # the last command sent (or none yet) is a zero
        self.last_stamp = None
        rospy.Timer(rospy.Duration(timeout / 3.0), self._check_watchdog)
        rospy.on_shutdown(self._shutdown)

    def send(self, header, desired, active, state):
        """One frame's decision, by follow_bot_common::CommandOutput::send's rules: the limiter
        runs on every frame; the command goes out while active, and while idle until it is zero
        (that zero included); the frame's ~status. Returns the limited command."""
        stamp = header.stamp.to_sec() if not header.stamp.is_zero() else rospy.get_time()
        self.watchdog.frame_arrived(rospy.get_time())
        # A gap longer than the watchdog timeout counts as the timeout; a backward stamp gives
        # dt <= 0 (the limiter then only slows down).
        last, self.last_stamp = self.last_stamp, stamp
        dt = 0.0 if last is None else min(stamp - last, self.watchdog.timeout)
        command = self.limiter.limit(desired, dt)
        zero = command.linear == 0.0 and command.angular == 0.0
        sent = active or not zero or not self.quiet
        if sent:
            self.cmd_vel.publish(twist_msg(command))
            self.quiet = zero and not active
        self.status.publish(BehaviourStatus(
            header=header, state=state, enabled=True, active=active, command_sent=sent,
            command=twist_msg(command) if sent else Twist(),
        ))  # fmt: skip
        return command

    def stop(self):
        """An immediate zero, unless already stopped."""
        if not self.quiet:
            self.limiter.stop()
            self.cmd_vel.publish(Twist())
            self.quiet = True

    def _check_watchdog(self, _event):
        if self.watchdog.should_send_stop(rospy.get_time()):
            rospy.logwarn("no camera frame for %.2f s: stopping", self.watchdog.timeout)
            self.stop()

    def _shutdown(self):
        self.cmd_vel.publish(Twist())
        time.sleep(0.1)  # let the last zero leave (rospy.sleep ends at shutdown)


def twist_msg(command):
    msg = Twist()
    msg.linear.x, msg.angular.z = command.linear, command.angular
    return msg


class Display:
    """Publishes a lab node's picture on ~image (bgr8 or mono8, queue 1) and, with ~show true
    and OpenCV for this Python, shows it in a window as the worksheet does (cv2.imshow)."""

    def __init__(self, title):
        self.title = title
        self.publisher = rospy.Publisher("~image", Image, queue_size=1)
        self.cv2 = None
        if rospy.get_param("~show", False):
            try:
                import cv2  # not in Debian's python3: the window is optional

                self.cv2 = cv2
            except ImportError:
                rospy.logwarn("~show: no OpenCV for this Python; publishing ~image only")

    def show(self, header, picture):
        self.publisher.publish(image_msg(header, picture))
        if self.cv2 is not None:
            self.cv2.imshow(self.title, picture)
            self.cv2.waitKey(1)


def image_msg(header, picture):
    """An HxWx3 (bgr8) or HxW (mono8) uint8 array as an Image with `header`."""
    msg = Image(header=header, height=picture.shape[0], width=picture.shape[1])
    msg.encoding = "bgr8" if picture.ndim == 3 else "mono8"
    msg.step = picture[0].nbytes
    msg.data = picture.tobytes()
    return msg
