"""robot:= of every launch that starts a driving node sets that robot's hard limits (its preset's
`limits` in config/robots.yaml) as the node's ~limit_* params, and generic sets none (the
defaults of follow_bot_common/cfg/CommandOutput.cfg). Checked as roslaunch resolves it
(--dump-params), without a roscore."""

import subprocess

import pytest
import yaml

from harness.testing import REPO

# launch file and its arguments: the driving node it starts
LAUNCHES = {
    ("follower.launch",): "/follower",
    ("parker.launch",): "/parker",
    ("beacon_chaser.launch",): "/beacon_chaser",
    ("panorama_node.launch",): "/panorama",
    ("lab.launch", "node:=line_follower.py"): "/line_follower",
    ("lab.launch", "node:=follow_green_stop_red.py"): "/follow_green_stop_red",
}
PRESETS = yaml.safe_load((REPO / "follow_bot/config/robots.yaml").read_text())


def limit_params(launch: tuple, robot: str) -> dict:
    done = subprocess.run(
        ["roslaunch", "--dump-params", "follow_bot", *launch, f"robot:={robot}"],
        capture_output=True, text=True, timeout=60,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    node = LAUNCHES[launch]
    params = yaml.safe_load(done.stdout)
    return {
        name.removeprefix(f"{node}/"): value
        for name, value in params.items()
        if name.startswith(f"{node}/limit_")
    }


@pytest.mark.parametrize("launch", LAUNCHES, ids=" ".join)
def test_the_robots_limits_reach_the_driving_node(launch):
    assert limit_params(launch, "turtlebot3_burger") == PRESETS["turtlebot3_burger"]["limits"]
    assert limit_params(launch, "generic") == {}
