"""Shared fixtures; puts harness/src first on sys.path so tests need no install or roscore."""

import sys
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src"
if str(SRC) not in sys.path:
    sys.path.insert(0, str(SRC))

from harness.world import WORLDS_DIR, World  # noqa: E402
from harness.world_file import load_world  # noqa: E402


@pytest.fixture(scope="session")
def worlds() -> dict[str, World]:
    """The shipped worlds, loaded once."""
    return {
        name: load_world(WORLDS_DIR / f"{name}.yaml")
        for name in ("course", "rgb", "dumpster", "parking", "parking_sign")
    }
