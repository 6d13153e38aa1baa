"""Absurd ~params are a clear start-up error (exit 1, the parameter named), never a crash.

A value of the wrong type is never silently replaced by the default: the error names the ~param,
the expected type and its range. A ~param the node does not have (a misspelt name) is warned
about, with the nearest name it has; with ~strict_params it is a start-up error.
"""

import subprocess

import pytest

from harness.processes import WatchedProcess, private_master, stop


@pytest.fixture(scope="module")
def master_env():
    with private_master() as env:
        yield env


@pytest.mark.parametrize(
    ("node", "param", "words"),
    [
        ("follow_bot follower", "_kp:=-1", "kp"),
        ("follow_bot follower", "_h_min:=200", "~h_min must be in [0, 179], got 200"),
        (
            "follow_bot follower",
            "_kp:=abc",
            "~kp must be a finite number in [0, 20], got the string 'abc'",
        ),
        (
            "follow_bot follower",
            "_kp:=.nan",
            "~kp must be a finite number in [0, 20], got the string '.nan'",
        ),
        (
            "follow_bot follower",
            "_kp:=nan",
            "~kp must be a finite number in [0, 20], got the number nan",
        ),
        (
            "follow_bot follower",
            "_band_rows:=2.5",
            "~band_rows must be an integer in [1, 480], got the number 2.5",
        ),
        (
            "follow_bot follower",
            "_look_ahead:=maybe",
            "~look_ahead must be a bool (true or false), got the string 'maybe'",
        ),
        ("follow_bot follower", "_mode:=3", "~mode must be a string, got the integer 3"),
        (
            "follow_bot follower",
            "_use_odom:=1",
            "~use_odom must be a bool (true or false), got the integer 1",
        ),
        (
            "follow_bot follower",
            "_limit_linear:=abc",
            "~limit_linear must be a finite number > 0, got the string 'abc'",
        ),
        (
            "follow_bot follower",
            "_camera_height:=inf",
            "~camera_height must be a finite number > 0, got the number inf",
        ),
        (
            "follow_bot follower",
            "_camera_mounting:=urdf",
            "~camera_mounting must be 'tf' or 'params', got 'urdf'",
        ),
        (
            "follow_bot parker",
            "_camera_mounting:=1",
            "~camera_mounting must be a string, got the integer 1",
        ),
        ("follow_bot beacon_chaser", "_base_frame:=", "~base_frame must not be empty"),
        (
            "follow_bot panorama",
            "_mounting_timeout:=0",
            "~mounting_timeout must be > 0, got 0",
        ),
        ("follow_bot follower", "_mode:=fast", "~mode"),
        ("follow_bot follower", "_limit_linear:=0", "~limit_linear must be > 0"),
        ("follow_bot follower", "_watchdog_timeout:=-1", "~watchdog_timeout must be > 0"),
        ("follow_bot parker", "_wall_watchdog_timeout:=0", "~wall_watchdog_timeout must be > 0"),
        ("follow_bot follower", "_band_distance:=20", "~band_distance"),
        ("follow_bot beacon_chaser", "_sensitivity:=95", "sensitivity must be in [0, 90]"),
        ("follow_bot beacon_chaser", "_mode:=dance", "~mode must be"),
        ("follow_bot beacon_chaser", "_target_colour:=purple", "purple"),
        ("follow_bot beacon_chaser", "_min_area:=-1", "min_area"),
        ("follow_bot beacon_chaser", "_stop_distance:=0", "stop_distance"),
        ("follow_bot beacon_chaser", "_sensitivity:=-1", "sensitivity must be in [0, 90]"),
        ("follow_bot beacon_chaser", "_close_area:=-5", "close_area"),
        ("follow_bot beacon_chaser", "_stop_min_area:=-5", "stop_min_area"),
        ("follow_bot beacon_chaser", "_follow_colour:=yellow", "~follow_colour must be red"),
        ("follow_bot beacon_chaser", "_stop_colour:=green", "stop_colour must differ"),
        ("follow_bot beacon_chaser", "_target_shape:=cube", "~target_shape"),
        ("follow_bot beacon_chaser", "_target_size:=0", "~target_size must be > 0"),
        ("follow_bot beacon_chaser", "_turn_gain:=50", "~turn_gain must be in [0, 10], got 50"),
        (
            "follow_bot beacon_chaser",
            "_sensitivity:=abc",
            "~sensitivity must be an integer in [0, 90], got the string 'abc'",
        ),
        (
            "follow_bot beacon_chaser",
            "_stop_distance:=.nan",
            "~stop_distance must be a finite number",
        ),
        (
            "follow_bot beacon_chaser",
            "_target_size:=big",
            "~target_size must be a finite number > 0, got the string 'big'",
        ),
        ("follow_bot parker", "_tag_size:=0", "~tag_size must be in [0.001, 10], got 0"),
        (
            "follow_bot parker",
            "_tag_size:=abc",
            "~tag_size must be a finite number in [0.001, 10], got the string 'abc'",
        ),
        (
            "follow_bot parker",
            "_tag_id:=one",
            "~tag_id must be an integer in [0, 1000000], got the string 'one'",
        ),
        (
            "follow_bot parker",
            "_publish_tf:=banana",
            "~publish_tf must be a bool (true or false), got the string 'banana'",
        ),
        ("follow_bot parker", "_tag_size:=-0.3", "~tag_size must be in [0.001, 10], got -0.3"),
        ("follow_bot parker", "_target:=laser", "~target must be 'apriltag' or 'sign'"),
        ("follow_bot parker", "_tag_family:=tag99h1", "~tag_family must be one of tag36h11"),
        ("follow_bot parker", "_tag_id:=600", "~tag_id must be < 587 for tag36h11"),
        ("follow_bot parker", "_standoff:=0", "~standoff must be in [0.01, 10], got 0"),
        (
            "follow_bot parker",
            "_standoff:=0.2 _camera_x_offset:=0.2",
            "~standoff must exceed ~camera_x_offset + 0.05 m",
        ),
        ("follow_bot parker", "_search_rate:=9", "~search_rate must be in [-3.2, 3.2], got 9"),
        (
            "follow_bot parker",
            "_min_decision_margin:=-1",
            "~min_decision_margin must be in [0, 255], got -1",
        ),
        (
            "follow_bot parker",
            "_max_bearing_deg:=40",
            "~max_bearing_deg must be in [0, 28], got 40",
        ),
        ("follow_bot parker", "_target:=sign", "~sign_image must name"),
        ("follow_bot parker", "_target:=sign _sign_image:=/no/such.png", "~sign_image: "),
        ("follow_bot parker", "_target:=sign _sign_image:=/dev/null", "~sign_image: "),
        (
            "follow_bot parker",
            "_target:=sign _sign_width:=0",
            "~sign_width must be in [0.001, 10], got 0",
        ),
        ("follow_bot parker", "_camera_pitch_deg:=95", "~camera_pitch_deg must be within"),
        (
            "image_converter image_converter",
            "_circle_radius:=0",
            "~circle_radius must be in [1, 16384], got 0",
        ),
        (
            "image_converter image_converter",
            "_circle_radius:=2.5",
            "~circle_radius must be an integer in [1, 16384], got the number 2.5",
        ),
        (
            "image_converter image_converter",
            "_display:=banana",
            "~display must be a bool (true or false), got the string 'banana'",
        ),
        (
            "follow_bot panorama",
            "_max_angular:=abc",
            "~max_angular must be a finite number in [0.01, 10], got the string 'abc'",
        ),
        (
            "follow_bot panorama",
            "_return_to_start:=no",
            "~return_to_start must be a bool (true or false), got the string 'no'",
        ),
        ("image_converter image_converter", "_image_transport:=nope", "~image_transport 'nope'"),
        ("follow_bot panorama", "_stitch_method:=magic", "~stitch_method must be"),
        ("follow_bot panorama", "_detector:=surf", "~detector must be orb or sift"),
        (
            "follow_bot panorama",
            "_step_angle_deg:=0",
            "~step_angle_deg must be in [0.5, 359], got 0",
        ),
        (
            "follow_bot panorama",
            "_step_angle_deg:=200",
            "~step_angle_deg must be at most ~total_angle_deg, got 200 and 120",
        ),
        (
            "follow_bot panorama",
            "_min_angular:=1",
            "~min_angular must be at most ~max_angular, got 1 and 0.5",
        ),
        (
            "follow_bot panorama",
            "_yaw_tolerance_deg:=10",
            "~yaw_tolerance_deg must be below ~step_angle_deg / 2, got 10 and 20",
        ),
        ("follow_bot panorama", "_limit_angular:=0", "~limit_angular must be > 0, got 0"),
    ],
)
def test_bad_parameter_is_a_named_startup_error(master_env, node, param, words, request):
    # A node name of its own: private params set by `_x:=` stay on the master after a run.
    name = f"__name:=case{abs(hash(request.node.name))}"
    result = subprocess.run(
        ["rosrun", *node.split(), *param.split(), name],
        env=master_env, capture_output=True, text=True, timeout=60,
    )  # fmt: skip
    assert result.returncode == 1, result.stdout + result.stderr
    assert words in result.stdout + result.stderr


def test_a_nodelet_that_fails_to_load_in_a_manager_logs_why(master_env):
    # A nodelet manager itself only reports "Failed to load nodelet" to the loader.
    manager = subprocess.Popen(
        ["rosrun", "nodelet", "nodelet", "manager", "__name:=params_manager"],
        env=master_env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
    )  # fmt: skip
    try:
        load = subprocess.run(
            ["rosrun", "nodelet", "nodelet", "load", "follow_bot/FollowerNodelet",
             "params_manager", "__name:=params_follower", "_kp:=abc"],
            env=master_env, capture_output=True, text=True, timeout=60,
        )  # fmt: skip
        assert "Failed to load nodelet" in load.stdout + load.stderr
    finally:
        stop(manager)
    log = manager.stdout.read()
    assert (
        "/params_follower cannot start: ~kp must be a finite number in [0, 20], "
        "got the string 'abc'" in log
    ), log


# (node, a misspelt ~param, the name it should suggest). The tester's own misspellings first:
# none is one typo from a name the node has, so nothing is suggested.
MISSPELT = [
    ("follow_bot follower", "band_top_fraction", None),
    ("follow_bot beacon_chaser", "max_speed", None),
    ("follow_bot panorama", "turn_rate", None),
    ("follow_bot follower", "max_liner", "max_linear"),
    ("follow_bot follower", "watchdog_timout", "watchdog_timeout"),  # CommandOutput's
    ("follow_bot beacon_chaser", "turn_gian", "turn_gain"),
    ("follow_bot beacon_chaser", "target_sise", "target_size"),  # read at start-up only
    ("follow_bot parker", "tag_sise", "tag_size"),
    ("follow_bot parker", "camera_heigth", "camera_height"),  # the mounting's
    ("follow_bot panorama", "min_inlier", "min_inliers"),  # image_converter's Matching.cfg
    ("image_converter image_converter", "circle_radus", "circle_radius"),
]


def unknown_warning(param: str, nearest: str | None) -> str:
    suggestion = f"; did you mean ~{nearest}?" if nearest else ""
    return f"~{param} is not a parameter of this node{suggestion}"


@pytest.mark.parametrize(("node", "param", "nearest"), MISSPELT)
def test_a_misspelt_parameter_is_warned_with_the_nearest_name(master_env, node, param, nearest):
    args = ["rosrun", *node.split(), f"_{param}:=5", f"__name:=unknown_{param}"]
    process = WatchedProcess(args, master_env)
    try:
        warned = process.wait_for(unknown_warning(param, nearest) + " (ignored)", 60.0)
        running = process.process.poll() is None
    finally:
        stop(process.process)
    assert warned and running, process.output()
    assert "WARN" in process.output()


@pytest.mark.parametrize(("node", "param", "nearest"), MISSPELT)
def test_strict_params_makes_a_misspelt_parameter_a_startup_error(master_env, node, param, nearest):
    result = subprocess.run(
        ["rosrun", *node.split(), f"_{param}:=5", "_strict_params:=true",
         f"__name:=strict_{param}"],
        env=master_env, capture_output=True, text=True, timeout=60,
    )  # fmt: skip
    out = result.stdout + result.stderr
    assert result.returncode == 1, out
    assert f"cannot start: {unknown_warning(param, nearest)} (~strict_params is true)" in out, out


# Every documented ~param of each node (its manual's tables and follow_bot_common's), set at once:
# none may be taken for unknown.
COMMON = [
    "_camera_mounting:=params", "_base_frame:=base_link", "_mounting_timeout:=5",
    "_camera_height:=0.3", "_camera_pitch_deg:=20", "_camera_x_offset:=0",
    "_image_rectified:=false", "_image_transport:=raw", "_diagnostic_period:=1",
    "_limit_linear:=0.7", "_limit_angular:=3", "_limit_linear_accel:=1",
    "_limit_angular_accel:=6", "_watchdog_timeout:=0.15", "_wall_watchdog_timeout:=0.15",
    "_expected_frame_rate:=30",
]  # fmt: skip
KNOWN = {
    "follow_bot follower": [*COMMON, "_use_odom:=false", "_kp:=1.5", "_mode:=pd"],
    "follow_bot beacon_chaser": [*COMMON, "_target_shape:=box", "_target_size:=1.8"],
    "follow_bot parker": [*COMMON, "_tag_size:=0.2", "_target:=apriltag"],
    "follow_bot panorama": [*COMMON, "_detector:=orb", "_step_angle_deg:=20"],
    "image_converter image_converter": [
        "_image_transport:=raw",
        "_circle_radius:=10",
        "_diagnostic_period:=1",
    ],
}


@pytest.mark.parametrize("node", KNOWN)
def test_every_documented_parameter_is_known(master_env, node):
    # _started_probe, the one unknown, says when the check is over (its warning).
    name = f"known_{node.split()[1]}"
    args = ["rosrun", *node.split(), *KNOWN[node], "_started_probe:=1", f"__name:={name}"]
    process = WatchedProcess(args, master_env)
    try:
        checked = process.wait_for(unknown_warning("started_probe", None), 60.0)
    finally:
        stop(process.process)
    warnings = [line for line in process.output().splitlines() if "is not a parameter" in line]
    assert checked and len(warnings) == 1, process.output()
