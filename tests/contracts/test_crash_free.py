"""The four inputs that once killed every node, malformed payloads of the compressed
image_transport (the nodes run with _image_transport:=compressed) and broken or
extreme camera_info each followed by a frame (a lens's), each sent to a
fresh copy of every node: the process must survive, and a valid frame afterwards must get the
right answer, through `harness.fuzz --cases` (a roscore and nodes of its own)."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from harness.fuzz_cases import crash_cases
from harness.testing import NODES


@pytest.fixture(scope="module")
def results(tmp_path_factory) -> dict[tuple[str, str], dict]:
    out = tmp_path_factory.mktemp("crash_cases")
    done = subprocess.run(
        [sys.executable, "-m", "harness.fuzz", "--cases", "--json", str(out / "cases.json"),
         "--logs", str(out / "logs")],
        capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    print(done.stdout)
    assert (out / "cases.json").exists(), done.stdout + done.stderr
    return {(r["case"], r["node"]): r for r in json.loads((out / "cases.json").read_text())}


@pytest.mark.parametrize("node", list(NODES))
@pytest.mark.parametrize("case", list(crash_cases()))
def test_node_survives_and_answers_the_next_valid_frame(results, case, node):
    result = results[(case, node)]
    assert result["alive"], f"{node} died on {case} (exit code {result['exit_code']})"
    assert result["probe"] == "ok"
    assert result["non_finite"] == 0 and result["over_limit"] == 0
