"""`make deps` on a simulated fresh Debian machine: nothing installed, no venv.

The test runs the script `make deps` runs, with stand-ins first on PATH for everything that would
touch the machine (dpkg-query, dpkg, apt-get, sudo, id) and for the interpreter the venv is made
from, whose venv's python3 stands in for pip. Each stand-in records its arguments; nothing real is
installed and neither the real venv nor apt is touched.
"""

from __future__ import annotations

import os
import stat
import subprocess
from pathlib import Path

from harness.testing import REPO

INSTALLER = REPO / "tools" / "install_deps.sh"

# Every stand-in appends one line to $FRESH_LOG: its name and its arguments, tab-separated.
RECORD = '(printf %s "{tool}"; printf "\\t%s" "$@"; echo) >>"$FRESH_LOG"\n'

STAND_INS = {
    # A fresh machine: dpkg knows none of the packages, which makes dpkg-query exit 1.
    "dpkg-query": "echo 'dpkg-query: no packages found' >&2\nexit 1\n",
    "dpkg": "exit 0\n",
    "apt-get": "exit 0\n",
    # An ordinary user, so the installer goes through sudo.
    "id": 'if [ "$1" = -u ]; then echo 1000; else echo "uid=1000(user)"; fi\n',
    "sudo": 'exec "$@"\n',
}

# The interpreter the venv is made from: `-m venv ... DIR` makes DIR/bin/python3, a stand-in whose
# `-m pip install -r FILE` records the requirements it was asked for.
VENV_PYTHON = """if [ "$1 $2" = "-m venv" ]; then
  for dir in "$@"; do :; done
  mkdir -p "$dir/bin"
  cp "$0.venv" "$dir/bin/python3"
  chmod +x "$dir/bin/python3"
fi
"""
VENV_PIP = """if [ "$1 $2 $3" = "-m pip install" ]; then
  while [ $# -gt 0 ]; do
    [ "$1" != -r ] || grep -v '^#' "$2" | sed '/^$/d; s/^/requirement\t/' >>"$FRESH_LOG"
    shift
  done
fi
"""


def write_tool(path: Path, body: str) -> None:
    path.write_text("#!/bin/sh\n" + RECORD.replace("{tool}", path.name) + body)
    path.chmod(path.stat().st_mode | stat.S_IXUSR)


def listed(path: Path) -> list[str]:
    return [
        line.strip()
        for line in path.read_text().splitlines()
        if line.strip() and not line.startswith("#")
    ]


def test_make_deps_installs_everything_on_a_fresh_machine(tmp_path):
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    for name, body in STAND_INS.items():
        write_tool(bin_dir / name, body)
    venv_python = tmp_path / "python3"
    write_tool(venv_python, VENV_PYTHON)
    Path(f"{venv_python}.venv").write_text(
        "#!/bin/sh\n" + RECORD.replace("{tool}", "venv-python3") + VENV_PIP
    )
    log = tmp_path / "calls.jsonl"
    venv = tmp_path / "venv"
    env = {
        **os.environ,
        "PATH": f"{bin_dir}:/usr/bin:/bin",
        "FRESH_LOG": str(log),
        "FOLLOW_BOT_VENV": str(venv),
        "FOLLOW_BOT_VENV_PYTHON": str(venv_python),
    }

    run = subprocess.run([str(INSTALLER)], env=env, capture_output=True, text=True, timeout=60)

    assert run.returncode == 0, run.stdout + run.stderr
    assert run.stdout.splitlines()[-1] == "deps: ok"
    calls = [line.split("\t") for line in log.read_text().splitlines()]
    requirements = [argv for tool, *argv in calls if tool == "requirement"]
    calls = [{"tool": tool, "argv": argv} for tool, *argv in calls]

    apt = [c["argv"] for c in calls if c["tool"] == "apt-get"]
    assert ["update", "-q"] in apt
    installs = [argv for argv in apt if "install" in argv]
    assert len(installs) == 1
    assert installs[0][:4] == ["install", "-y", "-q", "--no-install-recommends"]
    packages = listed(REPO / "tools" / "debian-packages.txt")
    assert sorted(installs[0][4:]) == sorted(packages)
    # Both apt-get calls went through sudo (the stand-in user is not root).
    assert [c["argv"][0] for c in calls if c["tool"] == "sudo"] == ["apt-get", "apt-get"]

    made = [c["argv"] for c in calls if c["tool"] == "python3"]
    assert made == [["-m", "venv", "--system-site-packages", str(venv)]]
    pip = [c["argv"] for c in calls if c["tool"] == "venv-python3"]
    requirements_file = str(REPO / "harness" / "requirements.txt")
    assert pip == [
        ["-m", "pip", "install", "-q", "--disable-pip-version-check", "-r", requirements_file]
    ]
    assert requirements == [[line] for line in listed(REPO / "harness" / "requirements.txt")]
    assert (venv / "CATKIN_IGNORE").exists() and (venv / "COLCON_IGNORE").exists()
