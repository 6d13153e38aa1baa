"""What the parker's scenarios add to the harness: hiding an object for a time window, the
two-tag parking world, and the time from which a run stays still."""

import numpy as np
import pytest

from harness.apriltag_image import detect
from harness.scenario import ScenarioError
from harness.scenario_parse import parse_scenario
from harness.scoring import still_since
from harness.simulation import Perturbations, Simulation
from harness.world import WORLDS_DIR
from harness.world_file import load_world

BASE = {"world": "parking", "driver": {"constant": [0.0, 0.0]}, "duration": 1.0}


def test_hide_parses_object_and_window():
    hide = {"hide": [["goal_tag", 1.0, 2.0]]}
    scenario = parse_scenario({**BASE, "perturbations": hide}, WORLDS_DIR)
    assert scenario.perturbations.hidden == (("goal_tag", 1.0, 2.0),)


@pytest.mark.parametrize(
    "hide, words",
    [
        ([["goal_tag", 2.0, 1.0]], "end must be after start"),
        ([["goal_tag", 1.0]], "[object_name, start, end]"),
        ([[3, 1.0, 2.0]], "hide[0][0]"),
    ],
)
def test_malformed_hide_names_the_field(hide, words):
    with pytest.raises(ScenarioError, match=r"perturbations\.hide") as error:
        parse_scenario({**BASE, "perturbations": {"hide": hide}}, WORLDS_DIR)
    assert words in str(error.value)


def test_hidden_object_is_left_out_of_frames_in_its_window_only(worlds):
    hide = Perturbations(hidden=(("goal_tag", 0.1, 0.2),))
    sim = Simulation(worlds["parking"], start=(1.5, 0.0, 0.0), perturbations=hide)
    seen = []
    for _ in range(9):  # t = 0 .. 0.267 s at 30 Hz
        gray = sim.render()[..., 1]
        seen.append(any(d.tag_id == 0 for d in detect(gray)))
        sim.step((0.0, 0.0), frame=True, replies=1, missed=False)
    assert seen == [True, True, True, False, False, False, True, True, True]


def test_hiding_an_unknown_object_is_an_error(worlds):
    with pytest.raises(ValueError, match="no object named 'nope'"):
        Simulation(worlds["parking"], perturbations=Perturbations(hidden=(("nope", 0.0, 1.0),)))


def test_two_tag_world_shows_both_ids_from_the_start():
    world = load_world(WORLDS_DIR / "parking_two_tags.yaml")
    sim = Simulation(world, start=(1.2, 0.0, 0.0))
    ids = sorted(d.tag_id for d in detect(sim.render()[..., 1]))
    assert ids == [0, 5]


def test_still_since_is_the_start_of_the_final_standstill():
    t = np.arange(6) * 0.1
    assert still_since(t, [1, 1, 0, 1, 0, 0], [0, 0, 0, 0, 0, 0]) == pytest.approx(0.4)
    assert still_since(t, [0] * 6, [0] * 6) == 0.0
    assert still_since(t, [0, 0, 0, 0, 0, 0], [0, 0, 0, 0, 0, 0.1]) is None
