"""Packaging: catkin_lint -W2 finds nothing, every launch file documents its arguments
(`roslaunch --ros-args` shows each one's doc=), and every dependency a package.xml names is a
rosdep key (so `rosdep install --from-paths . --ignore-src` resolves it). roslaunch's file check
runs in catkin's run_tests (roslaunch_add_file_check in each package's CMakeLists.txt). The
product packages never need the harness."""

import re
import subprocess
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from harness.testing import REPO

LAUNCH_FILES = sorted(p for p in REPO.glob("*/**/*.launch") if ".venv" not in p.parts)
MANIFESTS = sorted(REPO.glob("*/package.xml"))
# Where Debian installs the manifests of its ROS packages (ros-*, lib*-dev): /usr/share/<name>/.
SYSTEM_MANIFESTS = Path("/usr/share")
# System keys that no installed ROS package depends on, checked by hand: visp and apriltag are
# rosdep keys (the library's Debian packages libvisp-dev and libapriltag-dev are not);
# pybind11-dev, python3-dev, python3-opencv and python3-matplotlib are rosdep/base.yaml and
# python.yaml keys of ros/rosdistro.
# The other system keys are ones a ROS package Debian ships depends on itself (cv_bridge on
# libopencv-dev, boost, python3-numpy, ...): keys its rosdep resolves by construction.
SYSTEM_KEYS = {
    "apriltag", "visp", "pybind11-dev", "python3-dev", "python3-opencv", "python3-matplotlib",
}  # fmt: skip


@pytest.mark.parametrize("path", LAUNCH_FILES, ids=lambda p: str(p.relative_to(REPO)))
def test_every_declared_arg_has_a_doc(path):
    # Declared arguments are the <launch>'s own; an <include>'s <arg> passes a value on.
    declared = ET.parse(path).getroot().findall("arg")
    undocumented = [a.get("name") for a in declared if not a.get("doc")]
    assert undocumented == []


def test_launch_files_are_found():
    assert len(LAUNCH_FILES) >= 12


def test_catkin_lint_is_clean():
    lint = subprocess.run(
        ["catkin_lint", "-W2", str(REPO)], capture_output=True, text=True, timeout=120
    )
    out = lint.stdout + lint.stderr
    assert lint.returncode == 0, out
    assert "checked 7 packages and found 0 problems" in out, out


def dependencies(manifest: Path) -> set[str]:
    root = ET.parse(manifest).getroot()
    return {element.text.strip() for element in root if element.tag.endswith("depend")}


def test_every_dependency_is_a_rosdep_key():
    ours = {manifest.parent.name for manifest in MANIFESTS}
    installed = {m.parent.name for m in SYSTEM_MANIFESTS.glob("*/package.xml")}
    keys_of_installed = set().union(
        *(dependencies(m) for m in SYSTEM_MANIFESTS.glob("*/package.xml"))
    )
    known = ours | installed | keys_of_installed | SYSTEM_KEYS
    unknown = {
        f"{manifest.parent.name}: {key}"
        for manifest in MANIFESTS
        for key in dependencies(manifest) - known
    }
    assert unknown == set()
    # The names the tester's rosdep refused: Debian packages, not keys.
    assert not any({"libvisp-dev", "libapriltag-dev"} & dependencies(m) for m in MANIFESTS)


PRODUCT = ("follow_bot", "follow_bot_common", "follow_bot_msgs", "image_converter",
           "compressed_transport")  # fmt: skip


@pytest.mark.parametrize("package", PRODUCT)
def test_the_product_never_needs_the_harness(package):
    """A robot installs the product alone: no manifest dependency on the harness or its worlds,
    no launch file that starts or finds them, no code that imports the harness."""
    root = REPO / package
    manifest = ET.parse(root / "package.xml").getroot()
    depends = {e.text for e in manifest if e.tag.endswith("depend")}
    assert not depends & {"harness", "worlds"}, depends
    for path in sorted(root.rglob("*")):
        if path.suffix == ".launch":
            text = path.read_text()
            assert 'pkg="harness"' not in text and "$(find harness)" not in text, path
            assert "rosrun harness" not in text and "$(find worlds)" not in text, path
        elif path.suffix == ".py":
            assert not re.search(r"^\s*(from|import) harness\b", path.read_text(), re.M), path
