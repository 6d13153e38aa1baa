"""rectify:=true of every behaviour launch (a real lens): Debian's image_proc rectify
nodelet (rectify.launch) in the behaviour's own nodelet manager, and the behaviour's nodelet on
its image_rect with ~image_rectified. Checked as roslaunch resolves it (--nodes, --args), without
a roscore."""

import subprocess

import pytest

# Infrastructure checks of a minute or more each: `make test-full` plays them, so `make test`
# keeps within its 12 minutes with every bad-input, fault and scenario-family test.
pytestmark = pytest.mark.full

# launch file: (node name, nodelet class, the manager it makes with rectify)
BEHAVIOURS = {
    "follower.launch": ("follower", "follow_bot/FollowerNodelet", "follower_manager"),
    "parker.launch": ("parker", "follow_bot/ParkerNodelet", "parker_manager"),
    "beacon_chaser.launch": (
        "beacon_chaser", "follow_bot/BeaconChaserNodelet", "beacon_chaser_manager",
    ),
}  # fmt: skip


def roslaunch(*args: str) -> str:
    done = subprocess.run(["roslaunch", *args], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    return done.stdout


@pytest.mark.parametrize("launch_file", BEHAVIOURS)
def test_rectify_loads_image_proc_and_the_behaviour_into_one_manager(launch_file):
    name, nodelet, manager = BEHAVIOURS[launch_file]
    launch = ("follow_bot", launch_file, "rectify:=true")
    assert roslaunch("--nodes", *launch).split() == [
        f"/{manager}", "/rectify", f"/{name}", "/robot_state_publisher",
    ]  # fmt: skip
    rectify = roslaunch("--args", "/rectify", *launch).split()
    assert rectify[1:4] == ["load", "image_proc/rectify", manager]
    assert "image_mono:=camera/rgb/image_raw" in rectify
    assert "image_rect:=camera/rgb/image_rect" in rectify
    behaviour = roslaunch("--args", f"/{name}", *launch).split()
    assert behaviour[1:4] == ["load", nodelet, manager]
    assert "camera/rgb/image_raw:=camera/rgb/image_rect" in behaviour
    params = roslaunch("--dump-params", *launch)
    assert f"/{name}/image_rectified: true" in params


@pytest.mark.parametrize("launch_file", BEHAVIOURS)
def test_rectify_joins_a_given_manager(launch_file):
    name, nodelet, _ = BEHAVIOURS[launch_file]
    launch = ("follow_bot", launch_file, "rectify:=true", "manager:=robot_manager")
    assert roslaunch("--nodes", *launch).split() == [
        "/rectify", f"/{name}", "/robot_state_publisher",
    ]  # fmt: skip
    assert roslaunch("--args", "/rectify", *launch).split()[3] == "robot_manager"
    assert roslaunch("--args", f"/{name}", *launch).split()[1:4] == [
        "load", nodelet, "robot_manager",
    ]  # fmt: skip


@pytest.mark.parametrize("launch_file", BEHAVIOURS)
def test_without_rectify_the_behaviour_runs_alone_on_image_raw(launch_file):
    name, _, _ = BEHAVIOURS[launch_file]
    launch = ("follow_bot", launch_file)
    assert roslaunch("--nodes", *launch).split() == [f"/{name}", "/robot_state_publisher"]
    command = roslaunch("--args", f"/{name}", *launch).split()
    assert command[0].endswith(f"lib/follow_bot/{name}")
    assert "camera/rgb/image_raw:=camera/rgb/image_raw" in command
    assert "image_rectified" not in roslaunch("--dump-params", *launch)


def test_image_proc_provides_the_rectify_nodelet():
    # Debian ships image_proc's nodelet description in libimage-proc-dev.
    plugins = subprocess.run(
        ["rospack", "plugins", "--attrib=plugin", "nodelet"],
        capture_output=True, text=True, timeout=60,
    ).stdout  # fmt: skip
    found = [line.split()[1] for line in plugins.splitlines() if line.startswith("image_proc ")]
    assert found, "no nodelet description of image_proc (Debian: libimage-proc-dev)"
    description = found[0]
    with open(description) as xml:
        assert 'name="image_proc/rectify"' in xml.read()
