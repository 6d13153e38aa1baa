"""`rosrun harness sim`: the simulator as a ROS node (a thin shell around Simulation).

Publishes /clock, the camera image and camera_info (camera/rgb/image_raw, or its /compressed JPEG
as the world's or scenario's camera transport says; camera/rgb/camera_info; a robot preset's
topics with its camera), the robot's pose as a base driver does (odom, nav_msgs/Odometry, and tf
odom -> base_footprint, the root of the robot description; exact: the simulator's true pose), the
same on ~pose (e.g. /sim/pose); subscribes cmd_vel and the behaviour's per-frame status
(follow_bot_msgs/BehaviourStatus, docs/behaviour_contract.md). Topic names other than /clock are
relative, so under ROS_NAMESPACE or <group ns> the simulator and the behaviour it drives share
one namespace.

Lockstep (default): publish frame k, wait for the one status the behaviour answers with (up to
~reply_timeout wall seconds; a miss is counted, and a miss with no publisher left on the status
topic ends the run: the behaviour is not running, exit code BEHAVIOUR_GONE), apply the command
it says it sent on cmd_vel (none sent: the behaviour is quiet, its last command was a zero, the
robot stands), integrate one step, repeat: runs are repeatable and as fast as the behaviour.
Steps without a frame (camera dropout) pass at wall pace and apply what arrives on cmd_vel (the
watchdog's stop). Real-time (~lockstep false): frames at ~rate_hz of wall clock, the latest
cmd_vel applied.

Parameters: ~scenario (a scenario YAML; its world, start, rate, duration and perturbations) or
~world (a world YAML or name), ~robot (a robot preset of follow_bot/config/robots.yaml whose
camera and speed limits replace the world's; generic: the world's), ~rate_hz (30), ~duration (s, 0 =
forever), ~lockstep (true),
~reply_timeout (10.0 wall s), ~status (the behaviour's status topic, e.g. follower/status;
"" finds the one BehaviourStatus topic published in the simulator's namespace), ~record (path
of an .npz trajectory log written at the end),
~video (path of an MP4 of the camera view, optional), ~video_debug (the behaviour's namespace,
default follower: the video shows its ~debug_image and the state and command of its ~line beside
the camera view; "" for the camera view alone), ~wait_for_behaviour (20 wall s).
"""

from __future__ import annotations

import math
import threading
import time
import warnings
from pathlib import Path

import cv2
import numpy as np
import rospy
import tf2_ros
from geometry_msgs.msg import TransformStamped, Twist
from nav_msgs.msg import Odometry
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import CameraInfo, CompressedImage, Image

from follow_bot_msgs.msg import BehaviourStatus
from follow_bot_msgs.ros_image import bgr_to_jpeg_msg, bgr_to_msg, camera_info_msg
from harness.debug_video import DebugView
from harness.node_cli import BEHAVIOUR_GONE, parse_node_command_line
from harness.robot_preset import GENERIC, camera_topics, robot_world
from harness.scenario import REPLY_TIMEOUT_S, ScenarioError
from harness.scenario_file import load_scenario
from harness.scenario_parse import scenario_world
from harness.simulation import LapTracker, Perturbations, Simulation
from harness.validation import ValidationError
from harness.world import WorldError
from harness.world_file import load_world, resolve_world_path

# The robot description's root (harness/robot_description.py): a base driver's odom child frame.
BASE_FRAME = "base_footprint"
# ROS time at sim time 0. robot_state_publisher sends the description's fixed joints from a
# one-shot timer (its publish period, 0.02 s at the default 50 Hz), which under /clock fires only
# once the clock has moved: the sim moves it this far before frame 0 and waits for the camera's
# mounting on tf, so every run's behaviour knows its mounting from its first frame on.
CLOCK_PREROLL_S = 0.1
# How long to wait for that mounting; a description whose frames the sim cannot see (another
# tf tree) only costs this once.
MOUNTING_WAIT_S = 5.0


class CommandInbox:
    """Collects cmd_vel commands and the behaviour's statuses from the subscriber threads for
    the stepping loop. A frame's command is taken from its status (which says what it sent), so
    it cannot race the reply on the other connection; cmd_vel is counted, and applied on steps
    without a frame (the watchdog's stop)."""

    def __init__(self):
        self._cond = threading.Condition()
        self._statuses = 0
        self._sent = 0  # statuses that say a command went out on cmd_vel
        self._commands = 0
        self.status_command: tuple[float, float] | None = None  # sent by the latest status
        self.latest = (0.0, 0.0)  # the latest cmd_vel

    def put_command(self, msg: Twist) -> None:
        with self._cond:
            self.latest = (msg.linear.x, msg.angular.z)
            self._commands += 1
            self._cond.notify_all()

    def put_status(self, msg: BehaviourStatus) -> None:
        with self._cond:
            if msg.command_sent:
                self.status_command = (msg.command.linear.x, msg.command.angular.z)
                self._sent += 1
            self._statuses += 1
            self._cond.notify_all()

    def take(self) -> tuple[int, int, int, tuple[float, float] | None]:
        """How many statuses arrived since the last take(), how many of them say a command went
        out, how many cmd_vel commands arrived, and the command the last status in that time
        said it sent (None: no status sent one)."""
        with self._cond:
            taken = (self._statuses, self._sent, self._commands, self.status_command)
            self._statuses = self._sent = self._commands = 0
            self.status_command = None
            return taken

    def wait(self, timeout: float) -> bool:
        """Wait (wall time) until at least one status is pending."""
        with self._cond:
            return self._cond.wait_for(lambda: self._statuses > 0, timeout)


def find_topic(topic_type: str, timeout: float) -> str:
    """The one topic of `topic_type` in this node's namespace (waits up to `timeout` s); "" when
    there is none by then. ValueError when there are several (the caller names the one)."""
    deadline = time.monotonic() + timeout
    while not rospy.is_shutdown():
        topics = [name for name, kind in rospy.get_published_topics(rospy.get_namespace())
                  if kind == topic_type]  # fmt: skip
        if len(topics) > 1:
            raise ValueError(f"several {topic_type} topics {topics}")
        if topics or time.monotonic() >= deadline:
            return topics[0] if topics else ""
        time.sleep(0.05)
    return ""


class SimNode:
    def __init__(self):
        scenario_path = rospy.get_param("~scenario", "")
        if scenario_path:
            scenario = load_scenario(scenario_path)
            world = scenario_world(scenario)
            transport = scenario.camera_transport or world.camera_transport
            self.rate_hz, self.duration = scenario.rate_hz, scenario.duration
            self.lockstep, self.reply_timeout = scenario.lockstep, scenario.reply_timeout
            start, perturbations = scenario.start, scenario.perturbations
            self.stop_at_lap = scenario.stop_when == "lap_complete"
            # stop_when: still ends the run after this long without motion (None: it does not)
            self.still_stop_s = scenario.still_stop_s if scenario.stop_when == "still" else None
            robot = scenario.robot
        else:
            world = load_world(resolve_world_path(rospy.get_param("~world", "course")))
            robot = rospy.get_param("~robot", GENERIC)
            world = robot_world(world, robot)
            transport = world.camera_transport
            self.rate_hz = float(rospy.get_param("~rate_hz", 30.0))
            self.duration = float(rospy.get_param("~duration", 0.0))
            self.lockstep = bool(rospy.get_param("~lockstep", True))
            self.reply_timeout = float(rospy.get_param("~reply_timeout", REPLY_TIMEOUT_S))
            start, perturbations, self.stop_at_lap = None, Perturbations(), False
            self.still_stop_s = None
        if self.duration < 0 or not math.isfinite(self.duration):
            raise ValueError(f"~duration must be >= 0 s, got {self.duration}")
        self.sim = Simulation(world, rate_hz=self.rate_hz, start=start, perturbations=perturbations)
        self.record_path = rospy.get_param("~record", "")
        self.video_path = rospy.get_param("~video", "")
        debug_ns = rospy.get_param("~video_debug", "follower")
        self.debug_view = DebugView(debug_ns) if self.video_path and debug_ns else None
        self.wait_for_behaviour = float(rospy.get_param("~wait_for_behaviour", 20.0))
        self.laps = LapTracker(world.centreline()) if self.stop_at_lap else None

        self.camera_info = camera_info_msg(**self.sim.renderer.camera.camera_info_dict())
        self.inbox = CommandInbox()
        # Synchronous publishing (queue_size=None): each message is on the wire before the next
        # is made, so a behaviour never sees frame k while its clock still says k - n. With a
        # queue, a busy sim starved rospy's sender thread and the behaviour's clock lagged frames.
        # rospy warns about every queue_size=None publisher; here it is the intent.
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", "The publisher should be created", SyntaxWarning)
            self.clock_pub = rospy.Publisher("/clock", Clock, queue_size=None)
            self.jpeg_quality = transport.jpeg_quality if transport.name == "compressed" else None
            image_topic, info_topic = camera_topics(robot)
            if self.jpeg_quality is None:
                self.image_pub = rospy.Publisher(image_topic, Image, queue_size=None)
            else:  # what image_transport's `compressed` publisher would send
                self.image_pub = rospy.Publisher(
                    f"{image_topic}/compressed", CompressedImage, queue_size=None
                )
            self.info_pub = rospy.Publisher(info_topic, CameraInfo, queue_size=None)
            # Odometry too: a behaviour that steers by it (the follower's default) must have this
            # step's before this step's frame, or lockstep runs would not repeat.
            self.pose_pub = rospy.Publisher("~pose", Odometry, queue_size=None)
            self.odom_pub = rospy.Publisher("odom", Odometry, queue_size=None)
        self.tf = tf2_ros.TransformBroadcaster()
        self.cmd_sub = rospy.Subscriber("cmd_vel", Twist, self.inbox.put_command, queue_size=10)
        self.status_topic = rospy.get_param("~status", "")
        self.status_sub = None

    # -- helpers ----------------------------------------------------------------------------

    def _stamp(self) -> rospy.Time:
        return rospy.Time.from_sec(CLOCK_PREROLL_S + self.sim.time)

    def _publish_clock(self) -> None:
        self.clock_pub.publish(Clock(clock=self._stamp()))

    def _publish_frame(self) -> np.ndarray:
        stamp = self._stamp()
        image = self.sim.render()
        self.camera_info.header.stamp = stamp
        self.info_pub.publish(self.camera_info)
        frame_id = self.camera_info.header.frame_id
        if self.jpeg_quality is None:
            self.image_pub.publish(bgr_to_msg(image, stamp, frame_id))
        else:
            self.image_pub.publish(bgr_to_jpeg_msg(image, stamp, frame_id, self.jpeg_quality))
        return image

    def _publish_pose(self) -> None:
        x, y, yaw = self.sim.pose
        v, w = self.sim.robot.applied
        odom = Odometry()
        odom.header.stamp = self._stamp()
        odom.header.frame_id = "odom"
        odom.child_frame_id = BASE_FRAME
        odom.pose.pose.position.x, odom.pose.pose.position.y = x, y
        odom.pose.pose.orientation.z = math.sin(yaw / 2.0)
        odom.pose.pose.orientation.w = math.cos(yaw / 2.0)
        odom.twist.twist.linear.x, odom.twist.twist.angular.z = v, w
        self.pose_pub.publish(odom)
        self.odom_pub.publish(odom)
        tf = TransformStamped()
        tf.header, tf.child_frame_id = odom.header, BASE_FRAME
        tf.transform.translation.x, tf.transform.translation.y = x, y
        tf.transform.rotation = odom.pose.pose.orientation
        self.tf.sendTransform(tf)

    def _subscribe_status(self, timeout: float) -> None:
        try:
            topic = self.status_topic or find_topic(BehaviourStatus._type, timeout)
        except ValueError as error:
            raise ValueError(f"{error}: set ~status") from None
        if not topic:
            rospy.logwarn("sim: no behaviour status topic found; every frame will count as missed")
            return
        # A queue: every frame's answer counts, none may be dropped.
        self.status_sub = rospy.Subscriber(
            topic, BehaviourStatus, self.inbox.put_status, queue_size=100, tcp_nodelay=True
        )

    def _wait_for_behaviour(self) -> None:
        """Lockstep needs a listener on the image and a publisher of the status before frame 0,
        and the camera's mounting on tf (CLOCK_PREROLL_S)."""
        deadline = time.monotonic() + self.wait_for_behaviour
        self._subscribe_status(self.wait_for_behaviour)
        while not rospy.is_shutdown() and time.monotonic() < deadline:
            status_up = self.status_sub is not None and self.status_sub.get_num_connections()
            if self.image_pub.get_num_connections() and status_up:
                self._publish_clock()  # the pre-roll (robot_state_publisher's timer fires)
                self._wait_for_mounting()
                time.sleep(0.2)  # let the other connections (camera_info, clock, tf) settle too
                return
            time.sleep(0.02)
        rospy.logwarn("sim: no behaviour connected to the camera and its status; running anyway")

    def _wait_for_mounting(self) -> None:
        """Until the camera's frame is on tf, when a robot description is published: its latched
        /tf_static reaches the behaviour as it reaches this node."""
        if not rospy.has_param("robot_description"):
            return
        buffer = tf2_ros.Buffer()
        listener = tf2_ros.TransformListener(buffer)
        camera_frame = self.camera_info.header.frame_id
        deadline = time.monotonic() + MOUNTING_WAIT_S
        try:
            while not rospy.is_shutdown() and time.monotonic() < deadline:
                if buffer.can_transform(BASE_FRAME, camera_frame, rospy.Time()):
                    return
                self._publish_clock()  # again, for /clock connections still being made
                time.sleep(0.02)
            rospy.logwarn(f"sim: {BASE_FRAME} <- {camera_frame} not on tf; running anyway")
        finally:
            listener.unregister()

    def _finished(self) -> bool:
        if self.duration and self.sim.time >= self.duration - 1e-9:
            return True
        if self.still_stop_s is not None and self._still_for(self.still_stop_s):
            return True
        if self.laps is not None and self.sim.step_index % 15 == 0 and self.sim.record.pose:
            recent = np.asarray(self.sim.record.pose[-15:])[:, :2]
            self.laps.add(recent)
            return self.laps.lap_complete
        return False

    def _still_for(self, seconds: float) -> bool:
        """Every command of the last `seconds` of sim time was zero."""
        record = self.sim.record
        steps = int(math.ceil(seconds * self.rate_hz))
        if len(record.t) <= steps:
            return False
        recent = zip(record.v[-steps:], record.w[-steps:], strict=True)
        return all(v == 0.0 and w == 0.0 for v, w in recent)

    # -- loops ------------------------------------------------------------------------------

    def _behaviour_gone(self) -> bool:
        """No publisher on the status topic: the behaviour died or never started."""
        return self.status_sub is None or self.status_sub.get_num_connections() == 0

    def run(self) -> int:
        """Plays the run; the process's exit code (0, or BEHAVIOUR_GONE)."""
        video = None
        if self.video_path:
            cam = self.sim.renderer.camera
            fourcc = cv2.VideoWriter.fourcc(*"mp4v")
            width = cam.width * (2 if self.debug_view else 1)
            video = cv2.VideoWriter(self.video_path, fourcc, self.rate_hz, (width, cam.height))
        self.clock_pub.publish(Clock())  # ROS time 0 until the pre-roll
        if self.lockstep:
            self._wait_for_behaviour()
        self.inbox.take()  # forget anything sent before the run started
        applied = (0.0, 0.0)  # the robot starts still; an idle behaviour's silence holds this
        period = 1.0 / self.rate_hz
        next_wall = loop_start = time.monotonic()
        try:
            while not rospy.is_shutdown() and not self._finished():
                self._publish_clock()
                self._publish_pose()
                frame = self.sim.frames_flowing()
                image = self._publish_frame() if frame else None
                missed = False
                if self.lockstep:
                    if frame:
                        missed = not self.inbox.wait(self.reply_timeout)
                        if missed and self._behaviour_gone():
                            rospy.logerr(
                                "sim: no answer and no publisher on the behaviour's status "
                                f"topic at {self.sim.time:.2f} s: the behaviour is not running"
                            )
                            return BEHAVIOUR_GONE
                    else:
                        # Frames withheld (camera dropout): sim time passes at wall pace, as on a
                        # robot, so the behaviour's watchdog timers fire on time even when the
                        # machine is loaded (faster pacing starved them and delayed the stop).
                        time.sleep(period)
                else:
                    next_wall += period
                    time.sleep(max(0.0, next_wall - time.monotonic()))
                if video is not None and image is not None:  # after the reply: its overlay too
                    video.write(self.debug_view.frame(image) if self.debug_view else image)
                replies, sent, commands, command = self.inbox.take()
                if self.lockstep and frame:
                    # The frame's cmd_vel, as its status reports it: counted and applied in this
                    # step whenever it arrives on its own connection, so runs repeat exactly. No
                    # command: the behaviour is quiet, its last cmd_vel was a zero (its idle
                    # stop, the watchdog's or ~enable's), so the robot stands.
                    applied = command if command is not None else (0.0, 0.0)
                    commands = sent
                elif commands or not self.lockstep:
                    applied = self.inbox.latest
                self.sim.step(
                    applied, frame=frame, replies=replies, commands=commands, missed=missed
                )
        finally:
            if video is not None:
                video.release()
            self._write_record(time.monotonic() - loop_start)
        return 0

    def _write_record(self, loop_wall: float) -> None:
        if not self.record_path:
            return
        Path(self.record_path).parent.mkdir(parents=True, exist_ok=True)
        arrays = self.sim.record.arrays()
        np.savez(self.record_path, loop_wall=loop_wall, **arrays)
        rospy.loginfo(
            "sim: %d steps, %.2f s sim time, %d missed replies, record %s",
            len(arrays["t"]),
            self.sim.time,
            int(arrays["missed"].sum()),
            self.record_path,
        )


def main() -> None:
    example = "example: rosrun harness sim _world:=course _lockstep:=false"
    parse_node_command_line(rospy.myargv()[1:], "sim", __doc__, example)  # --help starts nothing
    rospy.init_node("sim")
    # A frame is a chain of small OpenCV calls: worker threads barely shorten it and their
    # hand-offs cost CPU the behaviour under test needs (realistic frames: 22 -> 17.6 ms of CPU at
    # the same wall time; the pixels are the same).
    cv2.setNumThreads(1)
    try:
        node = SimNode()
    except (ScenarioError, WorldError, ValidationError, ValueError) as error:
        rospy.logfatal(f"sim: {error}")
        raise SystemExit(2) from None
    raise SystemExit(node.run())


if __name__ == "__main__":
    main()
