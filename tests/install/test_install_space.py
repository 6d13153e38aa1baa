"""colcon install space: with only `install/setup.bash` sourced (no devel space, no source tree on
ROS_PACKAGE_PATH, no $FOLLOW_BOT_VENV), the installed simulator finds the project venv (cv2, set by
harness's env hook) and the worlds (the installed `worlds` package, through rospkg), and the
installed launch files find the sign image through `$(find follow_bot)`.

test_installed_sim_drives (make test, ~40 s): colcon installs `worlds`, `follow_bot_msgs` (the
status the sim waits for) and `harness` into a tmp prefix; the installed sim plays 1 s of lockstep
sim time on the course against the installed constant_twist.
test_installed_launch_files (marked full, make test-full only: colcon builds every package, several
minutes): `from follow_bot import core; from image_converter import core` with Debian's python and
the venv's; course.launch (lockstep) drives and ends on a zero Twist; park.launch starts with the
tag and with the sign.
"""

import os
import shutil
import signal
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest

from harness.processes import private_master, stop
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
    assert "FOLLOW_BOT_VENV" in env  # harness's env hook
    return dict(env, ROS_IP="127.0.0.1", ROS_HOME=str(tmp / "ros_home"))


@pytest.mark.skipif(shutil.which("colcon") is None, reason="colcon is in tools/debian-packages.txt")
def test_installed_sim_drives(tmp_path):
    install = colcon_install(tmp_path, ["worlds", "follow_bot_msgs", "harness"])
    installed = installed_env(install, tmp_path)
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
