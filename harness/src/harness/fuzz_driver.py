"""One node under the fuzzer: started in its own process, sent a storm, then checked (alive, a
valid frame answered rightly, every Twist finite and within the limits, its own counters
against what was sent).
"""

from __future__ import annotations

import math
import subprocess
import threading
import time
from pathlib import Path

from harness.fuzz_cases import CAMERA_INFO_OUTCOMES, FRAME_OUTCOMES, frame_outcome
from harness.processes import stop
from harness.testing import (
    LIMIT_ANGULAR,
    LIMIT_LINEAR,
    WIDTH,
    NodeSpec,
    compressed_msg,
    expected_range,
    odom_msg,
    pinhole_info,
    probe_frame,
)

# Messages lost in transport that a node's counters may miss, a fraction of those sent (see
# count_errors): the fuzzer's queues lose none, and the storm waits for the answer to every
# frame a node must accept, so a node's input queue of 1 loses a message only when the machine
# holds the node's thread for longer than the next two messages take to arrive (measured: 0 to
# 1 % at a load of 20 on 2 cores); and how long the final counters may take to reach
# /diagnostics.
LOST_ALLOWED = 0.03
COUNTS_TIMEOUT_S = 10.0
DIAGNOSTIC_PERIOD_S = 0.2
QUEUE = 100  # the fuzzer's publisher queues
PROCESSED_TIMEOUT_S = 5.0  # for a node's answer to a frame it must accept
MAX_UNANSWERED = 3


class FuzzedNode:
    def __init__(
        self, key: str, spec: NodeSpec, env: dict, log_dir: Path, run: int, compressed: bool
    ):
        import rospy
        from geometry_msgs.msg import PoseStamped, Twist
        from nav_msgs.msg import Odometry
        from sensor_msgs.msg import CameraInfo, Image

        self.key, self.spec = key, spec
        # A fresh name per run: the master shuts down a same-named node's old address, which a
        # new process may have been given.
        self.name = f"fuzz{run}_{key}"
        ns = f"/fuzz{run}/{key}"
        topics = {"camera/rgb/image_raw": "image", "camera/rgb/camera_info": "camera_info"}
        topics |= {"cmd_vel": "cmd_vel", "odom": "odom"}
        args = [f"{name}:={ns}/{short}" for name, short in topics.items()]
        args.append(f"_diagnostic_period:={DIAGNOSTIC_PERIOD_S}")  # the final counters sooner
        if compressed:
            args.append("_image_transport:=compressed")
        self.compressed = compressed
        log_dir.mkdir(parents=True, exist_ok=True)
        self.log = open(log_dir / f"{key}.log", "w")  # noqa: SIM115 (closed in finish)
        self.process = subprocess.Popen(
            ["rosrun", *spec.rosrun_args(f"__name:={self.name}", *args)],
            env=env, stdout=self.log, stderr=subprocess.STDOUT,
        )  # fmt: skip
        self.lock = threading.Lock()
        self.twists = 0
        self.non_finite = 0
        self.over_limit = 0
        self.answers: list = []
        self.counts: dict[str, int] = {}  # its diagnostics' frame counters, latest
        if compressed:
            from sensor_msgs.msg import CompressedImage

            self.image_pub = rospy.Publisher(
                f"{ns}/image/compressed", CompressedImage, queue_size=1, tcp_nodelay=True
            )
        else:  # a queue: the fuzzer loses none; the node's own input queue is 1
            self.image_pub = rospy.Publisher(
                f"{ns}/image", Image, queue_size=QUEUE, tcp_nodelay=True
            )
        self.info_pub = rospy.Publisher(
            f"{ns}/camera_info", CameraInfo, queue_size=QUEUE, tcp_nodelay=True
        )
        self.odom_pub = rospy.Publisher(f"{ns}/odom", Odometry, queue_size=1)
        # Every frame a node processes gets one answer: a behaviour's ~status, image_converter's
        # ~output. The storm waits for it after each frame the node must accept (wait_processed).
        self.processed = 0
        self.processed_cond = threading.Condition()
        self.awaiting = 0  # the processed count the last frame it must accept brings
        self.unanswered = 0  # frames it must accept whose answer never came
        self.subs = []
        if spec.behaviour:
            from follow_bot_msgs.msg import BehaviourStatus

            topic, answer_type = f"/{self.name}/status", BehaviourStatus
        else:
            topic, answer_type = f"/{self.name}/output", Image
        self.subs.append(rospy.Subscriber(topic, answer_type, self._on_processed, tcp_nodelay=True))
        if spec.probe == "overlay":
            topic = f"/{self.name}/output"
            self.subs.append(rospy.Subscriber(topic, Image, self._on_answer, tcp_nodelay=True))
        else:
            twists = rospy.Subscriber(f"{ns}/cmd_vel", Twist, self._on_twist, tcp_nodelay=True)
            self.subs.append(twists)
        if spec.probe in ("tag", "sign"):
            topic = f"/{self.name}/target_pose"
            self.subs.append(rospy.Subscriber(topic, PoseStamped, self._on_answer))
        if spec.probe == "line":
            from follow_bot.msg import LineStatus

            self.subs.append(rospy.Subscriber(f"/{self.name}/line", LineStatus, self._on_answer))
        if spec.probe == "idle":  # an idle behaviour answers on ~status only, never cmd_vel
            from follow_bot_msgs.msg import BehaviourStatus

            topic = f"/{self.name}/status"
            self.subs.append(rospy.Subscriber(topic, BehaviourStatus, self._on_answer))
        if spec.probe == "green":
            from follow_bot.msg import BeaconDetections

            topic = f"/{self.name}/detections"
            self.subs.append(rospy.Subscriber(topic, BeaconDetections, self._on_answer))
        self.capture_reply = None
        self.sent = {"image": 0, "camera_info": 0, "odom": 0}
        # The node's diagnostics counters as each message sent must move them (frame_outcome,
        # Storm.camera_info); None once a message's fate is not known (a compressed payload the
        # transport may drop before the node sees it, a camera_info of unknown usability).
        self.expected: dict[str, int] | None = dict.fromkeys(self.outcome_keys(), 0)

    def _on_twist(self, msg):
        values = [msg.linear.x, msg.linear.y, msg.linear.z, msg.angular.x, msg.angular.y]
        values.append(msg.angular.z)
        with self.lock:
            self.twists += 1
            if not all(math.isfinite(v) for v in values):
                self.non_finite += 1
            elif (
                abs(msg.linear.x) > LIMIT_LINEAR
                or abs(msg.angular.z) > LIMIT_ANGULAR
                or any(values[1:5])
            ):
                self.over_limit += 1
            if self.spec.probe in ("twist", "turning"):
                self.answers.append(msg)

    def _on_answer(self, msg):
        with self.lock:
            self.answers.append(msg)

    def _on_processed(self, _msg):
        with self.processed_cond:
            self.processed += 1
            self.processed_cond.notify_all()

    def wait_processed(self, timeout: float) -> None:
        """Waits until the node answered the last frame it must accept: the messages after it
        then find its input queue empty, unless the machine starves the node (count_errors).
        A node that left MAX_UNANSWERED such frames unanswered is not waited for any more: it
        drops frames it must accept, which its counters will show."""
        if self.unanswered >= MAX_UNANSWERED:
            return
        with self.processed_cond:
            if not self.processed_cond.wait_for(lambda: self.processed >= self.awaiting, timeout):
                self.unanswered += 1

    def wait_connected(self, timeout: float) -> bool:
        deadline = time.monotonic() + timeout
        pubs = [self.image_pub]
        while time.monotonic() < deadline:
            alive = self.process.poll() is None
            if not alive:
                return False
            if all(p.get_num_connections() > 0 for p in pubs) and all(
                s.get_num_connections() > 0 for s in self.subs
            ):
                return True
            time.sleep(0.05)
        return False

    def prepare(self):
        """Intrinsics and a pose; a capture running in the background when asked."""
        self.send(pinhole_info(), usable=True)
        self.odom_pub.publish(odom_msg())
        time.sleep(0.1)
        if self.spec.capturing:
            self.start_capture()

    def start_capture(self):
        import rospy
        from std_srvs.srv import Trigger

        service = f"/{self.name}/capture"
        rospy.wait_for_service(service, timeout=20)
        frame = self.valid(probe_frame("idle"))
        for _ in range(3):
            self.send(frame)
            time.sleep(0.05)

        def call():
            try:
                self.capture_reply = rospy.ServiceProxy(service, Trigger)()
            except Exception as error:  # the node going away mid-call is reported elsewhere
                self.capture_reply = error

        threading.Thread(target=call, daemon=True).start()
        time.sleep(0.2)

    def keep_capturing(self):
        """A valid frame for a capturing node: invalid ones do not count against the frame
        timeout (~frame_timeout, 1 s) that would end the capture."""
        if self.spec.capturing:
            self.send(self.valid(probe_frame("idle")))
            time.sleep(0.05)

    def valid(self, frame):
        """A valid bgr8 frame in this node's transport."""
        return compressed_msg(frame) if self.compressed else frame

    def outcome_keys(self) -> list[str]:
        return FRAME_OUTCOMES + (CAMERA_INFO_OUTCOMES if self.spec.behaviour else [])

    def send(self, msg, usable: bool | None = None):
        """Publishes `msg` and counts what the node must do with it (`usable`: a camera_info's
        fate, known by construction)."""
        kind = {"sensor_msgs/CameraInfo": "camera_info", "nav_msgs/Odometry": "odom"}.get(
            msg._type, "image"
        )
        with self.processed_cond:
            processed = self.processed
        {"image": self.image_pub, "camera_info": self.info_pub, "odom": self.odom_pub}[
            kind
        ].publish(msg)
        self.sent[kind] += 1
        if self.expected is None or kind == "odom":
            return
        if kind == "camera_info":
            if not self.spec.behaviour:  # image_converter reads none
                return
            outcome = None if usable is None else CAMERA_INFO_OUTCOMES[0 if usable else 1]
        else:
            outcome = None if self.compressed else frame_outcome(msg, self.spec.behaviour)
        if outcome is None:
            self.expected = None
        else:
            self.expected[outcome] += 1
            if outcome == "frames_accepted":
                self.awaiting = processed + 1

    def on_diagnostics(self, status: dict) -> None:
        """The node's latest frame counters (its "<node>: behaviour" or "<node>: frames")."""
        with self.lock:
            self.counts = {k: int(status[k]) for k in self.outcome_keys() if k in status}

    def diagnostics_name(self) -> str:
        # diagnostic_updater's "<node name without its leading slash>: <status>"
        return f"{self.name}: " + ("behaviour" if self.spec.behaviour else "frames")

    def wait_counts(self, timeout: float) -> dict[str, int]:
        """The node's counters once they add up to every message sent (or at the timeout: then
        the shortfall is what transport lost). With no expectation (a message's fate unknown)
        there is nothing to wait for: the counters as they are."""
        if self.expected is None:
            with self.lock:
                return dict(self.counts)
        deadline = time.monotonic() + timeout
        while True:
            with self.lock:
                counts = dict(self.counts)
            if sum(counts.values()) >= sum(self.expected.values()) or time.monotonic() > deadline:
                return counts
            time.sleep(0.05)

    def probe(self) -> str:
        """Empty when a valid frame gets the right answer, else what went wrong."""
        self.send(pinhole_info(), usable=True)
        self.odom_pub.publish(odom_msg())
        time.sleep(0.2)
        probe = self.spec.probe
        error = "no answer"
        for _ in range(5):  # the first answers may still be the watchdog's stop
            with self.lock:
                self.answers.clear()
            self.send(self.valid(probe_frame(probe)))
            deadline = time.monotonic() + 3.0
            while time.monotonic() < deadline:
                with self.lock:
                    answers = list(self.answers)
                if answers:
                    time.sleep(0.05)
                    with self.lock:
                        answers = list(self.answers)
                    error = check_answer(probe, answers)
                    break
                time.sleep(0.01)
            if not error:
                return ""
            time.sleep(0.05)
        return error

    def finish(self) -> dict:
        alive = self.process.poll() is None
        code = self.process.returncode
        probe_error = self.probe() if alive else "process died"
        if self.spec.probe == "idle" and self.twists and not probe_error:
            probe_error = f"idle node sent {self.twists} cmd_vel Twists"
        alive = alive and self.process.poll() is None
        counts = self.wait_counts(COUNTS_TIMEOUT_S) if alive else {}
        stop(self.process)
        self.log.close()
        with self.lock:
            return {
                "expected": self.expected,
                "counts": counts,
                "count_errors": count_errors(self.expected, counts),
                "node": self.key,
                "messages": sum(self.sent.values()),
                **self.sent,
                "alive": alive,
                "exit_code": None if alive else code,
                "crashes": 0 if alive else 1,
                "probe": probe_error or "ok",
                "twists": self.twists,
                "non_finite": self.non_finite,
                "over_limit": self.over_limit,
            }


def count_errors(expected: dict[str, int] | None, counts: dict[str, int]) -> list[str]:
    """How a node's own counters disagree with what it was sent. Every message is counted once,
    under the outcome the fuzzer expects: no counter may exceed its expected count (a message
    counted under the wrong reason fails); only messages lost in transport (the node's input
    queue of 1 drops the older message when a newer one arrives before the node took it) go
    uncounted, at most LOST_ALLOWED of all sent, and each counter may fall short by no more than
    were lost in all."""
    if expected is None:
        return []
    if not counts:
        return ["no frame counters on /diagnostics"]
    sent, counted = sum(expected.values()), sum(counts.values())
    lost = sent - counted
    errors = []
    if lost < 0:
        errors.append(f"{counted} messages counted, {sent} sent")
    elif lost > LOST_ALLOWED * sent:
        allowed = f"transport may lose {LOST_ALLOWED:.0%}"
        errors.append(f"{lost} of {sent} messages uncounted ({allowed})")
    for key, want in expected.items():
        got = counts.get(key, 0)
        if not want - max(lost, 0) <= got <= want:
            errors.append(f"{key}: {got} counted, {want} expected")
    return errors


def check_answer(probe: str, answers: list) -> str:
    last = answers[-1]
    if probe == "overlay":
        from follow_bot_msgs.ros_image import msg_to_bgr

        image = msg_to_bgr(last)
        # The red circle (radius 25) crosses the centre row 25 px right of the centre.
        if image.shape != (64, 64, 3) or tuple(image[32, 57]) != (0, 0, 255):
            return f"overlay wrong: {image.shape} {image[32, 57] if image.ndim == 3 else ''}"
        if tuple(image[32, 32]) != (90, 90, 90):
            return "overlay changed the centre pixel"
        return ""
    if probe == "line":
        if not last.found or abs(last.centroid_x - WIDTH / 2) > 1.0:
            return f"line at {last.centroid_x} found={last.found}, expected {WIDTH / 2}"
        return ""
    if probe == "green":
        green = [d for d in last.detections if d.colour == "green"]
        if not green or not green[0].found or abs(green[0].centroid_x - WIDTH / 2) > 2:
            return f"green beacon not found at the centre: {green}"
        return ""
    if probe in ("tag", "sign"):
        z = last.pose.position.z
        expected = expected_range(probe)
        assert expected is not None  # the marker probes have a range
        if abs(z - expected) > 0.05 * expected or abs(last.pose.position.x) > 0.05:
            return f"marker at z={z:.3f} x={last.pose.position.x:.3f}, expected z={expected:.3f}"
        return ""
    if probe == "idle":  # BehaviourStatus answers
        if any(s.active or s.command_sent for s in answers):
            return f"idle panorama steering: {last.state}, sent {last.command_sent}"
        return ""
    if probe == "turning":
        if not last.angular.z > 0.0:
            return f"capturing panorama not turning toward the left end: {last.angular.z}"
        return ""
    return f"unknown probe {probe}"
