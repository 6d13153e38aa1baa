"""Packaging: catkin_lint -W2 finds nothing, and every launch file documents its arguments
(`roslaunch --ros-args` shows each one's doc=). roslaunch's file check runs in catkin's
run_tests (roslaunch_add_file_check in each package's CMakeLists.txt)."""

import subprocess
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
LAUNCH_FILES = sorted(p for p in REPO.glob("*/**/*.launch") if ".venv" not in p.parts)


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
