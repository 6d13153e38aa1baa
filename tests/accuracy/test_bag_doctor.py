"""The bag doctor (`rosrun follow_bot inspect`) on recordings whose truth the doctor did not make.

- A lap of the course rendered by the harness, written as a bag the way a robot records one
  (raw bgr8 frames, camera_info, tf_static, cmd_vel): the doctor's sighting in every frame against
  where the renderer's own centreline crosses the band (projected through the harness camera),
  and the mounting it reads from tf_static against the world's; clean, under the harness's
  realistic profile and under its harsh one (one seed's draw, with its barrel lens).
- The same lap under a colour cast the default band misses (blue-green light: the line's hue
  moves from 25 to ~42), as JPEG: --fit-colours raises the detection rate, and the fitted band
  finds the line where the renderer put it.
- The beacons' drive toward a green ball under a growing glare the default s_min misses:
  --behaviour beacons --fit-colours raises the detection rate, and the fitted thresholds find
  the ball where the renderer put it.
- The real raspicam bags (old "jpg" format, a topic without a leading slash), when present.
- Under Debian's python3 without OpenCV, --help works and a run says what to install.
"""

import ast
import json
import math
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import rosbag
import rospy
import yaml
from geometry_msgs.msg import TransformStamped, Twist
from nav_msgs.msg import Odometry
from sensor_msgs.msg import CameraInfo, CompressedImage, Image
from tf2_msgs.msg import TFMessage

from follow_bot import bag_doctor, core
from harness.realism import PROFILES, barrel_distortion, realism_from
from harness.render import Renderer
from harness.world import WORLDS_DIR
from harness.world_file import load_world

STEP_M = 0.25  # lap frames this far apart along the line
RATE_HZ = 0.3 / STEP_M  # as a robot at 0.3 m/s
OFFSET_M = 0.04  # the robot weaves this far either side of the line
# A blue-green light: per-channel gains (B, G, R) on the rendered frames; the line reads hue ~45,
# past the default window's 40.
CAST = np.array([1.0, 0.95, 0.4])
HARSH_SEED = 1  # the harsh profile's draw: a run's seed


def lap_poses(world):
    """Poses every STEP_M along the course's centreline, weaving +-OFFSET_M across it and
    turned up to 0.1 rad off its heading, so the line sweeps across the band."""
    line = world.centreline(0)
    steps = np.linalg.norm(np.diff(line, axis=0, append=line[:1]), axis=1)
    along = np.r_[0.0, np.cumsum(steps)[:-1]]
    poses = []
    for s in np.arange(0.0, along[-1], STEP_M):
        i = int(np.searchsorted(along, s, side="right") - 1)
        a, b = line[i], line[(i + 1) % len(line)]
        heading = math.atan2(b[1] - a[1], b[0] - a[0])
        phase = 2 * math.pi * s / 3.0
        offset = OFFSET_M * math.sin(phase)
        x = a[0] - offset * math.sin(heading)
        y = a[1] + offset * math.cos(heading)
        poses.append((x, y, heading + 0.1 * math.cos(phase)))
    return poses


def band_truth(camera, centreline, pose, rows):
    """The normalised column (-1 left .. 1 right) where the centreline crosses the band's middle
    row (through the camera's lens), or None when it does not cross it inside the image once."""
    pixels, depth = camera.project(np.column_stack([centreline, np.zeros(len(centreline))]), pose)
    if camera.distorted:
        # Only rays within 1 of the optical axis (normalised): the barrel's polynomial folds
        # back far outside the view, where it would put far points inside the image.
        near = np.hypot(
            (pixels[:, 0] - camera.cx) / camera.fx, (pixels[:, 1] - camera.cy) / camera.fy
        )
        depth = np.where(near < 1.0, depth, -1.0)
        pixels = camera.distort_pixels(np.nan_to_num(pixels))
    row = (rows[0] + rows[1] - 1) / 2.0
    crossings = []
    for (u0, v0), (u1, v1), d0, d1 in zip(
        pixels, np.roll(pixels, -1, axis=0), depth, np.roll(depth, -1), strict=True
    ):
        if d0 > 0.05 and d1 > 0.05 and (v0 - row) * (v1 - row) <= 0 and v0 != v1:
            u = u0 + (row - v0) / (v1 - v0) * (u1 - u0)
            if 0 <= u < camera.width:
                crossings.append(u)
    if len(crossings) != 1:
        return None
    return (crossings[0] - camera.width / 2) / (camera.width / 2)


def quaternion(r):
    """(x, y, z, w) of a proper rotation matrix."""
    w = math.sqrt(max(0.0, 1.0 + np.trace(r))) / 2.0
    x = math.copysign(math.sqrt(max(0.0, 1 + r[0, 0] - r[1, 1] - r[2, 2])) / 2, r[2, 1] - r[1, 2])
    y = math.copysign(math.sqrt(max(0.0, 1 - r[0, 0] + r[1, 1] - r[2, 2])) / 2, r[0, 2] - r[2, 0])
    z = math.copysign(math.sqrt(max(0.0, 1 - r[0, 0] - r[1, 1] + r[2, 2])) / 2, r[1, 0] - r[0, 1])
    return x, y, z, w


def write_lap_bag(path, renderer, poses, light=None, compressed=False):
    """The frames at `poses` as a robot's recording: camera frames (raw bgr8, or JPEG with
    the raspicam's "jpg" format string), camera_info, tf_static and the cmd_vel that drove
    the robot from pose to pose, and /odom saying it did."""
    camera = renderer.camera
    info_fields = camera.camera_info_dict()
    with rosbag.Bag(str(path), "w") as bag:
        mount = TransformStamped()
        mount.header.frame_id, mount.child_frame_id = "base_footprint", camera.frame_id
        mount.header.stamp = rospy.Time.from_sec(1.0)
        mount.transform.translation.x = camera.x_offset_m
        mount.transform.translation.z = camera.height_m
        (q := mount.transform.rotation).x, q.y, q.z, q.w = quaternion(camera.base_to_optical())
        bag.write("/tf_static", TFMessage([mount]), mount.header.stamp)
        for i, pose in enumerate(poses):
            stamp = rospy.Time.from_sec(1.0 + i / RATE_HZ)
            nxt = poses[(i + 1) % len(poses)]
            command = Twist()
            command.linear.x = math.dist(pose[:2], nxt[:2]) * RATE_HZ
            command.angular.z = math.remainder(nxt[2] - pose[2], math.tau) * RATE_HZ
            # Blurred by that motion over the exposure (a realism's exposure_time).
            frame = renderer.render(pose, frame=i, motion=(command.linear.x, command.angular.z))
            if light is not None:  # (frame, index) -> the frame as another light shows it
                frame = np.clip(light(frame, i), 0, 255).astype(np.uint8)
            if compressed:
                msg = CompressedImage(format="jpg")
                msg.data = cv2_jpeg(frame)
            else:
                msg = Image(height=frame.shape[0], width=frame.shape[1], encoding="bgr8")
                msg.step, msg.data = frame.shape[1] * 3, frame.tobytes()
            msg.header.stamp, msg.header.frame_id = stamp, camera.frame_id
            topic = "camera/rgb/image_raw" + ("/compressed" if compressed else "")
            bag.write(topic, msg, stamp)
            info = CameraInfo(**{k: v for k, v in info_fields.items() if k != "frame_id"})
            info.header = msg.header
            bag.write("camera/rgb/camera_info", info, stamp)
            bag.write("/cmd_vel", command, stamp)
            odom = Odometry()
            odom.header.stamp, odom.twist.twist = stamp, command
            bag.write("/odom", odom, stamp)


def cv2_jpeg(frame):
    import cv2

    ok, data = cv2.imencode(".jpg", frame, [cv2.IMWRITE_JPEG_QUALITY, 90])
    assert ok
    return data.tobytes()


def make_lap(profile):
    """The renderer (clean with noise, or a harness realism profile: harsh's ranges drawn from
    HARSH_SEED, its barrel lens on the camera), the lap's poses and each frame's truth
    (band_truth)."""
    world = load_world(WORLDS_DIR / "course.yaml")
    if profile == "clean":
        renderer = Renderer(world, noise_sigma=3.0)
    else:
        seed = HARSH_SEED if profile == "harsh" else None  # None: the world's noise seed
        realism = realism_from(PROFILES[profile], seed=seed or 0)
        lens = barrel_distortion(realism.barrel) if realism.barrel else world.camera.distortion
        camera = replace(world.camera, distortion=lens)
        renderer = Renderer(world, camera, noise_sigma=0.0, realism=realism, seed=seed)
    poses = lap_poses(world)
    camera = renderer.camera
    geometry = core.CameraGeometry(
        fx=camera.fx, fy=camera.fy, cx=camera.cx, cy=camera.cy, height_m=camera.height_m,
        pitch_rad=camera.pitch, x_offset_m=camera.x_offset_m,
    )  # fmt: skip
    placed = core.place_band(geometry, core.LineDetectorConfig().band, camera.height)
    rows = (placed.row_begin, placed.row_end)
    truth = [band_truth(camera, world.centreline(0), pose, rows) for pose in poses]
    return renderer, poses, truth


@pytest.fixture(scope="module")
def lap():
    return make_lap("clean")


def inspect(bag, out, *options):
    """The doctor as a user runs it (the venv's python, which has OpenCV and matplotlib)."""
    run = subprocess.run(
        [sys.executable, "-m", "follow_bot.bag_doctor", str(bag), "--out", str(out), *options],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert run.returncode == 0, run.stdout + run.stderr
    return json.loads((out / "report.json").read_text()), run.stdout


def compare(records, truth):
    """(frames where found == line in the band, |position error| of frames both see)."""
    agree = sum(r["found"] == (t is not None) for r, t in zip(records, truth, strict=True))
    errors = [
        abs(r["position"] - t)
        for r, t in zip(records, truth, strict=True)
        if r["found"] and t is not None
    ]
    return agree, np.array(errors)


# Per lap: frames the doctor may miss where the line crosses the band, and bounds on
# |position - truth| over the frames both see (median, 95th percentile, largest), from the
# measured figures in docs/results.md. The centroid of the band's pixels vs the centreline at
# its middle row: a 5 cm line over 20 rows, within 2 % of the half width (6 px) on every frame
# of the clean and realistic laps.
LAP_BOUNDS = {
    "clean": (2, 0.01, 0.02, 0.02),
    "realistic": (2, 0.01, 0.02, 0.02),
    # HARSH_SEED's draw: a bluish shadow band drifts along the line over frames 7-17; in it
    # the floor test (floor_margin) rejects the line, a lit floor's yellowness in the band
    # beside it (12 frames lost; found without the test, below). As a shadow's edge leaves
    # the line, only its lit part counts (two frames off by 0.06-0.07, under a line width).
    "harsh": (13, 0.01, 0.01, 0.1),
}


@pytest.mark.parametrize("profile", LAP_BOUNDS)
def test_lap_report_matches_the_renderer(profile, tmp_path):
    # realistic: tiles, shadows, walls, yellow tape and a yellow box near the line, white
    # balance and exposure drift, vignetting, motion blur, JPEG 60 (harness/realism.py);
    # harsh: all of them stronger, a wood floor near the line's hue, drifting tinted shadows
    # and a barrel lens (the harness drops frames of a run too: a recording has none).
    renderer, poses, truth = make_lap(profile)
    bag = tmp_path / "lap.bag"
    write_lap_bag(bag, renderer, poses, compressed=profile != "clean")
    report, stdout = inspect(bag, tmp_path / "report", "--fit-colours")
    records = report["records"]
    assert report["frames"] == len(poses) == len(records)
    assert report["image_topic"].startswith("camera/rgb/image_raw")
    # The mounting from tf_static: the world's camera (0.30 m up, 20 deg down).
    mounting = report["camera"]
    assert mounting["mounting"] == "tf_static"
    assert mounting["height_m"] == pytest.approx(renderer.camera.height_m, abs=1e-6)
    assert mounting["pitch_deg"] == pytest.approx(math.degrees(renderer.camera.pitch), abs=0.01)
    visible = sum(t is not None for t in truth)
    agree, errors = compare(records, truth)
    print(f"lap, {profile}: {len(poses)} frames, line in the band {visible}, doctor found "
          f"{sum(r['found'] for r in records)}, agree {agree}, |position - truth| median "
          f"{np.median(errors):.4f} p95 {np.percentile(errors, 95):.4f} max "
          f"{errors.max():.4f}")  # fmt: skip
    missed, median, p95, largest = LAP_BOUNDS[profile]
    assert visible >= 0.9 * len(poses)
    assert agree >= len(poses) - missed
    assert report["detection_rate"] == pytest.approx(visible / len(poses), abs=missed / len(poses))
    assert np.median(errors) < median and np.percentile(errors, 95) < p95
    assert errors.max() < largest
    # The bag's commands (the weave) against the core's: every frame after the first command.
    assert report["commands"]["frames_with_a_bag_command"] == len(poses) - 1
    assert report["applied_from"] == "/odom"
    assert all("core_w" in r and "bag_w" in r for r in records[1:])
    for name in ("timeline.png", "worst_frames.png"):
        assert (tmp_path / "report" / name).stat().st_size > 10_000
    assert "detection rate" in stdout
    # The colours fitted to a lap the default band reads: no frame lost (a shadow band darkens
    # the line in three of the realistic lap's frames: the value bound keeps them). The harsh
    # lap's lost frames fail the floor test, not the band: the fit neither finds nor loses any.
    fit = report["fit"]
    print(f"fit: {fit['parameters']}, detection rate {fit['detection_rate_after']}")
    assert fit["detection_rate_after"] == report["detection_rate"] and fit["better"]
    if profile == "harsh":
        # Without the floor test (--params floor_margin: 0) the shadowed line is found; measured:
        # 91 of 93 frames, 90 within 0.025 of the centreline (the last on another blob, 0.33).
        (tmp_path / "no_floor_test.yaml").write_text("floor_margin: 0\n")
        bare, _ = inspect(bag, tmp_path / "bare", "--params", tmp_path / "no_floor_test.yaml")
        _, bare_errors = compare(bare["records"], truth)
        assert bare["detection_rate"] >= 90 / len(poses)
        assert (bare_errors < 0.03).sum() >= 89


def test_fit_colours_finds_the_line_under_a_colour_cast(lap, tmp_path):
    renderer, poses, truth = lap
    bag = tmp_path / "cast.bag"
    write_lap_bag(bag, renderer, poses, light=lambda frame, _: frame * CAST, compressed=True)
    report, stdout = inspect(bag, tmp_path / "report", "--fit-colours")
    fit = report["fit"]
    print(f"cast: detection rate {fit['detection_rate_before']} -> "
          f"{fit['detection_rate_after']}, fitted {fit['parameters']}")  # fmt: skip
    assert report["image_type"] == "sensor_msgs/CompressedImage"
    assert fit["detection_rate_before"] < 0.2  # the default band (hue 20-40) misses the line
    assert fit["better"]
    visible = sum(t is not None for t in truth) / len(poses)
    assert fit["detection_rate_after"] >= visible - 2 / len(poses)
    params = yaml.safe_load((tmp_path / "report" / "fitted_params.yaml").read_text())
    assert params == fit["parameters"]
    assert set(params) == {"h_min", "h_max", "s_min", "s_max", "v_min", "v_max"}
    # The cast line's hue (~45) inside the band, the grey floor's (~90) outside.
    assert params["h_min"] <= 45 <= params["h_max"] < 80
    # The fitted band's sightings are where the renderer put the line.
    config = bag_doctor.detector_config_with(core, params)
    assert config.lower.h == params["h_min"]
    fitted_file = tmp_path / "report" / "fitted_params.yaml"
    refit, _ = inspect(bag, tmp_path / "refit", "--params", str(fitted_file))
    agree, errors = compare(refit["records"], truth)
    assert refit["detection_rate"] == fit["detection_rate_after"]
    assert agree >= len(poses) - 2 and errors.max() < 0.02
    assert "->" in stdout
    # follower.launch takes the file as it is (params:=).
    dump = subprocess.run(
        ["roslaunch", "--dump-params", "follow_bot", "follower.launch", f"params:={fitted_file}",
         "robot_description:=false"], capture_output=True, text=True, timeout=60, check=True,
    )  # fmt: skip
    assert yaml.safe_load(dump.stdout)["/follower/h_min"] == params["h_min"]


# The real photographs with a colour cast (../shared/realdata/line_colour_cast, 1080x810, no
# calibration: the band lands on rows ~612-632), labelled by looking at rows 592-652: the yellow
# dash's columns there, or None where no line crosses the band.
CAST_PHOTOS = {
    "pic1_smaller": (55, 125),  # warm cast; the dash ends inside the band
    "pic2_smaller": (65, 170),  # warm cast
    "pic4_smaller": (0, 100),
    "pic5_smaller": None,  # cool cast; the centre line is far ahead, above the band
}


def test_fit_colours_keeps_the_real_line(realdata, tmp_path):
    # Frames the default band already reads: the fit must not lose them or find a line where
    # there is none.
    bag = tmp_path / "photos.bag"
    with rosbag.Bag(str(bag), "w") as out:
        for i, name in enumerate(CAST_PHOTOS):
            msg = CompressedImage(format="jpeg")
            msg.data = (realdata / "line_colour_cast" / f"{name}.jpg").read_bytes()
            msg.header.stamp = rospy.Time.from_sec(1.0 + i / 5)
            out.write("/raspicam_node/image/compressed", msg, msg.header.stamp)
    report, _ = inspect(bag, tmp_path / "report", "--fit-colours")
    fitted_file = tmp_path / "report" / "fitted_params.yaml"
    refit, _ = inspect(bag, tmp_path / "refit", "--params", str(fitted_file))
    fit = report["fit"]
    print(f"photos: detection rate {fit['detection_rate_before']} -> "
          f"{fit['detection_rate_after']}, fitted {fit['parameters']}")  # fmt: skip
    assert fit["detection_rate_before"] == fit["detection_rate_after"] == 0.75
    for replayed in (report, refit):
        for record, label in zip(replayed["records"], CAST_PHOTOS.values(), strict=True):
            assert record["found"] == (label is not None)
            if label:
                assert label[0] <= 540 * (1 + record["position"]) <= label[1]


def test_real_raspicam_bags_decode_and_report(realdata, tmp_path):
    bags = sorted((realdata / "raspicam_bags").glob("*.bag"))
    assert len(bags) == 3
    runs = [(bag, "follower") for bag in bags] + [(bags[0], "beacons"), (bags[0], "parker")]
    for bag, behaviour in runs:
        out = tmp_path / f"{bag.stem}_{behaviour}"
        report = bag_doctor.inspect(bag, out, behaviour)  # in this process: 5 runs, 1 import
        # One 1280-wide frame each, decoded ("jpg"), with its own calibration.
        assert report["frames"] == 1 and report["undecodable_frames"] == {}
        assert report["image_type"] == "sensor_msgs/CompressedImage"
        assert report["camera_info"] is not None and report["camera"]["fx"] > 900
        # ArUco markers on a desk: no line, no beacon, no AprilTag in any of them.
        assert report["detection_rate"] == 0.0
        assert (out / "worst_frames.png").is_file() and (out / "timeline.png").is_file()


def test_help_and_missing_libraries_under_debian_python(tmp_path):
    # A product tool: the harness depends on follow_bot, never the reverse.
    tree = ast.parse(Path(bag_doctor.__file__).read_text())
    imported = {a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
    imported |= {n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)}
    assert not any(name.split(".")[0] == "harness" for name in imported)
    script = ["/usr/bin/python3", "-m", "follow_bot.bag_doctor"]
    help_run = subprocess.run([*script, "--help"], capture_output=True, text=True, timeout=60)
    assert help_run.returncode == 0 and "--fit-colours" in help_run.stdout
    probe = ["/usr/bin/python3", "-c", "import cv2, matplotlib"]
    has_cv2 = subprocess.run(probe, capture_output=True).returncode == 0
    if has_cv2:
        pytest.skip("Debian's python3 has OpenCV and matplotlib: nothing is missing")
    run = subprocess.run([*script, str(tmp_path / "x.bag")], capture_output=True, text=True)
    assert run.returncode == 1 and "python3-opencv" in run.stderr


# A veiling glare (a window ahead, a milky lens) over the beacons' drive: each frame mixed with
# a light grey, more and more, from VEIL[0] to VEIL[1] of it. The green ball washes out below
# the default s_min (100) after 13 of the 30 frames.
VEIL = (0.4, 0.75)
VEIL_GREY = 170.0


def test_fit_colours_finds_the_beacons_in_a_glare(tmp_path):
    world = load_world(WORLDS_DIR / "green_red.yaml")
    renderer = Renderer(world, noise_sigma=3.0)
    # Toward the green ball (4 m ahead) from 3 m off, weaving +-0.25 rad.
    poses = [(x, 0.0, 0.25 * math.sin(x * 2.5)) for x in np.arange(0.0, 3.0, 0.1)]
    veils = np.linspace(*VEIL, len(poses))
    bag = tmp_path / "glare.bag"
    write_lap_bag(
        bag, renderer, poses, lambda frame, i: frame * (1 - veils[i]) + veils[i] * VEIL_GREY
    )
    # Truth: the green ball's silhouette centre (renderer), its whole silhouette in the frame.
    camera, truth = renderer.camera, []
    for pose in poses:
        (green,) = (p for p in renderer.object_projections(pose) if p["name"] == "green")
        centre = green.get("blob_centre_px")
        radius = camera.fx * 0.2 / max(green["depth"], 1e-6)
        inside = centre is not None and radius <= centre[0] < camera.width - radius
        truth.append((centre[0] - camera.width / 2) / (camera.width / 2) if inside else None)
    assert all(t is not None for t in truth)
    report, stdout = inspect(bag, tmp_path / "report", "--behaviour", "beacons", "--fit-colours")
    fit = report["fit"]
    fitted_file = tmp_path / "report" / "fitted_params.yaml"
    params = yaml.safe_load(fitted_file.read_text())
    assert params == fit["parameters"] and set(params) == {"sensitivity", "s_min", "v_min"}
    refit, _ = inspect(bag, tmp_path / "refit", "--behaviour", "beacons", "--params", fitted_file)
    found, errors = compare(refit["records"], truth)
    print(f"glare: detection rate {fit['detection_rate_before']} -> "
          f"{fit['detection_rate_after']}, fitted {params}; |position - truth| median "
          f"{np.median(errors):.4f} max {errors.max():.4f}")  # fmt: skip
    # Measured: 13 -> 30 of 30 frames (sensitivity 5, s_min 39, v_min 141: the glare lifts
    # every pixel's value).
    assert fit["detection_rate_before"] < 0.5 and fit["better"]
    assert fit["detection_rate_after"] >= 1 - 1.5 / len(poses)
    assert refit["detection_rate"] == fit["detection_rate_after"]
    # Every fitted sighting is the green ball, its centroid on the silhouette's centre.
    assert found == sum(r["found"] for r in refit["records"])
    assert np.median(errors) < 0.01 and errors.max() < 0.02
    assert "->" in stdout
    # beacon_chaser.launch takes the file as it is (params:=).
    dump = subprocess.run(
        ["roslaunch", "--dump-params", "follow_bot", "beacon_chaser.launch",
         f"params:={fitted_file}", "robot_description:=false"],
        capture_output=True, text=True, timeout=60, check=True,
    )  # fmt: skip
    assert yaml.safe_load(dump.stdout)["/beacon_chaser/s_min"] == params["s_min"]


def test_params_reach_the_cores_as_the_nodelets_map_them(tmp_path):
    # Values the defaults do not have, under the .cfg's names (cfg/Follower.cfg).
    params = {"mode": "pd", "max_linear": 0.45, "kp": 2.5, "curvature_taper": 0.9,
              "search_rate": 0.4, "heading_gain": 12.0, "command_latency": 0.2,
              "line_width": 0.08, "look_ahead": True, "h_max": 36}  # fmt: skip
    steering = bag_doctor.steering_config_with(core, params)
    assert steering.mode == core.SteeringMode.pd
    assert (steering.max_linear, steering.pd.kp, steering.pd.curvature_taper) == (0.45, 2.5, 0.9)
    assert (steering.search.search_rate, steering.path.heading_gain) == (0.4, 12.0)
    assert steering.path.command_latency == 0.2
    detector = bag_doctor.detector_config_with(core, params)
    assert detector.line_width_m == 0.08 and detector.look_ahead_enabled
    assert detector.upper.h == 36
    # A parameter in degrees sets a field in radians.
    servo = bag_doctor.set_from_params(core.ParkingServoConfig(), {"max_bearing_deg": 10.0})
    assert servo.max_bearing_rad == pytest.approx(math.radians(10.0), abs=1e-15)
    # A name no replay applies is refused, naming it.
    path = tmp_path / "params.yaml"
    path.write_text("kp: 2.0\nestimate_latency: false\nstandoff: 0.5\n")
    with pytest.raises(ValueError, match="estimate_latency, standoff"):
        bag_doctor.load_params(path, "follower")
