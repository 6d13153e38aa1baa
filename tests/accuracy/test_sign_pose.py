"""Sign poses measured by follow_bot's SignDetector (through `marker_probe`) on frames the
harness renders of worlds/parking_sign.yaml, against the renderer's ground truth.

Needs the built workspace (`rosrun follow_bot marker_probe`). Frames carry 2 grey levels of
noise; also raw frames through the harness's turtlebot3 barrel lens (the detector rectifying its
points), on the same bounds. Run with -s to print the error table.
"""

import json
import math
import subprocess
from dataclasses import replace

import cv2
import numpy as np
import pytest

from harness.camera import LENSES
from harness.geometry import incidence_deg, rotation_angle_deg
from harness.render import Renderer
from harness.scenario_file import load_scenarios
from harness.testing import REPO
from harness.world_file import load_world

WORLDS = REPO / "worlds"
SCENARIOS = WORLDS / "scenarios"
NOISE_SIGMA = 2.0
# Edge displacement below which a tilt goes unseen (see observable_bound): the aligned sign's
# outline is good to about this (measured 0.05-0.15 px), the tag test allows the same 0.1 px.
HIDDEN_PX = 0.1


def facing(sign, distance, lateral=0.0, heading_offset_deg=0.0, look_at=True):
    """Robot pose `distance` in front of the sign along its normal and `lateral` to its right
    (seen from the front), heading at the sign's centre (or along its normal when not
    `look_at`) plus an offset."""
    x, y, _, yaw = sign.pose
    rx = x + distance * math.cos(yaw) - lateral * math.sin(yaw)
    ry = y + distance * math.sin(yaw) + lateral * math.cos(yaw)
    heading = math.atan2(y - ry, x - rx) if look_at else yaw + math.pi
    return (rx, ry, heading + math.radians(heading_offset_deg))


def observable_bound(camera, sign, rot, centre):
    """1 deg, except seen face-on from afar: a tilt t moves the sign's edges by only
    fx (w/2)^2 t / range^2 pixels (0.04 px per degree at 3 m for the 0.4 m sign), so a tilt
    that moves them by less than HIDDEN_PX is not observable there."""
    rng = float(np.linalg.norm(centre))
    incidence = incidence_deg(rot, centre)
    if rng <= 1.05 or incidence >= 15.0:
        return 1.0
    return 1.0 + math.degrees(HIDDEN_PX * rng**2 / (camera.fx * (sign.width / 2) ** 2))


@pytest.fixture(scope="module")
def scene():
    world = load_world(WORLDS / "parking_sign.yaml")
    (sign,) = world.objects
    return world, sign, Renderer(world, noise_sigma=NOISE_SIGMA, seed=1)


@pytest.fixture(scope="module")
def scene_through_lens():
    """Raw frames through the harness's turtlebot3 barrel lens (the detector rectifies)."""
    world = load_world(WORLDS / "parking_sign.yaml")
    (sign,) = world.objects
    camera = replace(world.camera, distortion=LENSES["turtlebot3"])
    renderer = Renderer(world, camera, noise_sigma=NOISE_SIGMA, seed=1)
    return replace(world, camera=camera), sign, renderer


def run_probe(world, sign, frames, independent):
    cam = world.camera
    args = ["rosrun", "follow_bot", "marker_probe", "--sign", str(sign.path)]
    args += ["--width", str(sign.width), "--fx", str(cam.fx), "--fy", str(cam.fy)]
    args += ["--cx", str(cam.cx), "--cy", str(cam.cy)]
    if cam.distorted:
        args += ["--distortion", ",".join(str(d) for d in cam.distortion)]
    args += ["--independent"] if independent else []
    result = subprocess.run(
        [*args, *map(str, frames)], capture_output=True, text=True, timeout=600, check=True
    )
    return [json.loads(line) for line in result.stdout.splitlines()]


def measure(scene, tmp_path, poses, independent):
    world, sign, renderer = scene
    frames = []
    for i, pose in enumerate(poses):
        frames.append(tmp_path / f"frame{i:03d}.png")
        cv2.imwrite(str(frames[-1]), renderer.render(pose, frame=i))
    rows = []
    for pose, seen in zip(poses, run_probe(world, sign, frames, independent), strict=True):
        rot, centre = world.camera.marker_pose(pose, sign.pose)
        row = {"pose": pose, "range": float(np.linalg.norm(centre)), "seen": seen}
        if seen["found"]:
            row["position_error"] = float(np.linalg.norm(np.array(seen["translation"]) - centre))
            row["angle_error"] = rotation_angle_deg(np.array(seen["rotation"]), rot)
            row["bound"] = observable_bound(world.camera, sign, rot, centre)
            row["incidence"] = incidence_deg(rot, centre)
        rows.append(row)
    return rows


def print_table(title, rows):
    print(f"\n{title}\n range  incid.  position err  angle err  bound  inliers  detect ms")
    for r in rows:
        s = r["seen"]
        if not s["found"]:
            print(f" {r['range']:5.2f}  not found")
            continue
        print(
            f" {r['range']:5.2f}  {r['incidence']:5.1f}  {1000 * r['position_error']:8.1f} mm"
            f"  {r['angle_error']:6.3f}    {r['bound']:4.2f}  {s['quality']:5.0f}"
            f"  {s['detect_ms']:7.1f}"
        )


def assert_found_within_bounds(cases: list, rows: list[dict]) -> None:
    """Each case's row (in order): the sign found, within 1 cm and within its angle bound."""
    for case, r in zip(cases, rows, strict=True):
        assert r["seen"]["found"], case
        assert r["position_error"] < 0.01, (case, r["position_error"])
        assert r["angle_error"] < r["bound"], (case, r["angle_error"])


# (distance along the sign's normal, lateral offset, heading offset deg): 0.5-3 m, straight on,
# off to either side (incidence up to ~45 deg) and with the sign off the image centre.
VIEWS = [
    (0.5, 0.0, 0.0),
    (0.5, 0.1, 5.0),
    (0.5, -0.3, -3.0),
    (0.8, 0.4, 8.0),
    (1.0, 0.0, 0.0),
    (1.0, -0.6, 0.0),
    (1.5, 0.0, 10.0),
    (1.5, 1.0, -5.0),
    (2.0, 0.0, 0.0),
    (2.0, -1.2, 8.0),
    (2.5, 0.0, -12.0),
    (2.5, 1.5, 0.0),
    (3.0, 0.0, 0.0),
    (3.0, 0.5, 5.0),
    (2.6, -1.5, 0.0),
]


@pytest.mark.parametrize("frames", ["scene", "scene_through_lens"])
def test_sign_pose_on_harness_frames(frames, request, tmp_path):
    scene = request.getfixturevalue(frames)
    _, sign, _ = scene
    poses = [facing(sign, *v) for v in VIEWS]
    rows = measure(scene, tmp_path, poses, independent=True)
    print_table("views (fresh detector per frame)", rows)
    assert_found_within_bounds(VIEWS, rows)
    # Mean position error, measured 0.7 mm on pinhole frames and 1.0 mm through the lens (3.9 mm
    # while the sign was aligned on the raw frame, up to 6.5 mm at 0.9-2 m).
    assert np.mean([r["position_error"] for r in rows]) < 0.002


def test_no_flips_over_a_fronto_parallel_sweep(scene, tmp_path):
    """Camera axis square to the sign, sliding sideways at 2.5 m then backing off from 0.5 to
    3 m, one detector tracking: the planar pose's mirror solution (about 2x the angle between
    the line of sight and the sign's normal away) must never be chosen."""
    _, sign, _ = scene
    poses = [facing(sign, 2.5, lat, look_at=False) for lat in np.arange(-0.6, 0.61, 0.1)]
    poses += [facing(sign, d, 0.15, look_at=False) for d in np.arange(0.5, 3.01, 0.25)]
    rows = measure(scene, tmp_path, poses, independent=False)
    print_table("fronto-parallel sweep (one detector)", rows)
    assert_found_within_bounds(poses, rows)


def test_found_from_every_scenario_start_with_the_sign_in_view(scene, tmp_path):
    """The sign parking scenarios' start frames: found (within 1 cm) iff the sign is in view."""
    world, _, renderer = scene
    runs = load_scenarios(SCENARIOS / "parker_sign.yaml")
    starts = [s.start for s in runs if not s.perturbations.lens]  # the lens runs replay these
    rows = measure(scene, tmp_path, starts, independent=True)
    print_table("scenario start frames", rows)
    for start, r in zip(starts, rows, strict=True):
        (proj,) = renderer.object_projections(start)
        u, v = np.array(proj["corners_px"]).T
        cam = world.camera
        in_view = bool(((u >= 0) & (u < cam.width) & (v >= 0) & (v < cam.height)).all())
        assert r["seen"]["found"] == in_view, start
        if in_view:
            assert r["position_error"] < 0.01, (start, r["position_error"])
    assert sum(r["seen"]["found"] for r in rows) == 8
