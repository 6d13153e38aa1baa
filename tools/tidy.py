"""clang-tidy over the project's C++ (the checks in .clang-tidy), with the build's compile
commands (build/catkin/compile_commands.json), one file per core at a time.

A file that passed is not checked again until it, its compile command, .clang-tidy or any of the
project's headers and .cfg files (whose generated headers it may include) change: a stamp per
passed file under build/tidy_passed. clang-tidy parses every ROS and OpenCV header a file
includes, seconds per file, so only a fresh build checks them all.
"""

import argparse
import hashlib
import json
import os
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
BUILD = REPO / "build"
PACKAGES = ("follow_bot", "follow_bot_common", "image_converter", "compressed_transport")


def digest(*parts: bytes) -> str:
    h = hashlib.sha256()
    for part in parts:
        h.update(hashlib.sha256(part).digest())
    return h.hexdigest()


def shared_inputs() -> bytes:
    """What every file's verdict depends on besides itself: .clang-tidy, headers, .cfg files."""
    files = sorted(
        path
        for package in PACKAGES
        for pattern in ("**/*.h", "cfg/*.cfg")
        for path in (REPO / package).glob(pattern)
    )
    return b"".join(
        path.relative_to(REPO).as_posix().encode() + path.read_bytes()
        for path in [REPO / ".clang-tidy", *files]
    )


def run(entry: dict, stamps: Path, shared: bytes) -> tuple[str, str | None]:
    """(file, None) when it passes, else (file, clang-tidy's report)."""
    source = Path(entry["file"])
    command = entry.get("command") or " ".join(entry["arguments"])
    stamp = stamps / digest(source.read_bytes(), command.encode(), shared)
    name = source.relative_to(REPO).as_posix()
    if stamp.exists():
        return name, None
    result = subprocess.run(
        ["clang-tidy", "--quiet", "-p", str(BUILD / "catkin"), str(source)],
        capture_output=True,
        text=True,
    )
    if result.returncode != 0:
        return name, result.stdout + result.stderr
    stamp.touch()
    return name, None


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    args = parser.parse_args()
    database = BUILD / "catkin" / "compile_commands.json"
    if not database.exists():
        print(f"tidy: {database} is missing: build first (make build)", file=sys.stderr)
        return 1
    entries = [
        entry
        for entry in json.loads(database.read_text())
        if Path(entry["file"]).resolve().is_relative_to(REPO)
        and not Path(entry["file"]).resolve().is_relative_to(BUILD)
    ]
    stamps = BUILD / "tidy_passed"
    stamps.mkdir(parents=True, exist_ok=True)
    shared = shared_inputs()
    with ThreadPoolExecutor(args.jobs) as pool:
        results = list(pool.map(lambda entry: run(entry, stamps, shared), entries))
    failed = [(name, report) for name, report in results if report is not None]
    for name, report in failed:
        print(f"== {name}\n{report}")
    print(f"tidy: {len(entries) - len(failed)} of {len(entries)} files clean")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
