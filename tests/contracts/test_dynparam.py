"""dynamic_reconfigure tells the truth: a rejected update leaves, and reports, the settings in
force, and the next valid update is accepted; a value out of its .cfg range is clamped with a
warning naming the value asked and the value applied. One round trip per node with a .cfg."""

import subprocess
import time

import pytest
import yaml

from harness.processes import private_master, stop


@pytest.fixture(scope="module")
def master_env():
    with private_master() as env:
        yield env


def dynparam(env, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        ["rosrun", "dynamic_reconfigure", "dynparam", *args],
        env=env,
        capture_output=True,
        text=True,
        timeout=30,
        check=True,
    )


def settings(env, node: str) -> dict:
    """`dynparam get`: the settings the node reports, without the copy nested under "groups"."""
    reported = yaml.safe_load(dynparam(env, "get", node).stdout)
    reported.pop("groups")
    return reported


def start(env, node: str, ros_name: str) -> subprocess.Popen:
    """`rosrun follow_bot NODE` as `ros_name`, once its dynamic_reconfigure server is up."""
    behaviour = subprocess.Popen(
        ["rosrun", "follow_bot", node, f"__name:={ros_name[1:]}"],
        env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
    )  # fmt: skip
    deadline = time.monotonic() + 30.0
    while True:
        listed = subprocess.run(["rosservice", "list"], env=env, capture_output=True, text=True)
        if f"{ros_name}/set_parameters" in listed.stdout:
            return behaviour
        if time.monotonic() > deadline or behaviour.poll() is not None:
            stop(behaviour)
            raise AssertionError("node did not start: " + behaviour.stdout.read())
        time.sleep(0.2)


@pytest.mark.parametrize(
    ("node", "name", "bad", "valid"),
    [
        # An unknown steering law.
        ("follower", "mode", {"mode": "banana"}, {"mode": "pd"}),
        # Each within the .cfg's ranges, but the core rejects the combination.
        ("follower", "h_min", {"h_min": 45}, {"h_min": 25}),  # above ~h_max (40)
        ("beacon_chaser", "stop_colour", {"stop_colour": "green"}, {"stop_colour": "blue"}),
    ],
)
def test_rejected_update_reports_the_settings_in_force(master_env, node, name, bad, valid):
    ros_name = f"/{node}_{name}"
    behaviour = start(master_env, node, ros_name)
    try:
        before = settings(master_env, ros_name)

        dynparam(master_env, "set", ros_name, yaml.safe_dump(bad))
        assert settings(master_env, ros_name) == before

        dynparam(master_env, "set", ros_name, yaml.safe_dump(valid))
        assert settings(master_env, ros_name) == {**before, **valid}
    finally:
        stop(behaviour)
    log = behaviour.stdout.read()
    assert log.count("rejected reconfiguration, keeping the previous settings") == 1, log


@pytest.mark.parametrize(
    ("node", "name", "asked", "applied", "warning"),
    [
        # The tester's: the same kp at start-up is refused (test_node_params.py).
        ("follower", "kp", 50, 20, "clamped ~kp: asked 50, applied 20 (must be in [0, 20])"),
        ("beacon_chaser", "sensitivity", -3, 0, "~sensitivity: asked -3, applied 0 (must be in"),
    ],
)
def test_a_clamped_update_is_warned(master_env, node, name, asked, applied, warning):
    ros_name = f"/{node}_clamped_{name}"
    behaviour = start(master_env, node, ros_name)
    try:
        dynparam(master_env, "set", ros_name, yaml.safe_dump({name: asked}))
        assert settings(master_env, ros_name)[name] == applied
    finally:
        stop(behaviour)
    log = behaviour.stdout.read()
    assert log.count(warning) == 1, log
