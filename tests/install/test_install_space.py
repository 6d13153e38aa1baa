"""colcon install space: with only `install/setup.bash` sourced (no devel space, no source tree on
ROS_PACKAGE_PATH, no $FOLLOW_BOT_VENV), the installed simulator finds the project venv (cv2, set by
harness's env hook) and the worlds (the installed `worlds` package, through rospkg), and the
installed launch files find the sign image through `$(find follow_bot)`.

test_installed_sim_drives (make test, ~40 s): colcon installs `worlds`, `follow_bot_msgs` (the
status the sim waits for) and `harness` into a tmp prefix; the installed sim plays 1 s of lockstep
sim time on the course against the installed constant_twist.
test_installed_launch_files (marked full, make test-full only: colcon builds every package, several
minutes): `from follow_bot import core; from image_converter import core` with Debian's python and
the venv's; each node's --help names its installed manual (share/<package>/doc/<node>.md);
course.launch (lockstep) drives and ends on a zero Twist; park.launch starts with the tag and with
the sign.
test_product_runs_without_harness (marked full): the product packages alone, without harness or
worlds (they depend on it, never the reverse), import on Debian's python3 and drive: the
follower's launch with its robot description, fed line frames by this file run with --client.
"""

import ast
import json
import math
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from harness.processes import WatchedProcess, private_master, stop
from harness.testing import REPO

RATE_HZ = 30.0


def colcon_install(tmp: Path, packages: list[str]) -> Path:
    """Builds `packages` with colcon in a clean environment; returns the install prefix."""
    env = {"PATH": "/usr/bin:/bin", "HOME": str(tmp), "LANG": "C.UTF-8"}
    for name in ("CCACHE_DIR", "CCACHE_BASEDIR", "CCACHE_MAXSIZE", "CMAKE_CXX_COMPILER_LAUNCHER",
                 "CMAKE_C_COMPILER_LAUNCHER"):  # fmt: skip
        if name in os.environ:
            env[name] = os.environ[name]
    build = subprocess.run(
        ["colcon", "build", "--base-paths", *(str(REPO / p) for p in packages),
         "--build-base", str(tmp / "build"), "--install-base", str(tmp / "install"),
         "--catkin-skip-building-tests",
         "--cmake-args", "-DCMAKE_BUILD_TYPE=Release", "-DPYTHON_EXECUTABLE=/usr/bin/python3"],
        cwd=tmp, env=env, capture_output=True, text=True, timeout=1800,
    )  # fmt: skip
    assert build.returncode == 0, build.stdout[-3000:] + build.stderr[-3000:]
    return tmp / "install"


def installed_env(install: Path, tmp: Path) -> dict:
    """The environment `source install/setup.bash` gives a shell with nothing else sourced."""
    clean = {"PATH": "/usr/bin:/bin", "HOME": str(tmp), "LANG": "C.UTF-8"}
    dump = subprocess.run(
        ["bash", "-c", f"source {install}/setup.bash && env -0"],
        env=clean, capture_output=True, check=True,
    )  # fmt: skip
    env = dict(item.split("=", 1) for item in dump.stdout.decode().split("\0") if "=" in item)
    return dict(env, ROS_IP="127.0.0.1", ROS_HOME=str(tmp / "ros_home"))


@pytest.mark.skipif(shutil.which("colcon") is None, reason="colcon is in tools/debian-packages.txt")
def test_installed_sim_drives(tmp_path):
    install = colcon_install(tmp_path, ["worlds", "follow_bot_msgs", "harness"])
    installed = installed_env(install, tmp_path)
    assert "FOLLOW_BOT_VENV" in installed  # harness's env hook
    worlds = subprocess.run(
        ["rospack", "find", "worlds"], env=installed, capture_output=True, text=True
    )
    assert worlds.stdout.strip() == str(install / "worlds" / "share" / "worlds")
    record = tmp_path / "record.npz"
    with private_master(sim_time=True, env=installed, roscore=True) as env:
        behaviour = subprocess.Popen(
            ["rosrun", "harness", "constant_twist", "_v:=0.2"],
            env=env, stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT,
        )  # fmt: skip
        try:
            sim = subprocess.run(
                ["rosrun", "harness", "sim", "_world:=course", "_lockstep:=true",
                 "_duration:=1.0", f"_rate_hz:={RATE_HZ}", f"_record:={record}"],
                env=env, capture_output=True, text=True, timeout=120,
            )  # fmt: skip
        finally:
            stop(behaviour)
    assert sim.returncode == 0, sim.stdout[-2000:] + sim.stderr[-2000:]
    run = np.load(record)
    assert len(run["t"]) == RATE_HZ  # 1 s of frames
    assert int(run["missed"].sum()) == 0  # every frame answered by the installed behaviour
    assert run["v"][-1] == pytest.approx(0.2)


def drive_then_ctrl_c(env: dict, launch_args: list[str], drove) -> tuple[str, list[str]]:
    """Launches, waits until a /cmd_vel message satisfies `drove`, Ctrl-C; (output, Twists)."""
    echo = subprocess.Popen(  # `timeout`: the readline below ends even if nothing is sent
        ["timeout", "180", "rostopic", "echo", "-p", "/cmd_vel"],
        env=env, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
    )  # fmt: skip
    launch = subprocess.Popen(
        ["roslaunch", *launch_args], env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
        text=True,
    )  # fmt: skip
    try:
        deadline = time.monotonic() + 120.0
        while True:
            line = echo.stdout.readline()
            assert line and time.monotonic() < deadline, f"{launch_args}: no command"
            fields = line.strip().split(",")
            if fields[0] != "%time" and drove([float(v) for v in fields[1:]]):
                break
        launch.send_signal(signal.SIGINT)
        launch.wait(60)
        time.sleep(1.0)
    finally:
        stop(launch)
        stop(echo)
    twists = [line for line in echo.stdout.read().splitlines() if line and line[0] != "%"]
    return launch.stdout.read(), twists


@pytest.mark.full
@pytest.mark.skipif(shutil.which("colcon") is None, reason="colcon is in tools/debian-packages.txt")
def test_installed_launch_files(tmp_path):
    packages = [
        "worlds",
        "follow_bot_msgs",
        "follow_bot_common",
        "compressed_transport",
        "harness",
        "image_converter",
        "follow_bot",
    ]
    install = colcon_install(tmp_path, packages)
    installed = installed_env(install, tmp_path)
    assert "FOLLOW_BOT_VENV" in installed  # harness's env hook
    for python in ("/usr/bin/python3", str(REPO / ".venv" / "bin" / "python3")):
        # The bindings from the install space alone, with Debian's and with the venv's numpy.
        imported = subprocess.run(
            [python, "-c", "from follow_bot import core; from image_converter import core as ic; "
             "print(core.__file__); print(ic.__file__)"],
            env=installed, capture_output=True, text=True, check=True,
        )  # fmt: skip
        assert imported.stdout.splitlines() == [
            str(next((install / package).glob(f"lib/python3/dist-packages/{package}/core.*.so")))
            for package in ("follow_bot", "image_converter")
        ]  # fmt: skip
    for package, node in [("follow_bot", "follower"), ("follow_bot", "beacon_chaser"),
                          ("follow_bot", "parker"), ("follow_bot", "panorama"),
                          ("image_converter", "image_converter")]:  # fmt: skip
        # --help names the node's manual, installed with it (no master needed).
        shown = subprocess.run(["rosrun", package, node, "--help"], env=installed,
                               capture_output=True, text=True, check=True, timeout=30)  # fmt: skip
        manual = install / package / "share" / package / "doc" / f"{node}.md"
        assert f"  {manual}\n" in shown.stdout and manual.is_file(), shown.stdout
    with private_master(env=installed, roscore=True) as env:
        out, twists = drive_then_ctrl_c(
            env, ["harness", "course.launch", "lockstep:=true"], lambda t: t[0] > 0.2
        )
        assert "has died" not in out, out[-3000:]
        assert [float(v) for v in twists[-1].split(",")[1:]] == [0.0] * 6, twists[-1]
        for target in ("apriltag", "sign"):  # any command: the parker runs on its marker
            out, _ = drive_then_ctrl_c(
                env, ["harness", "park.launch", f"target:={target}"], lambda t: True
            )
            assert "has died" not in out and "cannot start" not in out, out[-3000:]


PRODUCT = ["follow_bot_msgs", "follow_bot_common", "image_converter", "follow_bot"]
ROBOT = "generic"


def follow_client(camera_frame: str) -> dict:
    """The camera side of the product test (this file with --client, in the test's own
    environment): camera_info, odom and line frames at 30 Hz until a cmd_vel drives forward;
    then the robot description's tf base_footprint <- the camera's optical frame."""
    import rospy
    import tf2_ros
    from geometry_msgs.msg import Twist
    from nav_msgs.msg import Odometry
    from sensor_msgs.msg import CameraInfo, Image

    from follow_bot_msgs.msg import BehaviourStatus
    from harness.testing import odom_msg, pinhole_info, probe_frame

    rospy.init_node("product_client", anonymous=True, disable_signals=True)
    twists: list[list[float]] = []
    states: list[str] = []
    rospy.Subscriber("/cmd_vel", Twist, lambda m: twists.append([m.linear.x, m.angular.z]))
    rospy.Subscriber("/follower/status", BehaviourStatus, lambda m: states.append(m.state))
    tf_buffer = tf2_ros.Buffer()
    tf2_ros.TransformListener(tf_buffer)
    rospy.Publisher("/camera/rgb/camera_info", CameraInfo, queue_size=1, latch=True).publish(
        pinhole_info()
    )
    rospy.Publisher("/odom", Odometry, queue_size=1, latch=True).publish(odom_msg(0.0))
    images = rospy.Publisher("/camera/rgb/image_raw", Image, queue_size=10)
    deadline = time.monotonic() + 60.0
    while images.get_num_connections() == 0 and time.monotonic() < deadline:
        time.sleep(0.05)
    frames = 0
    while not any(linear > 0.0 for linear, _ in twists) and time.monotonic() < deadline:
        images.publish(probe_frame("line"))  # a yellow stripe down the middle, on grey
        frames += 1
        time.sleep(1.0 / RATE_HZ)
    t = tf_buffer.lookup_transform(
        "base_footprint", camera_frame, rospy.Time(0), rospy.Duration(10)
    )
    xyz, q = t.transform.translation, t.transform.rotation
    return {
        "frames": frames, "twists": twists, "states": states,
        "translation": [xyz.x, xyz.y, xyz.z], "rotation": [q.x, q.y, q.z, q.w],
    }  # fmt: skip


@pytest.mark.full
@pytest.mark.skipif(shutil.which("colcon") is None, reason="colcon is in tools/debian-packages.txt")
def test_product_runs_without_harness(tmp_path):
    """The product packages alone (no harness, no worlds) install, import and drive: the
    follower's launch with its robot description answers line frames with a forward Twist and
    takes the preset's camera mounting from robot_state_publisher's tf (marked full: colcon
    builds every product package, ~8 min on 2 shared cores; the rest takes ~10 s)."""
    install = colcon_install(tmp_path, PRODUCT)
    installed = installed_env(install, tmp_path)
    assert sorted(p.name for p in install.iterdir() if p.is_dir()) == sorted(PRODUCT)
    assert "FOLLOW_BOT_VENV" not in installed  # no harness env hook
    for variable in ("ROS_PACKAGE_PATH", "PYTHONPATH", "CMAKE_PREFIX_PATH", "PATH"):
        assert str(REPO) not in installed.get(variable, ""), (variable, installed.get(variable))

    def run(*args: str) -> subprocess.CompletedProcess:  # not in the source tree: python's
        # sys.path[0] would make its harness/ folder a namespace package
        return subprocess.run(
            args, env=installed, cwd=tmp_path, capture_output=True, text=True, timeout=60
        )

    for package in ("harness", "worlds"):
        assert run("rospack", "find", package).returncode != 0, package
    for package in PRODUCT:
        manifest = (install / package / "share" / package / "package.xml").read_text()
        assert not re.search(r"depend>\s*(harness|worlds)\s*<", manifest), package
    assert "No module named 'harness'" in run("/usr/bin/python3", "-c", "import harness").stderr
    assert run("rospack", "find", "follow_bot").stdout.strip() == str(
        install / "follow_bot" / "share" / "follow_bot"
    )
    imported = run("/usr/bin/python3", "-c", "from follow_bot import core; print(core.__file__)")
    assert imported.stdout.strip() == str(
        next((install / "follow_bot").glob("lib/python3/dist-packages/follow_bot/core.*.so"))
    ), imported.stderr

    presets = install / "follow_bot" / "share" / "follow_bot" / "config" / "robots.yaml"
    preset = ast.literal_eval(presets.read_text())[ROBOT]
    with private_master(env=installed, roscore=True) as env:
        launch = WatchedProcess(
            ["roslaunch", "follow_bot", "follower.launch", f"robot:={ROBOT}"], env
        )
        try:
            client = subprocess.run(
                [sys.executable, __file__, "--client", preset["camera_frame"]],
                env=dict(os.environ, ROS_MASTER_URI=env["ROS_MASTER_URI"], ROS_IP="127.0.0.1"),
                capture_output=True, text=True, timeout=180,
            )  # fmt: skip
            assert launch.process.poll() is None, launch.output()[-3000:]
        finally:
            stop(launch.process)
    out = launch.output()
    assert client.returncode == 0, client.stdout[-2000:] + client.stderr[-3000:] + out[-3000:]
    seen = json.loads(client.stdout.strip().splitlines()[-1])
    print({k: seen[k] for k in ("frames", "translation", "rotation")}, seen["twists"][-3:])

    # Driving: every Twist finite, the last one forward along the centred line.
    assert seen["twists"] and all(math.isfinite(v) for twist in seen["twists"] for v in twist)
    linear, angular = seen["twists"][-1]
    assert linear > 0.0 and abs(angular) < 0.05, seen["twists"]
    assert seen["states"][-1] == "following", seen["states"][-5:]
    # The mounting: robot_state_publisher's tf is the preset's, and the follower took it from tf.
    pitch = math.radians(preset["camera_pitch_deg"])
    assert seen["translation"] == pytest.approx(
        [preset["camera_x_offset"], 0.0, preset["camera_height"]], abs=1e-6
    )
    x, y, z, w = seen["rotation"]
    rotation = np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])  # fmt: skip
    # Optical axes (REP 103): z forward pitched down, x to the robot's right, y down.
    forward = [math.cos(pitch), 0.0, -math.sin(pitch)]
    down = [-math.sin(pitch), 0.0, -math.cos(pitch)]
    np.testing.assert_allclose(rotation.T, [[0.0, -1.0, 0.0], down, forward], atol=1e-6)
    mounted = re.findall(
        r"/follower: camera mounting from tf \(base_link <- (\S+)\): height (\S+) m, "
        r"pitch (\S+) deg down, x offset (\S+) m", out
    )  # fmt: skip
    assert len(mounted) == 1, out[-3000:]
    frame, *numbers = mounted[0]
    assert frame == preset["camera_frame"]
    assert [float(v) for v in numbers] == pytest.approx(
        [preset["camera_height"], preset["camera_pitch_deg"], preset["camera_x_offset"]], abs=1e-3
    )
    assert "has died" not in out, out[-3000:]


if __name__ == "__main__" and sys.argv[1:2] == ["--client"]:
    print(json.dumps(follow_client(sys.argv[2])))
