"""Realism options: each effect's pixels on small frames, determinism per seed, distractors."""

import math
from dataclasses import replace

import cv2
import numpy as np
import pytest

from harness.distractors import TAPE_COLOUR, with_distractors
from harness.realism import PROFILES, Realism, parse_realism, realism_from
from harness.render import Renderer
from harness.sensor import Sensor, line_kernel
from harness.textures import floor_texture, shadow_band_mask
from harness.validation import ValidationError

REALISTIC = realism_from(PROFILES["realistic"])


def uniform(value: int, shape=(9, 11)) -> np.ndarray:
    return np.full((*shape, 3), value, np.uint8)


def test_parse_expands_the_profile_and_lays_fields_over_it():
    options = parse_realism({"profile": "realistic", "jpeg_quality": 40}, "realism")
    assert options == {**PROFILES["realistic"], "jpeg_quality": 40}
    with pytest.raises(ValidationError, match=r"realism\.floor: one of plain, wood"):
        parse_realism({"floor": "marble"}, "realism")
    with pytest.raises(ValidationError, match=r"realism\.profile: unknown profile 'gritty'"):
        parse_realism({"profile": "gritty"}, "realism")
    with pytest.raises(ValidationError, match=r"realism\.glare: unknown field"):
        parse_realism({"glare": 1}, "realism")


def test_a_range_is_drawn_per_run_from_its_seed():
    options = parse_realism({"shadow_depth": [0.3, 0.55], "tape": [4, 6], "floor": "wood"}, "r")
    assert options == {"shadow_depth": (0.3, 0.55), "tape": (4, 6), "floor": "wood"}
    runs = [realism_from(options, seed=seed) for seed in range(200)]
    depths = [r.shadow_depth for r in runs]
    assert min(depths) >= 0.3 and max(depths) < 0.55 and np.ptp(depths) > 0.2
    assert {r.tape for r in runs} == {4, 5, 6}
    assert realism_from(options, seed=7) == realism_from(options, seed=7)
    # An option's draw depends on its name and the seed only, not on the other options.
    alone = realism_from(parse_realism({"shadow_depth": [0.3, 0.55]}, "r"), seed=7)
    assert alone.shadow_depth == realism_from(options, seed=7).shadow_depth
    with pytest.raises(ValidationError, match=r"realism\.tape: needs low <= high"):
        parse_realism({"tape": [6, 4]}, "realism")
    with pytest.raises(ValidationError, match=r"realism\.vignetting\[1\]: must be < 1"):
        parse_realism({"vignetting": [0.2, 1.5]}, "realism")


def test_the_harsh_profile_draws_every_range_within_it():
    ranges = {k: v for k, v in PROFILES["harsh"].items() if isinstance(v, tuple)}
    for seed in range(20):
        harsh = realism_from(PROFILES["harsh"], seed=seed)
        for key, (low, high) in ranges.items():
            assert low <= getattr(harsh, key) <= high, key
        assert harsh.floor == "wood" and harsh.jpeg_quality == 60 and harsh.yellow_box
    assert 0.05 <= realism_from(PROFILES["harsh"], seed=3).actuation_delay <= 0.15


def test_drifting_shadows_darken_and_tint_the_floor_and_move(worlds):
    world = worlds["rgb"]  # plain grey floor (120), balls far ahead
    realism = Realism(shadow_bands=6, shadow_depth=0.4, shadow_drift=0.5, shadow_tint=0.2)
    renderer = Renderer(world, realism=realism, seed=3)
    pose = (0.0, 0.0, math.pi)  # facing the open floor
    first = renderer.render(pose, frame=0)
    later = renderer.render(pose, frame=30)  # 1 s later: the bands moved 0.5 m
    floor = first[300:]
    expected = 120 * 0.4 * np.array([1.2, 1.0, 0.8])  # depth 40 %, blue up and red down 20 %
    shadowed = np.all(np.abs(floor - expected) <= 1.0, axis=-1)  # the gain is kept to 1/255
    lit = np.all(floor == 120, axis=-1)
    assert shadowed.any() and lit.any()
    assert np.count_nonzero(~(shadowed | lit)) < 0.05 * lit.size  # hard edges
    assert (first[300:] != later[300:]).any()
    assert (renderer.render(pose, frame=30) == later).all()  # and repeat


def test_a_realism_lens_delay_lag_and_dropped_frames_reach_the_run():
    from harness.scenario_parse import parse_scenario
    from harness.simulation import Simulation
    from harness.world_file import load_world

    realism = {"barrel": 0.28, "actuation_delay": 0.05, "motor_lag": 0.1, "frame_drop": 0.2}
    scenario = parse_scenario(
        {
            "world": "course",
            "driver": {"constant": [0.1, 0.0]},
            "duration": 1.0,
            "perturbations": {"realism": realism},
        }
    )
    sim = Simulation(load_world(scenario.world_path), perturbations=scenario.perturbations)
    assert sim.renderer.camera.camera_info_dict()["D"] == [-0.28, 0.07, 0.0, 0.0, 0.0]
    assert len(sim.robot._queue) == 2  # 50 ms at 30 Hz: one whole step and a half
    assert sim.robot.delay_fraction == pytest.approx(0.5)
    assert sim.robot.lag == 0.1
    dropped = 0
    for _ in range(3000):
        dropped += not sim.frames_flowing()
        sim.step((0.1, 0.0), frame=True, replies=1, missed=False)
    assert dropped == pytest.approx(600, abs=75)  # 20 %, binomial sigma 22


def test_vignetting_darkens_the_corners_by_its_strength():
    sensor = Sensor(Realism(vignetting=0.3), 11, 9, seed=0, rate_hz=30.0)
    out = sensor.apply(uniform(200), frame=0, flow_px=(0.0, 0.0))
    assert (out[4, 5] == 200).all()  # centre
    assert (out[0, 0] == 140).all() and (out[8, 10] == 140).all()  # 200 * (1 - 0.3)


def test_exposure_and_white_balance_scale_each_channel_by_its_gain():
    sensor = Sensor(Realism(exposure_drift=0.1, white_balance=0.08), 11, 9, seed=4, rate_hz=30.0)
    for frame in (0, 45, 300):
        gains = sensor.channel_gains(frame)
        out = sensor.apply(uniform(100), frame=frame, flow_px=(0.0, 0.0))
        assert out[0, 0].tolist() == [round(100 * g) for g in gains]
    assert not np.allclose(sensor.channel_gains(0), sensor.channel_gains(135))  # it drifts
    assert np.ptp(sensor.channel_gains(0)) > 0.0  # the channels differ


def test_noise_grows_with_brightness_and_repeats_per_seed_and_frame():
    sensor = Sensor(Realism(read_noise=1.0, shot_noise=0.2), 400, 300, seed=5, rate_hz=30.0)
    dark = sensor.apply(uniform(10, (300, 400)), 3, (0.0, 0.0)).astype(float)
    bright = sensor.apply(uniform(200, (300, 400)), 3, (0.0, 0.0)).astype(float)
    assert dark.std() == pytest.approx(math.sqrt(1.0 + 0.2 * 10), rel=0.05)
    assert bright.std() == pytest.approx(math.sqrt(1.0 + 0.2 * 200), rel=0.05)
    again = sensor.apply(uniform(200, (300, 400)), 3, (0.0, 0.0))
    assert (again == bright).all()
    other = sensor.apply(uniform(200, (300, 400)), 4, (0.0, 0.0))
    assert (other != bright).any()


def test_jpeg_is_opencvs_round_trip_at_the_quality():
    image = np.random.default_rng(1).integers(0, 256, (16, 16, 3), dtype=np.uint8)
    out = Sensor(Realism(jpeg_quality=40), 16, 16, 0, 30.0).apply(image, 0, (0.0, 0.0))
    _, data = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, 40])
    assert (out == cv2.imdecode(data, cv2.IMREAD_COLOR)).all()
    assert (out != image).any()


def test_motion_blur_spreads_a_bright_column_along_the_motion():
    assert line_kernel(0.3, 0.0) is None  # under half a pixel: no blur
    kernel = line_kernel(4.0, 0.0)
    assert kernel.sum() == pytest.approx(1.0)
    assert np.count_nonzero(kernel.sum(axis=1)) == 1  # horizontal motion: one row
    image = np.zeros((5, 21, 3), np.uint8)
    image[:, 10] = 250
    out = Sensor(Realism(exposure_time=0.01), 21, 5, 0, 30.0).apply(image, 0, (4.0, 0.0))
    row = out[2, :, 0].astype(int)
    assert (row[:8] == 0).all() and (row[13:] == 0).all()
    assert np.count_nonzero(row) == 5 and abs(row.sum() - 250) <= 3
    assert (out[:, :, 0] == out[:, :, 1]).all() and (out[0] == out[4]).all()


def test_motion_flow_of_a_turn_is_sideways_and_scales_with_exposure(worlds):
    world = worlds["course"]
    renderer = Renderer(world, realism=Realism(exposure_time=0.02))
    du, dv = renderer.motion_flow(world.robot.start, (0.0, 1.0))
    assert abs(du) == pytest.approx(world.camera.fx * 0.02, rel=0.15)
    assert abs(dv) < 0.2 * abs(du)
    assert renderer.motion_flow(world.robot.start, (0.0, 0.0)) == (0.0, 0.0)
    du_fwd, dv_fwd = renderer.motion_flow(world.robot.start, (0.5, 0.0))
    assert abs(du_fwd) < 1e-6 and dv_fwd > 0.0  # driving forward: the floor slides down


@pytest.mark.parametrize("kind", ["wood", "tiles", "carpet", "concrete"])
def test_floor_textures_are_seeded(kind):
    a = floor_texture(kind, (120, 160), 0.01, seed=3)
    assert a.shape == (120, 160, 3) and a.dtype == np.uint8
    assert (a == floor_texture(kind, (120, 160), 0.01, seed=3)).all()
    assert (a != floor_texture(kind, (120, 160), 0.01, seed=4)).any()
    assert a.std() > 2.0  # not a plain colour


def test_tiles_have_grout_every_30_cm():
    tex = floor_texture("tiles", (100, 100), 0.01, seed=0)
    assert tex[0, 5].tolist() == [120, 125, 130] and tex[30, 5].tolist() == [120, 125, 130]
    assert tex[15, 15].tolist() != [120, 125, 130]


def test_wood_stays_out_of_the_lines_yellow_hue():
    hsv = cv2.cvtColor(floor_texture("wood", (200, 300), 0.005, seed=1), cv2.COLOR_BGR2HSV)
    yellow = cv2.inRange(hsv, (20, 100, 100), (30, 255, 255))  # the follower's default
    assert np.count_nonzero(yellow) == 0


def test_shadow_bands_are_hard_edged_stripes():
    mask = shadow_band_mask((200, 200), 0.01, 2, seed=2)
    assert mask.min() == pytest.approx(0.0) and mask.max() == pytest.approx(1.0, abs=0.01)
    soft = np.count_nonzero((mask > 0.05) & (mask < 0.95))
    assert 0 < soft < 0.1 * mask.size  # edges a few pixels wide, not a gradient


def test_clean_default_renders_as_before(worlds):
    world = worlds["course"]
    plain = Renderer(world).render(world.robot.start)
    explicit = Renderer(world, realism=Realism()).render(world.robot.start)
    assert (plain == explicit).all()


@pytest.mark.parametrize("name", ["course", "rgb", "parking_sign"])
def test_realistic_frames_repeat_per_seed(worlds, name):
    world = worlds[name]
    pose = world.robot.start
    a = Renderer(world, realism=REALISTIC, seed=7).render(pose, frame=5, motion=(0.2, 0.4))
    b = Renderer(world, realism=REALISTIC, seed=7).render(pose, frame=5, motion=(0.2, 0.4))
    c = Renderer(world, realism=REALISTIC, seed=8).render(pose, frame=5, motion=(0.2, 0.4))
    assert (a == b).all()
    assert (a != c).any()


def test_walls_close_the_horizon(worlds):
    world = worlds["rgb"]
    pose = (0.0, 0.0, math.pi)  # balls behind
    image = Renderer(world, realism=Realism(walls=1.2)).render(pose)
    # The 1.2 m wall 6 m away spans 0.9 m above the 0.3 m high camera to 0.3 m below it:
    # rows 240 - 554 * 0.9 / 6 = 157 to 240 + 554 * 0.3 / 6 = 268.
    assert (image[160:266, 320] != 200).all()
    assert (image[:154, 320] == 200).all()  # the sky (ceiling) above it
    assert (image[271:, 320] == 120).all()  # the floor below it as before


def test_distractors_keep_clear_of_the_course_and_the_robots_way(worlds):
    course = worlds["course"]
    line = course.ground.lines[0].points
    real = with_distractors(course, replace(REALISTIC, tape=8), seed=1, starts=[(-2.5, -3.5)])
    lane = real.ground.lines[1]
    distance = np.min(np.hypot(*(lane.points[:, None] - line[None]).transpose(2, 0, 1)), axis=1)
    assert distance == pytest.approx(np.full(len(distance), 0.3), abs=0.005)
    tapes = [ln for ln in real.ground.lines[2:] if ln.colour == TAPE_COLOUR]
    assert len(tapes) == 8
    for tape in tapes:
        centre = tape.points.mean(axis=0)
        assert np.min(np.hypot(*(line - centre).T)) >= 0.3 - 1e-6
    assert real.ground.lines[0] is course.ground.lines[0]
    beacons = worlds["rgb"]
    real = with_distractors(beacons, REALISTIC, seed=1, starts=[(0.0, 0.0)])
    added = real.objects[len(beacons.objects) :]
    assert len([o for o in added if o.name.startswith("clutter")]) == REALISTIC.clutter
    for obj in added:
        xy = np.array(getattr(obj, "position", None) or obj.pose)[:2]
        for ball in beacons.objects:
            b = np.array(ball.position[:2])
            t = np.clip(xy @ b / (b @ b), 0.0, 1.0)  # the way from the start (0, 0) to the ball
            assert np.hypot(*(xy - t * b)) >= 0.6 - 1e-6
    sign = worlds["parking_sign"]
    real = with_distractors(sign, REALISTIC, seed=1, starts=[(0.0, 0.0)])
    posters = [o for o in real.objects if o.name.startswith("poster")]
    assert len(posters) == REALISTIC.posters
    for poster in posters:
        assert abs(poster.pose[1] - sign.objects[0].pose[1]) >= 0.75  # beside the sign


def test_a_scenario_sets_realism_and_lens_over_the_world(tmp_path):
    from harness.camera import LENSES
    from harness.scenario_parse import parse_scenario
    from harness.simulation import Simulation
    from harness.world_file import load_world

    scenario = parse_scenario(
        {
            "world": "course",
            "driver": {"constant": [0.1, 0.0]},
            "duration": 1.0,
            "perturbations": {"realism": {"profile": "realistic"}, "lens": "turtlebot3"},
        }
    )
    sim = Simulation(load_world(scenario.world_path), perturbations=scenario.perturbations)
    assert sim.renderer.realism == REALISTIC
    info = sim.renderer.camera.camera_info_dict()
    assert info["D"] == list(LENSES["turtlebot3"])
    assert sim.render().shape == (480, 640, 3)


def test_realistic_families_extend_the_clean_ones_with_their_bounds():
    from pathlib import Path

    from harness.scenario_file import load_scenarios

    folder = Path(__file__).resolve().parents[2] / "worlds" / "realistic"
    sizes = {
        "follower_realistic": 19,
        "dumpster_realistic": 2,
        "beacons_follow_green_realistic": 1,
        "beacons_red_stop_realistic": 1,
        "parker_tag_realistic": 3,
        "parker_sign_realistic": 3,
    }
    for family, size in sizes.items():
        runs = load_scenarios(folder / f"{family}.yaml")
        assert len(runs) == size, family
        clean = load_scenarios(folder.parent / "scenarios" / f"{family[: -len('_realistic')]}.yaml")
        for run in runs:
            assert run.perturbations.realism, run.name
            assert {c.metric for c in clean[0].criteria} <= {c.metric for c in run.criteria}
    lap = load_scenarios(folder / "follower_realistic.yaml")[0]
    assert lap.name == "follower_realistic/realistic"
    assert dict(lap.perturbations.realism) == PROFILES["realistic"]
    assert {c.metric: c.maximum for c in lap.spec_criteria}["cross_track.rms"] == 0.001
    laps = {run.name: run for run in load_scenarios(folder / "follower_realistic.yaml")}
    for seed in (1, 2, 3):
        other = laps[f"follower_realistic/realistic_seed{seed}"]
        assert other.seed == seed
        assert other.perturbations.realism == lap.perturbations.realism
    fast = laps["follower_realistic/realistic_fast"]
    assert fast.perturbations.realism == lap.perturbations.realism
    assert fast.behaviour.args["max_linear"] == "0.7"
    assert {c.metric: c.maximum for c in fast.spec_criteria}["cross_track.max"] == 0.030
