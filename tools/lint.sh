#!/usr/bin/env bash
# Style gate: one .clang-format for all C++, ruff for all Python, mypy on the harness (mypy.ini),
# clang-tidy on the C++ (.clang-tidy, tools/tidy.py: after a build). --fix rewrites instead of
# checking.
set -euo pipefail
cd "$(dirname "$0")/.."
venv=$(realpath "${FOLLOW_BOT_VENV:-.venv}")
ruff=$venv/bin/ruff
mapfile -t cpp < <(git ls-files --cached --others --exclude-standard '*.cpp' '*.h' '*.hpp')
if [ "${1:-}" = "--fix" ]; then
  clang-format -i "${cpp[@]}"
  "$ruff" check --fix .
  "$ruff" format .
else
  clang-format --dry-run -Werror "${cpp[@]}"
  "$ruff" check .
  "$ruff" format --check .
  (cd harness/src && "$venv/bin/mypy" --config-file ../../mypy.ini --no-error-summary -p harness)
  /usr/bin/python3 tools/tidy.py
fi
echo "lint: ok (${#cpp[@]} C++ files, ruff, mypy, clang-tidy)"
