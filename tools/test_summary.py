"""`test_summary.py SUITE=PATH...`: adds up the JUnit XML results of each suite (gtest, rostest,
pytest; PATH a file or a folder searched recursively) and prints one closing line.

A suite whose PATH holds no test case at all (its runner died before writing results) is named as
"no results", never read as "0 failed". gtest cases reported `notrun` (DISABLED_) or `skipped`
count as skipped, not passed. Exits non-zero when anything failed, when a suite has no results,
or when no test passed at all.
"""

import sys
import xml.etree.ElementTree as ET
from pathlib import Path


def suites(root: ET.Element):
    return [root] if root.tag == "testsuite" else root.iter("testsuite")


def verdict(case: ET.Element) -> str:
    if case.find("failure") is not None or case.find("error") is not None:
        return "failed"
    skipped = case.find("skipped") is not None
    # gtest marks disabled tests status="notrun"; newer gtest adds result="skipped".
    skipped |= case.get("status") == "notrun" or case.get("result") in ("skipped", "suppressed")
    return "skipped" if skipped else "passed"


def result_files(path: Path) -> list[Path]:
    if path.is_file():
        return [path]
    return sorted(path.rglob("*.xml")) if path.is_dir() else []


def main(arguments: list[str]) -> int:
    counts = {"passed": 0, "failed": 0, "skipped": 0}
    empty = []
    for argument in arguments:
        name, _, location = argument.rpartition("=")
        name = name or location
        cases = 0
        for path in result_files(Path(location)):
            try:
                root = ET.parse(path).getroot()
            except ET.ParseError as error:
                print(f"unreadable result {path}: {error}")
                counts["failed"] += 1
                continue
            for suite in suites(root):
                for case in suite.iter("testcase"):
                    cases += 1
                    outcome = verdict(case)
                    counts[outcome] += 1
                    if outcome == "failed":
                        print(f"FAILED {path.name}: {case.get('classname')}.{case.get('name')}")
        if cases == 0:
            empty.append(name)
    line = ", ".join(f"{n} {outcome}" for outcome, n in counts.items())
    line = f"tests: {line}"
    if empty:
        line += f"; NO RESULTS from {', '.join(empty)} (its runner wrote no test case)"
    print(line)
    return 1 if counts["failed"] or empty or counts["passed"] == 0 else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
