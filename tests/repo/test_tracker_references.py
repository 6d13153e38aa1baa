"""Comments and docs give the current reason, not a tracker's history: no file refers to an issue
number of a tracker that is not in the repository (the history is in the commit messages)."""

import re
import subprocess

from harness.testing import REPO

ISSUE_NUMBER = re.compile(r"\bissues? #?\d+|#\d+ \(issue|\bissue's\b", re.IGNORECASE)


def test_no_file_names_an_issue_number():
    files = subprocess.run(
        ["git", "ls-files"], cwd=REPO, check=True, capture_output=True, text=True
    ).stdout.split()
    hits = []
    for name in files:
        path = REPO / name
        if path.suffix in {".png", ".jpg", ".pgm", ".npz", ".bag"} or not path.is_file():
            continue
        for number, line in enumerate(path.read_text(errors="replace").splitlines(), 1):
            if ISSUE_NUMBER.search(line) and name != "tests/repo/test_tracker_references.py":
                hits.append(f"{name}:{number}: {line.strip()}")
    assert not hits, "\n".join(hits)
