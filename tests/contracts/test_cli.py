"""Every command-line tool behaves as ROS users expect: --help prints the usage on stdout and
exits 0 (starting nothing), bad usage exits 2 with the problem and the usage on stderr. A node's
--help also names its topics and its manual (doc/<node>.md of its package), which documents them
and its parameters."""

import json
import os
import re
import signal
import subprocess
import time
from pathlib import Path

import pytest

from harness.processes import free_port, private_master

TOOLS = {
    "stitch": ["rosrun", "image_converter", "stitch"],
    "marker_probe": ["rosrun", "follow_bot", "marker_probe"],
    "core_reference": ["rosrun", "follow_bot", "core_reference"],
    "core_call_timer": ["rosrun", "follow_bot", "core_call_timer"],
    # "package tool" where two packages have a tool of that name
    "image_converter core_reference": ["rosrun", "image_converter", "core_reference"],
    "sim": ["rosrun", "harness", "sim"],
    "run_scenario": ["rosrun", "harness", "run_scenario"],
    "constant_twist": ["rosrun", "harness", "constant_twist"],
    "image_stream_demo": ["rosrun", "harness", "image_stream_demo"],
    "follower": ["rosrun", "follow_bot", "follower"],
    "beacon_chaser": ["rosrun", "follow_bot", "beacon_chaser"],
    "parker": ["rosrun", "follow_bot", "parker"],
    "panorama": ["rosrun", "follow_bot", "panorama"],
    "image_converter": ["rosrun", "image_converter", "image_converter"],
    "robot_description": ["rosrun", "follow_bot", "robot_description"],
}
NODES = ["follower", "beacon_chaser", "parker", "panorama", "image_converter"]

# No master listens here: a tool that tried to start ROS would hang until the timeout.
NO_MASTER = dict(os.environ, ROS_MASTER_URI=f"http://127.0.0.1:{free_port()}")


def run(args: list[str]) -> subprocess.CompletedProcess:
    return subprocess.run(args, env=NO_MASTER, capture_output=True, text=True, timeout=20)


@pytest.mark.parametrize(
    ("tool", "flag"),
    [
        ("stitch", "--help"),
        ("stitch", "-h"),
        ("marker_probe", "--help"),
        ("core_reference", "--help"),
        ("core_call_timer", "--help"),
        ("image_converter core_reference", "--help"),
        ("sim", "--help"),
        ("run_scenario", "--help"),
        ("constant_twist", "--help"),
        ("image_stream_demo", "--help"),
        ("robot_description", "--help"),
        *[(node, flag) for node in NODES for flag in ("--help", "-h")],
    ],
)
def test_help_prints_the_usage_and_exits_0(tool, flag):
    result = run([*TOOLS[tool], flag])
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith(f"usage: {tool.split()[-1]}"), result.stdout
    assert result.stderr == ""


@pytest.mark.parametrize("node", NODES)
def test_a_node_help_names_its_topics_and_its_manual(node):
    help_text = run([*TOOLS[node], "--help"]).stdout
    manual = re.search(r"^  (/\S+)/doc/(\S+)\.md$", help_text, re.M)
    assert manual, help_text
    assert manual[2] == node
    package = run(["rospack", "find", TOOLS[node][1]]).stdout.strip()
    assert manual[1] == package, help_text
    page = Path(manual[0].strip()).read_text()
    # The node's manual (the truth the help is held to) is about the node and names every topic.
    assert page.startswith(f"# {node} (node `{node}`"), page[:200]
    assert "<!-- params: " in page  # its generated parameter table (tools/param_tables.py)
    topics = re.findall(r"^  (?:in|out|service) +(\S+)", help_text, re.M)
    assert "camera/rgb/image_raw" in topics, help_text
    undocumented = [t for t in topics if t != "/diagnostics" and f"`{t}`" not in page]
    assert undocumented == [], help_text


@pytest.mark.parametrize(
    ("tool", "args", "problem"),
    [
        ("stitch", [], "stitch: no output file (-o pano.png)"),
        ("stitch", ["a.png", "b.png", "-o"], "stitch: the required argument for option"),
        ("stitch", ["a.png", "b.png", "-o", "p.png", "--frob"], "unrecognised option '--frob'"),
        ("stitch", ["a.png", "-o", "p.png"], "need at least two input images, got 1"),
        ("stitch", ["a.png", "b.png", "-o", "p.png", "--detector", "surf"], "'surf'"),
        ("marker_probe", ["--tag-size", "0.2"], "marker_probe: no frames given"),
        ("marker_probe", ["--tag-size", "big", "f.png"], "marker_probe: the argument ('big')"),
        ("marker_probe", ["f.png"], "give either --sign IMAGE --width W or --tag-size S"),
        ("core_reference", ["--line"], "core_reference: give --line, --blobs, --steer MODE or"),
        ("core_reference", ["--frob", "f.png"], "core_reference: give --line, --blobs"),
        ("core_reference", ["--steer", "fast", "f.png"], "unknown steering mode 'fast'"),
        ("image_converter core_reference", ["--match", "a.png"], "core_reference: bad arguments"),
        ("core_call_timer", ["--line"], "core_call_timer: no frames given"),
        ("core_call_timer", ["--tag", "--rounds", "0", "f.png"], "--rounds needs a count >= 1"),
        ("core_call_timer", ["--sign"], "--sign needs the sign's IMAGE and width W (m)"),
        ("sim", ["--frob"], "sim: error: unrecognized arguments: --frob"),
        ("run_scenario", ["--frob"], "error: "),  # its prog name is the scenarios owner's
        ("robot_description", ["--robot", "turtlebot4"], "unknown robot 'turtlebot4': one of"),
    ],
)
def test_bad_usage_exits_2_with_the_usage_on_stderr(tool, args, problem):
    result = run([*TOOLS[tool], *args])
    assert result.returncode == 2, result.stdout + result.stderr
    assert problem in result.stderr
    assert "usage: " + tool.split()[-1] in result.stderr
    assert result.stdout == ""


def test_the_simulator_starts_without_warnings():
    with private_master() as env:
        sim = subprocess.run(
            [*TOOLS["sim"], "_world:=course", "_lockstep:=false", "_duration:=0.5"],
            env=env, capture_output=True, text=True, timeout=60,
        )  # fmt: skip
    assert sim.returncode == 0, sim.stderr
    assert "Warning" not in sim.stderr and "WARN" not in sim.stdout + sim.stderr, sim.stderr


def test_a_behaviour_dead_at_launch_ends_its_run_as_could_not_run(tmp_path):
    """A follower refusing its ~max_linear at start-up: the lockstep simulator's first frame gets
    no answer from a status topic nobody publishes, so the run ends there as an error (it used
    to wait the reply timeout on each of the 6 000 frames of its 200 s)."""
    scenario = tmp_path / "dead.yaml"
    scenario.write_text(
        "name: dead_at_launch\nworld: course\nduration: 200.0\n"
        "behaviour: {launch: follow_bot follower.launch, args: {max_linear: -1}}\n"
        "criteria: {lap.complete: {equals: true}}\n"
    )
    done = subprocess.run(
        [*TOOLS["run_scenario"], str(scenario), "--out", str(tmp_path / "out")],
        capture_output=True, text=True, timeout=240,
    )  # fmt: skip
    assert done.returncode == 2, done.stdout + done.stderr  # 2: a run could not be played
    assert "0/1 passed (1 could not run)" in done.stdout, done.stdout
    result = json.loads((tmp_path / "out" / "summary.json").read_text())["runs"][0]
    assert result["error"].startswith("the behaviour under test is not running"), result


def test_run_scenario_stopped_by_sigterm_leaves_no_process_of_its_runs(tmp_path):
    """Killed mid-run (a `timeout`, a cancelled job), run_scenario stops its runs' ROS graphs:
    each one's roscore, simulator, behaviour and robot description, whose command lines or
    logs name the run's folder, must all be gone."""
    scenario = tmp_path / "long.yaml"
    scenario.write_text(
        "name: killed\nworld: course\nduration: 200.0\n"
        "behaviour: {launch: follow_bot follower.launch}\n"
        "criteria: {lap.complete: {equals: true}}\n"
    )
    out = tmp_path / "out"
    run_scenario = subprocess.Popen(
        [*TOOLS["run_scenario"], str(scenario), "--out", str(out)],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
    )  # fmt: skip

    def processes_of_the_run() -> list[str]:
        listing = subprocess.run(["ps", "-eo", "pid=,args="], capture_output=True, text=True)
        return [line for line in listing.stdout.splitlines()
                if str(out) in line and str(run_scenario.pid) != line.split()[0]]  # fmt: skip

    deadline = time.monotonic() + 120
    while not any("sim_node" in line for line in processes_of_the_run()):
        assert time.monotonic() < deadline and run_scenario.poll() is None, "the run never began"
        time.sleep(0.5)
    run_scenario.terminate()
    assert run_scenario.wait(timeout=30) == 128 + signal.SIGTERM
    assert processes_of_the_run() == []
