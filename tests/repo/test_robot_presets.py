"""Robot presets (follow_bot/config/robots.yaml): the file the launch files read is both YAML and
a Python literal; each preset's limits are the manufacturers' published figures and its mounting
the robot's published URDF composed down to the RGB optical centre (numbers copied here from
those sources, not from the presets); every behaviour launch file turns robot:=NAME into the
preset's topics, transport, expected rate and ~limit_* params, with the URDF made on Debian's
python3 without the harness venv; roslaunch --ros-args reports no optional arg as Required; and
the "On a real robot" commands of the manual (follow_bot/doc/robot.md) run.
"""

from __future__ import annotations

import ast
import math
import os
import re
import shlex
import subprocess
from pathlib import Path
from xml.etree import ElementTree

import pytest
import yaml

from harness.testing import REPO

LAUNCH = REPO / "follow_bot" / "launch"
PRESETS_FILE = REPO / "follow_bot" / "config" / "robots.yaml"
ROBOTS = ["generic", "turtlebot3_burger", "turtlebot3_waffle_pi", "turtlebot2_kinect",
          "turtlebot2_astra"]  # fmt: skip
# The launch files that start a behaviour on a robot (the simulator's launches include them).
ROBOT_LAUNCHES = ["follower.launch", "beacon_chaser.launch", "parker.launch",
                  "panorama_node.launch"]  # fmt: skip
NODE_OF = {"follower.launch": "follower", "beacon_chaser.launch": "beacon_chaser",
           "parker.launch": "parker", "panorama_node.launch": "panorama"}  # fmt: skip

# Published top speeds: ROBOTIS e-manual, TurtleBot3 specifications (Burger 0.22 m/s and
# 2.84 rad/s, Waffle Pi 0.26 m/s and 1.82 rad/s); Kobuki specification (0.7 m/s, 180 deg/s).
PUBLISHED_LIMITS = {
    "turtlebot3_burger": (0.22, 2.84),
    "turtlebot3_waffle_pi": (0.26, 1.82),
    "turtlebot2_kinect": (0.7, math.pi),
    "turtlebot2_astra": (0.7, math.pi),
}


def composed(base_z, joint_xyz, joint_pitch, rgb_xyz):
    """Optical centre (x ahead, height) of base_footprint -> base_link (base_z) -> camera link
    (joint_xyz, pitched joint_pitch rad) -> rgb frame (rgb_xyz in the camera link)."""
    x, _, z = rgb_xyz
    c, s = math.cos(joint_pitch), math.sin(joint_pitch)
    return joint_xyz[0] + c * x + s * z, base_z + joint_xyz[2] - s * x + c * z


# The URDFs' joints (turtlebot3_description, turtlebot_description): (x ahead, height) of the
# RGB optical centre and its pitch, deg.
PUBLISHED_MOUNTINGS = {
    "turtlebot3_burger": (
        *composed(0.010, (0.040, -0.011, 0.130), 0.174, (0.003, 0.011, 0.009)),
        math.degrees(0.174),
    ),
    "turtlebot3_waffle_pi": (
        *composed(0.010, (0.073, -0.011, 0.084), 0.0, (0.003, 0.011, 0.008)),
        0.0,
    ),
    "turtlebot2_kinect": (-0.087, 0.0102 + 0.287, 0.0),
    "turtlebot2_astra": (-0.087, 0.0102 + 0.287, 0.0),
}


def presets() -> dict:
    return yaml.safe_load(PRESETS_FILE.read_text())


def debian_env() -> dict:
    """The environment a robot has: Debian's python3 and ROS, this workspace's devel space, no
    harness venv (no numpy or cv2 of its own)."""
    keep = ("ROS_PACKAGE_PATH", "ROS_ROOT", "ROS_ETC_DIR", "ROS_DISTRO", "ROS_PYTHON_VERSION",
            "CMAKE_PREFIX_PATH", "LD_LIBRARY_PATH", "HOME")  # fmt: skip
    env = {k: os.environ[k] for k in keep if k in os.environ}
    env["PATH"] = "/usr/bin:/bin"
    env["PYTHONPATH"] = ":".join(
        p for p in os.environ.get("PYTHONPATH", "").split(":") if p and ".venv" not in p
    )
    return env


def test_the_presets_file_is_yaml_and_a_python_literal_with_every_robot():
    text = PRESETS_FILE.read_text()
    assert yaml.safe_load(text) == ast.literal_eval(text)
    assert sorted(presets()) == sorted(ROBOTS)


@pytest.mark.parametrize("robot", sorted(PUBLISHED_LIMITS))
def test_limits_and_mountings_are_the_published_figures(robot):
    p = presets()[robot]
    v, w = PUBLISHED_LIMITS[robot]
    assert p["limits"]["limit_linear"] == pytest.approx(v)
    assert p["limits"]["limit_angular"] == pytest.approx(w, abs=0.002)
    x, height, pitch_deg = PUBLISHED_MOUNTINGS[robot]
    assert p["camera_x_offset"] == pytest.approx(x, abs=0.001)
    assert p["camera_height"] == pytest.approx(height, abs=0.001)
    assert p["camera_pitch_deg"] == pytest.approx(pitch_deg, abs=0.05)


def test_generic_is_todays_behaviour():
    p = presets()["generic"]
    assert (p["image"], p["camera_info"], p["image_transport"]) == (
        "camera/rgb/image_raw", "camera/rgb/camera_info", "raw",
    )  # fmt: skip
    assert "limits" not in p and "frame_rate" not in p  # the nodes' own defaults


@pytest.mark.parametrize("robot", ROBOTS)
def test_the_urdf_is_made_on_debians_python_without_the_venv(robot):
    """The description's command exactly as robot_description.launch runs it (rosrun, the
    script's /usr/bin/python3), in an environment without the venv; and the module alone under
    /usr/bin/python3 -I (isolated: no PYTHONPATH, no user site)."""
    env = debian_env()
    done = subprocess.run(["rosrun", "follow_bot", "robot_description", "--robot", robot],
                          env=env, capture_output=True, text=True, timeout=30)  # fmt: skip
    assert done.returncode == 0, done.stderr
    p = presets()[robot]
    joints = {j.get("name"): j for j in ElementTree.fromstring(done.stdout).iter("joint")}
    origin = joints["camera_joint"].find("origin")
    x, _, z = (float(v) for v in origin.get("xyz").split())
    assert x == pytest.approx(p["camera_x_offset"])
    assert z + 0.0102 == pytest.approx(p["camera_height"])  # base_link 0.0102 m up
    assert float(origin.get("rpy").split()[1]) == pytest.approx(math.radians(p["camera_pitch_deg"]))
    assert joints["camera_optical_joint"].find("child").get("link") == p["camera_frame"]
    module = REPO / "follow_bot" / "python"
    isolated = subprocess.run(
        ["/usr/bin/python3", "-I", "-c", f"import sys; sys.path.insert(0, {str(module)!r}); "
         "from follow_bot.robot_description import main; main(['--robot', sys.argv[1]])", robot],
        env=env, capture_output=True, text=True, timeout=30,
    )  # fmt: skip
    assert isolated.returncode == 0, isolated.stderr
    assert isolated.stdout == done.stdout


def ros_args(launch: Path) -> tuple[list[str], dict[str, str]]:
    """`roslaunch --ros-args`: the Required args' names and the Optional ones' defaults."""
    done = subprocess.run(["roslaunch", "--ros-args", str(launch)], capture_output=True,
                          text=True, timeout=60)  # fmt: skip
    assert done.returncode == 0, done.stderr
    required, optional, section = [], {}, None
    for line in done.stdout.splitlines():
        if line.endswith("Arguments:"):
            section = line
        elif section == "Required Arguments:":
            required.append(line.split(":")[0].strip())
        elif section == "Optional Arguments:":
            name, default = re.match(r'  (\S+) \(default "(.*)"\):', line).groups()
            optional[name] = default
        assert "undocumented" not in line, (launch.name, line)
    return required, optional


@pytest.mark.parametrize("launch", sorted(p.name for p in LAUNCH.glob("*.launch")))
def test_no_optional_arg_is_reported_required(launch):
    path = LAUNCH / launch
    required, optional = ros_args(path)
    # None of the launch files has an arg without a default: each would be reported Required.
    declared = {a.get("name"): a for a in ElementTree.parse(path).getroot().findall("arg")}
    truly_required = [n for n, a in declared.items() if "default" not in a.attrib
                      and "value" not in a.attrib]  # fmt: skip
    assert required == truly_required == []
    assert set(optional) == {n for n, a in declared.items() if "value" not in a.attrib}
    for name, arg in declared.items():
        assert arg.get("doc"), (launch, name)


@pytest.mark.parametrize("launch", [*ROBOT_LAUNCHES, "lab.launch"])
def test_every_robot_launch_has_the_frame_rate_and_watchdog_args(launch):
    _, optional = ros_args(LAUNCH / launch)
    assert {"expected_frame_rate", "watchdog_timeout"} <= set(optional)


def loaded(launch: Path, args: list[str]):
    """The launch file as roslaunch loads it with `args` (includes, the description's command
    run): its config's nodes and params."""
    import roslaunch.config
    import roslaunch.xmlloader

    config = roslaunch.config.ROSLaunchConfig()
    roslaunch.xmlloader.XmlLoader().load(str(launch), config, argv=["roslaunch", *args])
    return config


@pytest.mark.parametrize("robot", ROBOTS)
@pytest.mark.parametrize("launch", ROBOT_LAUNCHES)
def test_robot_arg_sets_topics_transport_rate_limits_and_description(launch, robot):
    p = presets()[robot]
    config = loaded(LAUNCH / launch, [f"robot:={robot}"])
    node = NODE_OF[launch]
    params = {k: v.value for k, v in config.params.items()}
    (behaviour,) = [n for n in config.nodes if n.name == node]
    remaps = dict(behaviour.remap_args)
    assert remaps["camera/rgb/image_raw"] == p["image"]
    assert remaps["camera/rgb/camera_info"] == p["camera_info"]
    assert params[f"/{node}/image_transport"] == p["image_transport"]
    if "frame_rate" in p:
        assert params[f"/{node}/expected_frame_rate"] == p["frame_rate"]
    else:
        assert f"/{node}/expected_frame_rate" not in params
    limits = {k.rsplit("/", 1)[1]: v for k, v in params.items() if "/limit_" in k}
    assert limits == p.get("limits", {})
    description = ElementTree.fromstring(params["/robot_description"])
    assert p["camera_frame"] in {link.get("name") for link in description.iter("link")}
    # An arg given beside the preset wins over it.
    config = loaded(LAUNCH / launch, [f"robot:={robot}", "image:=my/image",
                                      "image_transport:=raw"])  # fmt: skip
    (behaviour,) = [n for n in config.nodes if n.name == node]
    assert dict(behaviour.remap_args)["camera/rgb/image_raw"] == "my/image"
    assert config.params[f"/{node}/image_transport"].value == "raw"


def readme_robot_commands() -> list[str]:
    """The shell commands of follow_bot/doc/robot.md's "On a real robot" (its ```sh blocks)."""
    manual = (REPO / "follow_bot" / "doc" / "robot.md").read_text()
    section = manual.split("\n## On a real robot\n", 1)[1].split("\n## ", 1)[0]
    blocks = re.findall(r"```sh\n(.*?)```", section, re.S)
    lines = [line.split("  #")[0].strip() for block in blocks for line in block.splitlines()]
    return [line for line in lines if line and not line.startswith("#")]


def test_the_readme_robot_steps_run():
    """Every step of "On a real robot": a rosrun of the description prints the URDF on Debian's
    python3; a roslaunch loads (args, preset, includes, the URDF command) as it would start."""
    commands = readme_robot_commands()
    assert any("robot:=" in c for c in commands)
    for command in commands:
        words = shlex.split(command)
        if words[:2] == ["rosrun", "follow_bot"]:
            done = subprocess.run(words, env=debian_env(), capture_output=True, text=True,
                                  timeout=30)  # fmt: skip
            assert done.returncode == 0, (command, done.stderr)
        elif words[0] == "roslaunch":
            launch = LAUNCH / words[2]
            config = loaded(launch, [w for w in words[3:] if ":=" in w])
            assert config.nodes, command
        else:
            pytest.fail(f"manual step not covered by this test: {command}")
