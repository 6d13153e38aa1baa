"""tools/test_summary.py: the closing line counts what ran, and says so when a suite has none."""

import subprocess
import sys

from harness.testing import REPO

SUMMARY = REPO / "tools" / "test_summary.py"

GTEST = """<?xml version="1.0" encoding="UTF-8"?>
<testsuites tests="4" failures="1" disabled="1" errors="0" name="AllTests">
  <testsuite name="Core" tests="4" failures="1" disabled="1" errors="0">
    <testcase name="Passes" status="run" result="completed" classname="Core" />
    <testcase name="DISABLED_Off" status="notrun" result="suppressed" classname="Core" />
    <testcase name="Skips" status="run" result="skipped" classname="Core"><skipped /></testcase>
    <testcase name="Fails" status="run" result="completed" classname="Core">
      <failure message="boom" />
    </testcase>
  </testsuite>
</testsuites>
"""

PYTEST = """<?xml version="1.0" encoding="utf-8"?>
<testsuites><testsuite name="pytest" tests="2">
  <testcase classname="tests.test_a" name="test_one" />
  <testcase classname="tests.test_a" name="test_two" />
</testsuite></testsuites>
"""


def summary(*suites: str) -> tuple[int, list[str]]:
    done = subprocess.run(
        [sys.executable, str(SUMMARY), *suites], capture_output=True, text=True, timeout=60
    )
    return done.returncode, done.stdout.splitlines()


def test_notrun_and_skipped_gtest_cases_are_skipped_not_passed(tmp_path):
    (tmp_path / "gtest.xml").write_text(GTEST)
    code, lines = summary(f"gtest={tmp_path}")
    assert lines == ["FAILED gtest.xml: Core.Fails", "tests: 1 passed, 1 failed, 2 skipped"]
    assert code == 1


def test_all_passed_exits_zero(tmp_path):
    (tmp_path / "pytest.xml").write_text(PYTEST)
    code, lines = summary(f"pytest={tmp_path / 'pytest.xml'}")
    assert (code, lines) == (0, ["tests: 2 passed, 0 failed, 0 skipped"])


def test_a_suite_without_results_is_named_and_fails_the_run(tmp_path):
    (tmp_path / "catkin").mkdir()
    (tmp_path / "catkin" / "gtest.xml").write_text(PYTEST)
    code, lines = summary(f"catkin={tmp_path / 'catkin'}", f"pytest={tmp_path / 'pytest.xml'}")
    assert lines == [
        "tests: 2 passed, 0 failed, 0 skipped;"
        " NO RESULTS from pytest (its runner wrote no test case)"
    ]
    assert code == 1


def test_an_unreadable_result_is_a_failure(tmp_path):
    (tmp_path / "broken.xml").write_text("<testsuite><testcase")
    code, lines = summary(f"pytest={tmp_path}")
    assert code == 1
    assert lines[0].startswith(f"unreadable result {tmp_path / 'broken.xml'}")
    assert lines[-1].endswith("NO RESULTS from pytest (its runner wrote no test case)")
