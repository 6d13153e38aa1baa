#!/usr/bin/env bash
# Runs a command with every core kept busy, as `stress --cpu N` would (Debian's stress is not
# installed here): one busy loop per core at normal priority, stopped when the command ends.
# Used to show that the suite has no wall-clock flakes: tools/under_load.sh make test
set -euo pipefail
if [[ $# -eq 0 || $1 == --help || $1 == -h ]]; then
  echo "usage: tools/under_load.sh COMMAND [ARG...]   (CPU_HOGS=N: busy loops, default nproc)"
  [[ $# -eq 0 ]] && exit 2 || exit 0
fi
hogs=()
for _ in $(seq "${CPU_HOGS:-$(nproc)}"); do
  /usr/bin/python3 -c 'while True: pass' &
  hogs+=($!)
done
trap 'kill "${hogs[@]}" 2>/dev/null || true' EXIT
"$@"
