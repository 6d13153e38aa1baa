#!/usr/bin/env bash
# Installs everything the workspace needs on a fresh Debian 12 machine (idempotent, quick when
# all is present): Debian's ROS 1 and C++ packages, then the harness venv from PyPI.
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
venv=${FOLLOW_BOT_VENV:-$repo/.venv}
# The interpreter the venv is made from: Debian's, whatever python3 is first on PATH (the
# fresh-machine test points this at a stand-in).
venv_python=${FOLLOW_BOT_VENV_PYTHON:-/usr/bin/python3}
packages=$(grep -v '^#' "$repo/tools/debian-packages.txt" | tr '\n' ' ')

# dpkg-query exits 1 when any listed package is unknown to dpkg (always so on a fresh machine):
# that is an answer, not a failure, so its exit code is ignored and only its output counts.
installed=$(dpkg-query -W -f='${db:Status-Status} ${Package}\n' $packages 2>/dev/null || true)
missing=$(comm -13 <(awk '$1 == "installed" {print $2}' <<<"$installed" | sort) \
  <(tr ' ' '\n' <<<"$packages" | sed '/^$/d' | sort))
if [ -n "$missing" ]; then
  echo "deps: installing Debian packages: $missing"
  sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  $sudo apt-get update -q
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -q --no-install-recommends $packages
fi

# The venv sees Debian's rospy (system site packages); its own numpy/cv2 shadow any Debian copy.
stamp="$venv/.requirements.sha256"
want=$(sha256sum "$repo/harness/requirements.txt" | cut -d' ' -f1)
if [ ! -x "$venv/bin/python3" ] || [ "$(cat "$stamp" 2>/dev/null)" != "$want" ]; then
  echo "deps: creating the harness venv in $venv"
  "$venv_python" -m venv --system-site-packages "$venv"
  "$venv/bin/python3" -m pip install -q --disable-pip-version-check -r "$repo/harness/requirements.txt"
  # catkin and colcon must not crawl the venv for packages.
  touch "$venv/CATKIN_IGNORE" "$venv/COLCON_IGNORE"
  echo "$want" >"$stamp"
fi
echo "deps: ok"
