"""Quiet when idle (docs/behaviour_contract.md), on real nodes: a behaviour publishes
cmd_vel only while it steers, one zero when it stops, ~enable turns it off and on, and its
~status answers every frame.

Each case starts a roscore and one node, then plays frames from a child process (this file with
--client CASE, tests/README.md) in lockstep on the node's ~status: publish a frame, wait for its
status (and for the cmd_vel that status says went out). The child prints what it saw as JSON. No
wall-clock window decides anything: the first frame waits for the node's /diagnostics to count the
camera_info taken, and the nodes run with their frame watchdogs raised (a loaded machine can hold
the client longer than the default 0.15 s between two frames, and a watchdog's zero would be a
cmd_vel no frame asked for), except the idle panorama's, whose silence when the frames stop is part
of its case."""

from __future__ import annotations

import json
import sys
import time

import cv2
import pytest

from harness.apriltag_image import tag_image
from harness.processes import run_with_client
from harness.testing import Lockstep, bgr_msg, floor, probe_frame

RATE = Lockstep.RATE
MUX_TIMEOUT_S = 0.5  # an input silent this long loses the mux (twist_mux's usual timeout)


def blank():
    return bgr_msg(floor())


def tag_at(cell: int):
    """The tag probe frame with the tag `cell` px per tag cell (12: the probe's 1.73 m)."""
    image = floor((255, 255, 255))
    big = cv2.resize(tag_image(), None, fx=cell, fy=cell, interpolation=cv2.INTER_NEAREST)
    y0, x0 = (480 - big.shape[0]) // 2, (640 - big.shape[1]) // 2
    image[y0 : y0 + big.shape[0], x0 : x0 + big.shape[1]] = big[:, :, None]
    return bgr_msg(image)


def client(case: str) -> dict:
    import rospy
    from geometry_msgs.msg import Twist
    from std_srvs.srv import SetBool

    rospy.init_node("idle_client", disable_signals=True)
    out: dict = {}
    if case == "panorama_idle":
        steps = Lockstep("panorama")
        for _ in range(int(10 * RATE)):  # 10 s of frames at 30 Hz, no capture
            steps.frame(probe_frame("idle"), wall_rate=True)
        # The watchdog has seen the frames stop too, and sent nothing: there was nothing to stop.
        out["outage_seen"] = steps.wait_diagnostics(
            lambda d: d.get("message", "").startswith("no frames, idle: nothing to stop")
        )
    elif case == "follower_gives_up":
        steps = Lockstep("follower")
        # A mux-like priority node: the behaviour's cmd_vel wins over teleop while it has spoken
        # within MUX_TIMEOUT_S; the mux's output is what the base would get.
        muxed: list[tuple[float, str]] = []
        teleop = Twist()
        teleop.linear.x = 0.123

        def mux_tick(_event):
            with steps.cond:
                last = steps.twists[-1][0] if steps.twists else -1e9
            source = "behaviour" if time.monotonic() - last < MUX_TIMEOUT_S else "teleop"
            muxed.append((time.monotonic(), source))

        for _ in range(30):
            steps.frame(probe_frame("line"))
        # Line gone: lost (1 s), searching (12 s), gave up; then 3 s more at 30 Hz of wall
        # clock with teleop driving through the mux.
        while steps.statuses[-1].active:
            steps.frame(blank())
            assert len(steps.statuses) < 30 + 20 * RATE, "never gave up"
        out["gave_up_at"] = len(steps.statuses) - 1
        timer = rospy.Timer(rospy.Duration(1.0 / RATE), mux_tick)
        for _ in range(int(3 * RATE)):
            steps.frame(blank(), wall_rate=True)
        timer.shutdown()
        out["muxed"] = muxed
    elif case == "follower_enable":
        steps = Lockstep("follower")
        enable = rospy.ServiceProxy("/follower/enable", SetBool)
        for _ in range(30):
            steps.frame(probe_frame("line"))
        before = len(steps.twists)
        reply = enable(False)
        out["disable_reply"] = [reply.success, reply.message]
        # The zero is published by the call itself, before the next frame; a second Twist would
        # come while the disabled frames are answered.
        out["disabled_from"] = len(steps.statuses)
        for _ in range(30):
            steps.frame(probe_frame("line"))
        out["twists_at_disable"] = steps.twists[before:]
        out["enabled_from"] = len(steps.statuses)
        enable(True)
        for _ in range(30):
            steps.frame(probe_frame("line"))
    elif case == "parker_parked":
        steps = Lockstep("parker")
        for _ in range(10):  # the tag twice as far as the standoff: approaching
            steps.frame(tag_at(6))
        out["at_standoff_from"] = len(steps.statuses)
        for _ in range(30):  # the tag right at the standoff: parks
            steps.frame(tag_at(12))
        out["pushed_from"] = len(steps.statuses)
        for _ in range(10):  # pushed back to twice as far: out of tolerance
            steps.frame(tag_at(6))
    out.update(steps.summary())
    return out


# No robot description here: every node takes its camera's mounting from its ~params. Frame
# watchdogs raised (see the module's docstring), on wall time as on ROS time: there is no /clock.
RAISED_WATCHDOGS = ["_watchdog_timeout:=10", "_wall_watchdog_timeout:=10"]
NODES = {
    "panorama_idle": ["follow_bot", "panorama", "_camera_mounting:=params"],
    "follower_gives_up": [
        "follow_bot", "follower", "_mode:=pd", "_camera_mounting:=params", *RAISED_WATCHDOGS,
    ],
    "follower_enable": [
        "follow_bot", "follower", "_mode:=pd", "_camera_mounting:=params", *RAISED_WATCHDOGS,
    ],
    # The standoff is the probe tag's distance (fuzz.expected_range("tag"), camera at the base
    # origin, level), tolerances wide enough that its quantised pose counts as parked.
    "parker_parked": [
        "follow_bot", "parker", "_standoff:=1.7321", "_camera_x_offset:=0.0",
        "_camera_pitch_deg:=0", "_position_tolerance:=0.05", "_lateral_tolerance:=0.05",
        "_heading_tolerance_deg:=5", "_camera_mounting:=params", *RAISED_WATCHDOGS,
    ],
}  # fmt: skip


def play(case: str) -> dict:
    return run_with_client(NODES[case], [sys.executable, __file__, "--client", case], timeout=180)


def sent_commands(result: dict, start: int = 0) -> list[tuple[float, float]]:
    return [(s[2], s[3]) for s in result["statuses"][start:] if s[1]]


def test_idle_panorama_sends_no_cmd_vel_in_10_s_but_answers_every_frame():
    result = play("panorama_idle")
    assert result["outage_seen"], "the watchdog never saw the frames stop"
    assert result["twists"] == []
    assert len(result["statuses"]) == 300
    assert all(s[:2] == [False, False] and s[4] == "idle" for s in result["statuses"])


@pytest.fixture(scope="module")
def gave_up() -> dict:
    return play("follower_gives_up")


def test_follower_that_gave_up_sends_exactly_one_zero_then_nothing(gave_up):
    statuses, k = gave_up["statuses"], gave_up["gave_up_at"]
    assert statuses[29][:2] == [True, True] and statuses[29][2] > 0  # it drove
    assert statuses[k][4] == "gave_up"
    after = sent_commands(gave_up, k)
    assert after[-1] == (0.0, 0.0) and (0.0, 0.0) not in after[:-1]  # a ramp down, one zero
    last_sent = max(i for i, s in enumerate(statuses) if s[1])
    assert last_sent < k + 10 and len(statuses) - 1 - last_sent >= 80  # then ~3 s of silence
    # Every status that says "sent" has its cmd_vel, and no other cmd_vel went out.
    assert len(gave_up["twists"]) == len(sent_commands(gave_up))
    assert [tuple(t[1:]) for t in gave_up["twists"]] == sent_commands(gave_up)


def test_teleop_through_a_priority_mux_is_never_overridden_by_the_idle_follower(gave_up):
    last_twist = gave_up["twists"][-1][0]
    after = [source for t, source in gave_up["muxed"] if t > last_twist + MUX_TIMEOUT_S]
    assert len(after) > 60 and set(after) == {"teleop"}


def test_enable_false_sends_one_zero_at_once_and_true_drives_again():
    result = play("follower_enable")
    statuses = result["statuses"]
    assert result["disable_reply"][0] is True
    assert [tuple(t[1:]) for t in result["twists_at_disable"]] == [(0.0, 0.0)]
    disabled = statuses[result["disabled_from"] : result["enabled_from"]]
    assert len(disabled) == 30 and not any(s[0] or s[1] for s in disabled)
    assert len(result["twists"]) == len(sent_commands(result)) + 1  # + the disabling zero
    enabled = statuses[result["enabled_from"] :]
    assert all(s[0] and s[1] for s in enabled) and enabled[-1][2] > 0.1


def test_parked_parker_sends_one_zero_stays_quiet_and_a_push_reactivates_it():
    result = play("parker_parked")
    statuses, pushed = result["statuses"], result["pushed_from"]
    approaching = statuses[: result["at_standoff_from"]]
    assert all(s[0] and s[1] and s[4] == "approaching" for s in approaching)
    assert approaching[-1][2] > 0.0  # driving toward the tag
    parked = [i for i, s in enumerate(statuses) if s[4] == "parked"]
    assert parked and parked[-1] == pushed - 1, [s[4] for s in statuses]  # parked till pushed
    first = parked[0]
    assert all(not s[0] for s in statuses[first:pushed])
    # The limiter's ramp down to the one zero, then nothing while parked.
    stopping = sent_commands(result, first)[: sum(s[1] for s in statuses[first:pushed])]
    assert stopping[-1] == (0.0, 0.0) and (0.0, 0.0) not in stopping[:-1]
    assert not any(s[1] for s in statuses[pushed - 10 : pushed])
    pushed_away = statuses[pushed:]
    assert all(s[0] and s[1] for s in pushed_away) and pushed_away[-1][2] > 0.0  # steers again
    assert [tuple(t[1:]) for t in result["twists"]] == sent_commands(result)


if __name__ == "__main__" and sys.argv[1:2] == ["--client"]:
    print(json.dumps(client(sys.argv[2]), default=float))
