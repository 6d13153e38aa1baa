#!/usr/bin/env bash
# Style gate: one .clang-format for all C++, ruff for all Python. --fix rewrites instead of checking.
set -euo pipefail
cd "$(dirname "$0")/.."
ruff=${FOLLOW_BOT_VENV:-.venv}/bin/ruff
mapfile -t cpp < <(git ls-files --cached --others --exclude-standard '*.cpp' '*.h' '*.hpp')
if [ "${1:-}" = "--fix" ]; then
  clang-format -i "${cpp[@]}"
  "$ruff" check --fix .
  "$ruff" format .
else
  clang-format --dry-run -Werror "${cpp[@]}"
  "$ruff" check .
  "$ruff" format --check .
fi
echo "lint: ok (${#cpp[@]} C++ files, ruff)"
