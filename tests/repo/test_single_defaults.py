"""Each parameter default is written once, in its .cfg: launch files and config YAML leave a
parameter unset (an empty arg) rather than repeat its default, and the cores whose Config
structs take their defaults from the generated <Name>Defaults.h (generate_cfg_defaults) hold no
literal initialisers of their own."""

import re
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
import yaml

from harness.testing import REPO

sys.path.insert(0, str(REPO / "follow_bot_common" / "cmake"))
from cfg_defaults import read_cfg

CFGS = sorted(p for p in REPO.glob("*/cfg/*.cfg"))
# Cores whose defaults come from a generated header, by the .cfg they come from.
GENERATED = {
    "follow_bot/cfg/BeaconChaser.cfg": [
        "follow_bot/include/follow_bot/beacon_controller.h",
        "follow_bot/include/follow_bot/colour_blobs.h",
    ],
    "follow_bot/cfg/Follower.cfg": [
        "follow_bot/include/follow_bot/line_detector.h",
        "follow_bot/include/follow_bot/steering_law.h",
    ],
    "follow_bot/cfg/Parker.cfg": ["follow_bot/include/follow_bot/parking_servo.h"],
    "follow_bot/cfg/Panorama.cfg": [
        "follow_bot/include/follow_bot/panorama_capture.h",
        "follow_bot/include/follow_bot/panorama_session.h",
    ],
    "image_converter/cfg/Matching.cfg": [
        "image_converter/include/image_converter/feature_matching.h"
    ],
}
# Core fields that hold a .cfg parameter under another name (or type): header -> field -> the
# <Name>Defaults member its initialiser must name.
RENAMED = {
    "follow_bot/include/follow_bot/colour_blobs.h": {
        "sensitivity": "BeaconChaserDefaults::sensitivity",
        "s_min": "BeaconChaserDefaults::s_min",
        "v_min": "BeaconChaserDefaults::v_min",
    },
    "follow_bot/include/follow_bot/steering_law.h": {"mode": "FollowerDefaults::mode"},
    "follow_bot/include/follow_bot/tag_detector.h": {
        "family": "ParkerDefaults::tag_family",
        "id": "ParkerDefaults::tag_id",
        "size_m": "ParkerDefaults::tag_size",
        "quad_decimate": "ParkerDefaults::quad_decimate",
        "full_resolution_below": "ParkerDefaults::full_resolution_below",
        "min_decision_margin": "ParkerDefaults::min_decision_margin",
        "max_hamming": "ParkerDefaults::max_hamming",
    },
    "follow_bot/include/follow_bot/sign_detector.h": {
        "image_path": "ParkerDefaults::sign_image",
        "width_m": "ParkerDefaults::sign_width",
    },
    "image_converter/include/image_converter/overlay.h": {
        "radius_px": "ImageConverterDefaults::circle_radius",
        "thickness_px": "ImageConverterDefaults::circle_thickness",
    },
    "follow_bot_common/include/follow_bot_common/velocity_limiter.h": {
        "max_linear": "CommandOutputDefaults::limit_linear",
        "max_angular": "CommandOutputDefaults::limit_angular",
        "max_linear_accel": "CommandOutputDefaults::limit_linear_accel",
        "max_angular_accel": "CommandOutputDefaults::limit_angular_accel",
    },
}
# A ~param read with a fallback in C++ (param, checkedParam, positiveParam) or Python
# (rospy.get_param): its name and the fallback's text.
PARAM_FALLBACK = re.compile(
    r"""(?:[pP]aram(?:<[\w:]+>)?|get_param)\(\s*(?:\w+,\s*)?"~?(\w+)",\s*([^,)]+)"""
)

CONFIG_STRUCT = re.compile(r"^struct \w*(?:Config|Options) \{\n(.*?)^\};", re.M | re.S)
LITERAL_INITIALISER = re.compile(
    r"^\s*(?:double|float|int|bool|std::string)\s+(\w+)\s*=\s*"
    r"(?:-?[\d.]+(?:e-?\d+)?|true|false|\".*\")\s*;",
    re.M,
)

LITERAL_VALUE = re.compile(
    r"^\s*(?:double|float|int|bool|std::string)\s+(?P<name>\w+)\s*=\s*"
    r"(?P<value>-?[\d.]+(?:e-?\d+)?|true|false|\".*\")\s*;"
)


def same(text: str, default) -> bool:
    if isinstance(default, bool):
        return text.strip().lower() == str(default).lower()
    if isinstance(default, int | float):
        try:
            return float(text) == float(default)
        except ValueError:
            return False
    return text == default


def defaults() -> dict[str, object]:
    found = {}
    for cfg in CFGS:
        for param in read_cfg(cfg):
            found.setdefault(param["name"], []).append(param["default"])
    return found


def repeated_in_launch(path: Path, known: dict) -> list[str]:
    repeats = []
    for element in ET.parse(path).getroot().iter():
        name = element.get("name")
        value = element.get("default") if element.tag == "arg" else element.get("value")
        if element.tag not in ("arg", "param") or name not in known or value in (None, ""):
            continue
        if "$(" not in value and any(same(value, d) for d in known[name]):
            repeats.append(f"{path.relative_to(REPO)}: {name}={value}")
    return repeats


def test_launch_files_and_yaml_do_not_repeat_cfg_defaults():
    known = defaults()
    repeats = []
    for path in sorted(REPO.glob("*/launch/*.launch")):
        repeats += repeated_in_launch(path, known)
    for path in sorted(REPO.glob("*/config/*.yaml")):
        for name, value in (yaml.safe_load(path.read_text()) or {}).items():
            if name in known and any(same(str(value), d) for d in known[name]):
                repeats.append(f"{path.relative_to(REPO)}: {name}={value}")
    assert repeats == []


@pytest.mark.parametrize("cfg", sorted(GENERATED))
def test_generated_cores_hold_no_literal_defaults(cfg):
    """A Config member named as a .cfg parameter takes the generated default, not a literal."""
    names = {param["name"] for param in read_cfg(REPO / cfg)}
    for header in GENERATED[cfg]:
        text = (REPO / header).read_text()
        assert f"{Path(cfg).stem}Defaults" in text, header
        members = [
            m for body in CONFIG_STRUCT.findall(text) for m in LITERAL_INITIALISER.findall(body)
        ]
        assert [m for m in members if m in names] == [], header


@pytest.mark.parametrize("header", sorted(RENAMED))
def test_renamed_core_fields_take_the_generated_default(header):
    """A core field holding a .cfg parameter under another name is initialised from the
    generated header, e.g. `double width_m = ParkerDefaults::sign_width;`."""
    text = (REPO / header).read_text()
    for field, default in RENAMED[header].items():
        initialiser = re.search(rf"^\s*[\w:<>]+\s+{field}\s*=\s*([^;]+);", text, re.M)
        assert initialiser, f"{header}: no initialiser of {field}"
        assert default in initialiser[1], f"{header}: {field} = {initialiser[1]}"


def test_no_core_config_repeats_a_cfg_default_under_its_name():
    """Whatever the package: a Config or Options member named as a .cfg parameter, with that
    parameter's default as a literal, writes the default a second time (MatchOptions'
    `int min_inliers = 25;` next to a .cfg's min_inliers 25)."""
    known = defaults()
    repeats = []
    for header in sorted(REPO.glob("*/include/**/*.h")):
        for body in CONFIG_STRUCT.findall(header.read_text()):
            for line in body.splitlines():
                initialiser = LITERAL_VALUE.match(line)
                if not initialiser or initialiser["name"] not in known:
                    continue
                value = initialiser["value"].strip('"')
                if any(same(value, d) for d in known[initialiser["name"]]):
                    repeats.append(f"{header.relative_to(REPO)}: {line.strip()}")
    assert repeats == []


def test_code_reads_no_cfg_parameter_with_a_literal_fallback():
    """Reading a .cfg parameter with a literal fallback (`positiveParam(pnh, "watchdog_timeout",
    0.15)`, `rospy.get_param("~watchdog_timeout", 0.15)`) writes its default a second time."""
    known = defaults()
    sources = [
        path
        for pattern in ("*/src/**/*.cpp", "*/include/**/*.h", "*/python/**/*.py", "*/scripts/*.py")
        for path in REPO.glob(pattern)
    ]
    repeats = [
        f"{path.relative_to(REPO)}: {name} = {fallback.strip()}"
        for path in sorted(sources)
        for name, fallback in PARAM_FALLBACK.findall(path.read_text())
        if name in known and any(same(fallback.strip().strip('"'), d) for d in known[name])
    ]
    assert repeats == []
