"""The display-only lab nodes (follow_bot/scripts: colour_filter.py, three_colours.py,
colour_flags.py) on a known frame: the exact pixels of their ~image and the flags they raise;
follow_green_stop_red.py keeping the behaviour contract (cmd_vel while driving, one zero on
stopping, a zero on shutdown).

Each case starts a roscore and the node (rosrun: Debian's python3), then a child process (this file
with --client NODE OUT, tests/README.md; the venv's python) publishes the frame on
camera/rgb/image_raw until the node answers, and writes what came back to OUT (.npz). The driving
lab nodes are played by the scenario families worlds/scenarios/lab_*.yaml
(tests/closed_loop/test_scenarios.py)."""

from __future__ import annotations

import json
import subprocess
import sys
import time

import numpy as np
import pytest

from harness.processes import private_master, run_with_client

GREY = (110, 115, 120)  # BGR floor: saturation 21, below every colour's floor
RECTS = {  # BGR colour and (rows, columns) of each patch
    "red": ((0, 0, 200), (slice(100, 180), slice(80, 200))),
    "green": ((0, 200, 0), (slice(100, 180), slice(260, 380))),
    "blue": ((200, 0, 0), (slice(300, 310), slice(400, 410))),  # 10x10: below min_area
}


def known_frame() -> np.ndarray:
    frame = np.full((480, 640, 3), GREY, np.uint8)
    for colour, (rows, cols) in RECTS.values():
        frame[rows, cols] = colour
    return frame


def patch_mask(*names: str) -> np.ndarray:
    """What the lab nodes' colour masks hold on known_frame(), from its geometry alone: each
    named patch but for its four corner pixels. The patches' pure colours are inside their
    colour boxes and the grey floor outside every one; the mask's 3x3 elliptical opening is a
    cross, which removes exactly a rectangle's corners, and its 5x5 closing adds none back."""
    mask = np.zeros((480, 640), bool)
    for name in names:
        rows, cols = RECTS[name][1]
        mask[rows, cols] = True
        for y in (rows.start, rows.stop - 1):
            for x in (cols.start, cols.stop - 1):
                mask[y, x] = False
    return mask


def boundary(mask: np.ndarray) -> np.ndarray:
    """The pixels of `mask` with a 4-neighbour outside it."""
    inner = mask.copy()
    inner[1:-1, 1:-1] &= mask[:-2, 1:-1] & mask[2:, 1:-1] & mask[1:-1, :-2] & mask[1:-1, 2:]
    return mask & ~inner


def patch_frame(colour, size=40) -> np.ndarray:
    """The grey floor with a `size` px square of `colour` (BGR) at the centre."""
    frame = np.full((480, 640, 3), GREY, np.uint8)
    frame[240 - size // 2 : 240 + size // 2, 320 - size // 2 : 320 + size // 2] = colour
    return frame


def contract_client() -> dict:
    """Lockstep on follow_green_stop_red's ~status: green ahead, then red, then `rosnode kill`."""
    import rospy

    from harness.testing import Lockstep, bgr_msg

    rospy.init_node("lab_client", disable_signals=True)
    steps = Lockstep("follow_green_stop_red", reads_camera_info=False)  # colour only
    for _ in range(15):
        steps.frame(bgr_msg(patch_frame(RECTS["green"][0])))
    for _ in range(30):
        steps.frame(bgr_msg(patch_frame(RECTS["red"][0], size=60)))
    time.sleep(0.5)  # frames stopped: the watchdog must not send a second zero
    subprocess.run(["rosnode", "kill", "/follow_green_stop_red"], capture_output=True, check=True)
    time.sleep(1.0)
    return steps.summary()


def client(node: str, out: str) -> dict:
    import rospy
    from sensor_msgs.msg import Image
    from std_msgs.msg import String

    from follow_bot_msgs.ros_image import bgr_to_msg, msg_to_bgr

    rospy.init_node("lab_client", disable_signals=True)
    got: dict = {}
    rospy.Subscriber(f"/{node}/image", Image, lambda m: got.setdefault("image", m))
    rospy.Subscriber(f"/{node}/flags", String, lambda m: got.setdefault("flags", m.data))
    publisher = rospy.Publisher("/camera/rgb/image_raw", Image, queue_size=1)
    wanted = {"image", "flags"} if node == "colour_flags" else {"image"}
    deadline = time.monotonic() + 60
    while not wanted <= got.keys() and time.monotonic() < deadline:
        publisher.publish(bgr_to_msg(known_frame(), rospy.Time.now(), "camera"))
        time.sleep(0.2)
    image = got["image"]
    picture = msg_to_bgr(image) if image.encoding == "bgr8" else None
    np.savez(out, image=picture)
    return {"encoding": image.encoding, "flags": json.loads(got.get("flags", "null"))}


def play(node: str, tmp_path) -> tuple[dict, np.ndarray]:
    out = tmp_path / "out.npz"
    result = run_with_client(
        ["follow_bot", f"{node}.py"], [sys.executable, __file__, "--client", node, str(out)],
        timeout=120,
    )  # fmt: skip
    assert result["encoding"] == "bgr8"
    return result, np.load(out)["image"]


def kept(frame: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """The frame where `mask` is set, black elsewhere (the worksheet's bitwise_and)."""
    return np.where(mask[..., None], frame, 0).astype(np.uint8)


def test_colour_filter_keeps_exactly_the_green_patch(tmp_path):
    _, image = play("colour_filter", tmp_path)  # ~colour: green by default
    frame = known_frame()
    rows, cols = RECTS["green"][1]
    inside = np.zeros(frame.shape[:2], bool)
    inside[rows, cols] = True
    assert not image[~inside].any()  # black everywhere outside the green patch
    # Inside it, the green itself, but for the corners the mask's opening (ellipse) rounds off.
    assert np.count_nonzero(image[inside].any(axis=1)) >= inside.sum() - 40
    assert tuple(image[140, 320]) == (0, 200, 0) and tuple(image[100, 300]) == (0, 200, 0)
    assert np.array_equal(image, kept(frame, patch_mask("green")))


def test_three_colours_keeps_red_green_and_blue(tmp_path):
    _, image = play("three_colours", tmp_path)
    frame = known_frame()
    assert np.array_equal(image, kept(frame, patch_mask("red", "green", "blue")))
    assert tuple(image[140, 140]) == (0, 0, 200) and tuple(image[140, 320]) == (0, 200, 0)
    assert tuple(image[20, 20]) == (0, 0, 0)  # the grey floor is gone
    big = np.zeros(frame.shape[:2], bool)
    for name in ("red", "green"):
        big[RECTS[name][1]] = True
    assert np.count_nonzero(image[big].any(axis=1)) >= big.sum() - 80


def test_colour_flags_raise_for_big_contours_only(tmp_path):
    result, image = play("colour_flags", tmp_path)
    flags = result["flags"]
    assert (flags["red"]["flag"], flags["green"]["flag"], flags["blue"]["flag"]) == (
        True, True, False,
    )  # fmt: skip
    # An 80x120 px patch without its corner pixels (patch_mask): its contour through the edge
    # pixels' centres encloses 79 x 119 px^2 less a half-pixel triangle at each corner; the
    # centroid at its centre. The 10x10 px blue patch (9 x 9 - 2) is below min_area (100 px^2):
    # no blob, no area.
    for name, (x, y) in (("red", (139.5, 139.5)), ("green", (319.5, 139.5))):
        assert flags[name]["area"] == 79 * 119 - 2
        assert flags[name]["centroid"] == pytest.approx([x, y], abs=0.01)
    assert flags["blue"]["area"] == 0
    # The flagged contours drawn in white over the patches' edge pixels, nothing else changed.
    changed = np.any(image != known_frame(), axis=2)
    assert np.all(image[changed] == 255)
    assert np.array_equal(changed, boundary(patch_mask("red", "green")))


def test_lab_nodes_answer_help_with_both_pythons():
    scripts = ["colour_filter", "three_colours", "colour_flags", "follow_green_stop_red",
               "line_follower"]  # fmt: skip
    for python in ("/usr/bin/python3", sys.executable):
        for script in scripts:
            path = subprocess.run(
                ["rospack", "find", "follow_bot"], capture_output=True, text=True, check=True
            ).stdout.strip()
            out = subprocess.run(
                [python, f"{path}/scripts/{script}.py", "--help"],
                capture_output=True, text=True, timeout=60,
            )  # fmt: skip
            assert out.returncode == 0, out.stderr
            assert "private parameters:" in out.stdout and "~" in out.stdout, script


@pytest.mark.parametrize("limit_linear", [None, 0.02])
def test_follow_green_stop_red_drives_then_stops_once_and_zeroes_on_shutdown(limit_linear):
    limit = [] if limit_linear is None else [f"_limit_linear:={limit_linear}"]
    with private_master() as env:
        node = subprocess.Popen(
            ["rosrun", "follow_bot", "follow_green_stop_red.py", *limit], env=env,
            stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT,
        )  # fmt: skip
        try:
            done = subprocess.run(
                [sys.executable, __file__, "--contract-client"], env=env, capture_output=True,
                text=True, timeout=120,
            )  # fmt: skip
            assert done.returncode == 0, done.stdout + done.stderr
            assert node.wait(10) == 0  # shut down by rosnode kill, cleanly
        finally:
            if node.poll() is None:
                node.kill()
    result = json.loads(done.stdout.strip().splitlines()[-1])
    statuses, twists = result["statuses"], [(v, w) for _, v, w in result["twists"]]
    assert [s[4] for s in statuses] == ["approaching"] * 15 + ["stopped_by_red"] * 30
    assert all(s[0] and s[1] for s in statuses[:15])  # active: a command every frame
    speeds = [s[2] for s in statuses[:15]]
    if limit_linear is None:
        # Ramped up by the limiter from the first frame's zero (no interval to accelerate yet).
        assert speeds == sorted(speeds) and speeds[0] == 0.0 < speeds[1] < speeds[-1]
    else:  # held at ~limit_linear from the second frame on (well below the approach speed)
        assert speeds == [0.0] + [limit_linear] * 14
    idle = statuses[15:]
    assert not any(s[0] for s in idle)
    sent = [(s[2], s[3]) for s in idle if s[1]]
    # The limiter's ramp down while idle, ending on exactly one zero, then silence.
    assert sent[-1] == (0.0, 0.0) and (0.0, 0.0) not in sent[:-1]
    assert [s[1] for s in idle] == [True] * len(sent) + [False] * (30 - len(sent))
    # cmd_vel: what the statuses say was sent, then the shutdown's zero (no watchdog zero).
    sent_all = [(s[2], s[3]) for s in statuses if s[1]]
    assert twists == [*sent_all, (0.0, 0.0)]


@pytest.mark.parametrize(
    "node, param, message",
    [
        ("line_follower", "_kp:=-1", "kp must be >= 0, got -1"),
        ("line_follower", "_mode:=fast", "mode: unknown value 'fast'"),
        ("follow_green_stop_red", "_close_area:=-1.0", "close_area must be >= 0, got -1"),
        ("line_follower", "_expected_frame_rate:=-5.0",
         "~expected_frame_rate must be >= 0 (0: unknown), got -5.0"),
        ("colour_filter", "_colour:=purple", "~colour must be red, green or blue, got 'purple'"),
        ("follow_green_stop_red", "_limit_linear:=0",
         "~limit_linear: max_linear must be > 0, got 0"),
        ("line_follower", "_limit_angular_accel:=fast",
         "~limit_angular_accel must be a number, got 'fast'"),
        ("three_colours", "_sensitivity:=95",
         "invalid parameter: colours[0] (red): sensitivity must be in [0, 90], got 95"),
    ],
)  # fmt: skip
def test_lab_nodes_refuse_bad_params_naming_them(node, param, message):
    with private_master() as env:
        out = subprocess.run(
            ["rosrun", "follow_bot", f"{node}.py", param], env=env, capture_output=True,
            text=True, timeout=60,
        )  # fmt: skip
    assert out.returncode == 2 and message in out.stdout + out.stderr, out.stdout + out.stderr


if __name__ == "__main__" and sys.argv[1:2] == ["--client"]:
    print(json.dumps(client(sys.argv[2], sys.argv[3])))
if __name__ == "__main__" and sys.argv[1:2] == ["--contract-client"]:
    print(json.dumps(contract_client()))
