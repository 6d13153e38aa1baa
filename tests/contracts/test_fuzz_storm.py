"""A short seeded storm (harness.fuzz, 1,000 messages per node: random and malformed Images,
random CameraInfo and odometry) against every node, so a crash regression cannot land, and the
node's own counters on /diagnostics held against what the fuzzer knows it sent: every malformed
frame dropped under its reason, every valid one accepted, every camera_info taken or refused as
built (a node that drops everything, or drops under the wrong reason, fails). `make fuzz` runs
the long one (10,000 per node). Prints the per-node counts."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from harness.testing import NODES

MESSAGES = 1000
SEED = 7


@pytest.fixture(scope="module")
def storm(tmp_path_factory) -> tuple[str, dict[str, dict]]:
    """The storm's printed per-node counts and its results by node."""
    out = tmp_path_factory.mktemp("storm")
    done = subprocess.run(
        [sys.executable, "-m", "harness.fuzz", "--messages", str(MESSAGES), "--seed", str(SEED),
         "--json", str(out / "storm.json"), "--logs", str(out / "logs")],
        capture_output=True, text=True, timeout=900,
    )  # fmt: skip
    assert (out / "storm.json").exists(), done.stdout + done.stderr
    return done.stdout, {r["node"]: r for r in json.loads((out / "storm.json").read_text())}


def test_storm_reaches_every_node_and_prints_the_counts(storm, record_property):
    table, results = storm
    record_property("summary", table)  # shown in the closing summary (tests/conftest.py)
    assert set(results) == set(NODES)


@pytest.mark.parametrize("node", list(NODES))
def test_storm_leaves_the_node_alive_correct_and_its_twists_sane(storm, node):
    r = storm[1][node]
    assert r["messages"] >= MESSAGES
    assert r["alive"], f"{node} died (exit code {r['exit_code']})"
    assert r["probe"] == "ok"
    assert r["non_finite"] == 0
    assert r["over_limit"] == 0


@pytest.mark.parametrize("node", list(NODES))
def test_storm_every_message_counted_by_the_node_under_its_outcome(storm, node):
    r = storm[1][node]
    assert r["expected"] is not None, "the storm sends only messages of known fate"
    assert r["expected"]["frames_accepted"] > 0 and r["expected"]["dropped_bad_size"] > 0
    assert r["count_errors"] == [], (r["counts"], r["expected"])
