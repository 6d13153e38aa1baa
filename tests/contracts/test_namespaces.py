"""Topic names: every node's default topics are relative to its namespace,
the same for the node executable and the nodelet; remapping the names `rosnode info` shows is
honoured; the simulator and a behaviour in one `<group ns>` drive together.

The master's system state (what `rosnode info` reads) is the evidence: the exact resolved names
each node publishes and subscribes.
"""

from __future__ import annotations

import subprocess
import textwrap
import time

import pytest
import rosgraph

from harness.processes import private_master, stop

# Topic naming over every node (about 35 s), not a bad-input or fault test: `make test-full`
# plays it, so `make test` keeps within its 12 minutes.
pytestmark = pytest.mark.full

# Global by convention: diagnostic_updater's aggregate topic, rosout, the sim clock and tf2's
# (one tree per robot only where they are remapped, as test_two_robots does).
GLOBAL_TOPICS = {"/diagnostics", "/rosout", "/clock", "/tf", "/tf_static"}
CAMERA_IN = {"/robot1/camera/rgb/image_raw", "/robot1/camera/rgb/camera_info"}

# (package, node executable, nodelet class, extra args, topics it must publish, subscribe).
BEHAVIOURS = [
    ("follow_bot", "follower", "follow_bot/FollowerNodelet", [],
     {"/robot1/cmd_vel", "/robot1/follower/status", "/robot1/follower/line"},
     CAMERA_IN | {"/robot1/odom"}),
    ("follow_bot", "follower", "follow_bot/FollowerNodelet", ["_use_odom:=false", "_mode:=path"],
     {"/robot1/cmd_vel"}, CAMERA_IN),
    ("follow_bot", "beacon_chaser", "follow_bot/BeaconChaserNodelet", [],
     {"/robot1/cmd_vel", "/robot1/beacon_chaser/status", "/robot1/beacon_chaser/detections"},
     CAMERA_IN),
    ("follow_bot", "parker", "follow_bot/ParkerNodelet", [],
     {"/robot1/cmd_vel", "/robot1/parker/status", "/robot1/parker/state"}, CAMERA_IN),
    ("follow_bot", "panorama", "follow_bot/PanoramaNodelet", [],
     {"/robot1/cmd_vel", "/robot1/panorama/status", "/robot1/panorama/panorama"},
     CAMERA_IN | {"/robot1/odom"}),
]  # fmt: skip


@pytest.fixture(scope="module")
def master_env():
    with private_master() as env:
        yield env


def topics_of(env: dict, node: str, timeout: float = 20.0, until=None) -> tuple[set, set]:
    """(published, subscribed) topic names of `node` as the master knows them, once `until`
    holds (default: the node publishes anything) or after `timeout` s."""
    master = rosgraph.Master("/test_namespaces", master_uri=env["ROS_MASTER_URI"])
    deadline = time.monotonic() + timeout
    while True:
        publishers, subscribers, _ = master.getSystemState()
        pubs = {topic for topic, nodes in publishers if node in nodes}
        subs = {topic for topic, nodes in subscribers if node in nodes}
        done = until(pubs, subs) if until else bool(pubs)
        if done or time.monotonic() > deadline:
            return pubs, subs
        time.sleep(0.1)


def without_ns(names: set, ns: str) -> set:
    return {name.removeprefix(ns) for name in names}


def started(command: list[str], env: dict, ns: str = "") -> subprocess.Popen:
    child_env = dict(env, ROS_NAMESPACE=ns) if ns else env
    return subprocess.Popen(
        command, env=child_env, stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT
    )


@pytest.mark.parametrize(
    ("package", "executable", "nodelet", "args", "publishes", "subscribes"),
    BEHAVIOURS,
    ids=[f"{b[1]}{'_without_odom' if b[3] else ''}" for b in BEHAVIOURS],
)
def test_node_and_nodelet_use_the_same_relative_names(
    master_env, package, executable, nodelet, args, publishes, subscribes
):
    """Under ROS_NAMESPACE=robot1 the node resolves every topic in /robot1; the nodelet
    (standalone, same name, in /robot2) resolves the same names in /robot2."""
    node = started(["rosrun", package, executable, *args], master_env, ns="robot1")
    standalone = started(
        ["rosrun", "nodelet", "nodelet", "standalone", nodelet, f"__name:={executable}", *args],
        master_env, ns="robot2",
    )  # fmt: skip
    try:
        wanted = publishes | subscribes

        def complete(ns):
            return lambda p, s: without_ns(wanted, "/robot1") <= without_ns(p | s, ns)

        pubs1, subs1 = topics_of(master_env, f"/robot1/{executable}", until=complete("/robot1"))
        pubs2, subs2 = topics_of(master_env, f"/robot2/{executable}", until=complete("/robot2"))
    finally:
        stop(node)
        stop(standalone)
    assert publishes <= pubs1, pubs1
    assert subscribes <= subs1, subs1
    outside = {t for t in pubs1 | subs1 if not t.startswith("/robot1/")} - GLOBAL_TOPICS
    assert not outside, f"topics outside the namespace: {outside}"
    assert without_ns(pubs1, "/robot1") == without_ns(pubs2, "/robot2")
    assert without_ns(subs1, "/robot1") == without_ns(subs2, "/robot2")


def test_image_converter_input_is_relative(master_env):
    """The converter subscribes its input lazily, once its ~output has a subscriber."""
    node = started(["rosrun", "image_converter", "image_converter"], master_env, ns="robot1")
    reader = started(["rostopic", "echo", "/robot1/image_converter/output"], master_env)
    try:
        _, subs = topics_of(
            master_env, "/robot1/image_converter",
            until=lambda p, s: "/robot1/camera/rgb/image_raw" in s,
        )  # fmt: skip
    finally:
        stop(reader)
        stop(node)
    assert "/robot1/camera/rgb/image_raw" in subs, subs


def test_remapping_the_shown_names_is_honoured(master_env):
    """The names `rosnode info` shows are the ones to remap, for the node and the nodelet."""
    remaps = [
        "camera/rgb/image_raw:=/usb_cam/image_raw",
        "camera/rgb/camera_info:=/usb_cam/camera_info",
        "cmd_vel:=/mobile_base/commands/velocity",
    ]
    node = started(["rosrun", "follow_bot", "follower", *remaps], master_env)
    standalone = started(
        ["rosrun", "nodelet", "nodelet", "standalone", "follow_bot/FollowerNodelet",
         "__name:=follower_nodelet", *remaps],
        master_env,
    )  # fmt: skip
    expected_subs = {"/usb_cam/image_raw", "/usb_cam/camera_info"}

    def remapped(pubs, subs):
        return expected_subs <= subs and "/mobile_base/commands/velocity" in pubs

    try:
        found = [topics_of(master_env, name, until=remapped)
                 for name in ("/follower", "/follower_nodelet")]  # fmt: skip
    finally:
        stop(node)
        stop(standalone)
    for pubs, subs in found:
        assert expected_subs <= subs, subs
        assert "/mobile_base/commands/velocity" in pubs, pubs
        assert not {"/camera/rgb/image_raw", "/cmd_vel"} & (pubs | subs)


@pytest.mark.parametrize(
    ("package", "executable"),
    [("follow_bot", "follower"), ("image_converter", "image_converter")],
)
def test_a_remap_moves_the_compressed_topic_too(master_env, package, executable):
    """With _image_transport:=compressed the remapped base name carries the /compressed topic
    (image_transport alone would append to the unremapped name)."""
    node = started(
        ["rosrun", package, executable, "_image_transport:=compressed",
         "camera/rgb/image_raw:=/usb_cam/image_raw", f"__name:={executable}_compressed"],
        master_env, ns="robot3",
    )  # fmt: skip
    name = f"/robot3/{executable}_compressed"
    reader = started(["rostopic", "echo", f"{name}/output"], master_env)  # the converter is lazy
    try:
        _, subs = topics_of(
            master_env, name, until=lambda p, s: "/usb_cam/image_raw/compressed" in s
        )
    finally:
        stop(reader)
        stop(node)
    assert "/usb_cam/image_raw/compressed" in subs, subs


def test_sim_and_follower_drive_in_one_group_ns(tmp_path):
    """`<group ns="robot1">` around course.launch: the simulator's camera and cmd_vel meet the
    follower's under /robot1, and the robot drives (lockstep: every frame answered)."""
    launch = tmp_path / "robot1.launch"
    launch.write_text(
        textwrap.dedent("""\
        <launch>
          <group ns="robot1">
            <include file="$(find harness)/launch/course.launch">
              <arg name="lockstep" value="true"/>
              <arg name="duration" value="4"/>
            </include>
          </group>
        </launch>
        """)
    )
    with private_master() as env:
        echo = subprocess.Popen(
            ["rostopic", "echo", "-p", "/robot1/cmd_vel"],
            env=env, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
        )  # fmt: skip
        run = subprocess.Popen(
            ["roslaunch", str(launch)],
            env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
        )  # fmt: skip
        try:
            sim_pubs, sim_subs = topics_of(
                env, "/robot1/sim", timeout=60.0,
                until=lambda p, s: {"/robot1/cmd_vel", "/robot1/follower/status"} <= s,
            )  # fmt: skip
            output, _ = run.communicate(timeout=120)  # the sim ends the launch after 4 s
        finally:
            stop(run)
            stop(echo)
    speeds = [float(line.split(",")[1]) for line in echo.stdout.read().splitlines()
              if line and line[0] != "%"]  # fmt: skip
    assert {"/robot1/camera/rgb/image_raw", "/robot1/camera/rgb/camera_info",
            "/robot1/sim/pose"} <= sim_pubs, sim_pubs  # fmt: skip
    assert {"/robot1/cmd_vel", "/robot1/follower/status"} <= sim_subs, sim_subs
    assert max(speeds, default=0.0) > 0.1, output
