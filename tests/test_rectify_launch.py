"""follower.launch rectify:=true (issue 14, a real lens): Debian's image_proc rectify nodelet in
the follower's own nodelet manager, and the follower on its image_rect with ~image_rectified.
Checked as roslaunch resolves it (--nodes, --args), without a roscore."""

import subprocess


def roslaunch(*args: str) -> str:
    done = subprocess.run(["roslaunch", *args], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_rectify_loads_image_proc_and_the_follower_into_one_manager():
    launch = ("follow_bot", "follower.launch", "rectify:=true")
    assert roslaunch("--nodes", *launch).split() == [
        "/follower_manager", "/rectify", "/follower", "/robot_state_publisher",
    ]  # fmt: skip
    rectify = roslaunch("--args", "/rectify", *launch).split()
    assert rectify[1:4] == ["load", "image_proc/rectify", "follower_manager"]
    assert "image_mono:=camera/rgb/image_raw" in rectify
    assert "image_rect:=camera/rgb/image_rect" in rectify
    follower = roslaunch("--args", "/follower", *launch).split()
    assert follower[1:4] == ["load", "follow_bot/FollowerNodelet", "follower_manager"]
    assert "camera/rgb/image_raw:=camera/rgb/image_rect" in follower
    params = roslaunch("--dump-params", *launch)
    assert "/follower/image_rectified: true" in params


def test_rectify_joins_a_given_manager():
    launch = ("follow_bot", "follower.launch", "rectify:=true", "manager:=robot_manager")
    assert roslaunch("--nodes", *launch).split() == [
        "/rectify", "/follower", "/robot_state_publisher",
    ]  # fmt: skip
    assert roslaunch("--args", "/rectify", *launch).split()[3] == "robot_manager"


def test_without_rectify_the_follower_runs_alone_on_image_raw():
    launch = ("follow_bot", "follower.launch")
    assert roslaunch("--nodes", *launch).split() == ["/follower", "/robot_state_publisher"]
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
