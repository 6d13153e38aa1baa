"""Shared pytest hooks and fixtures.

Text a test asks to show in the closing summary (record_property("summary", text)): it reaches
the terminal from pytest-xdist workers too, where a test's own print does not."""

import warnings
from pathlib import Path

import cv2
import pytest

from harness.testing import REPO

# The suites run side by side on every core (tools/run_tests.sh): OpenCV's worker threads in a
# test process would only contend for them. The pixels are the same either way.
cv2.setNumThreads(1)


def pytest_terminal_summary(terminalreporter):
    for outcome in ("passed", "failed"):
        for report in terminalreporter.stats.get(outcome, []):
            for name, value in getattr(report, "user_properties", ()):
                if name == "summary" and report.when == "call":
                    terminalreporter.write_line(value)


# Real robot-camera frames that are not ours to ship (../shared/realdata/README.md): tests read
# them when the folder is beside the repository and skip, saying why once, when it is not.
REALDATA = REPO.parent / "shared" / "realdata"


@pytest.fixture(scope="session")
def realdata() -> Path:
    # Session scope: the body runs once (per xdist worker), so the absence is said once; pytest
    # then skips every test that asks for the folder.
    if not REALDATA.is_dir():
        warnings.warn(f"{REALDATA} is absent: tests on real camera frames skipped", stacklevel=2)
        pytest.skip(f"no real robot-camera frames at {REALDATA} (see its README when present)")
    return REALDATA
