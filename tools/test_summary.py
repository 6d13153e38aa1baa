"""Adds up every JUnit XML result (gtest, rostest, pytest) and prints one closing line.

Exits non-zero when anything failed or when no test ran at all.
"""

import sys
import xml.etree.ElementTree as ET
from pathlib import Path


def suites(root: ET.Element):
    return [root] if root.tag == "testsuite" else root.iter("testsuite")


def main(directories: list[str]) -> int:
    passed = failed = skipped = 0
    for directory in directories:
        for path in sorted(Path(directory).rglob("*.xml")):
            try:
                root = ET.parse(path).getroot()
            except ET.ParseError as error:
                print(f"unreadable result {path}: {error}")
                failed += 1
                continue
            for suite in suites(root):
                for case in suite.iter("testcase"):
                    problem = case.find("failure")
                    if problem is None:
                        problem = case.find("error")
                    if problem is not None:
                        failed += 1
                        print(f"FAILED {path.name}: {case.get('classname')}.{case.get('name')}")
                    elif case.find("skipped") is not None:
                        skipped += 1
                    else:
                        passed += 1
    print(f"tests: {passed} passed, {failed} failed, {skipped} skipped")
    return 1 if failed or passed == 0 else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
