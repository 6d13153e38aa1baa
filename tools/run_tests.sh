#!/usr/bin/env bash
# Runs every test suite after the build, then one closing summary over all JUnit results.
# A suite whose runner breaks (rather than reporting failed tests) fails the run too.
set -uo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
build=$repo/build
venv=${FOLLOW_BOT_VENV:-$repo/.venv}
set +u  # ROS's setup scripts read unset variables
# shellcheck disable=SC1091
source "$build/devel/setup.bash"
set -u
# The suites run side by side on every core: numpy's OpenBLAS threads would only spin.
export OPENBLAS_NUM_THREADS=${OPENBLAS_NUM_THREADS:-1}
rm -rf "$build/test_results" "$build/catkin/test_results"
mkdir -p "$build/test_results"
status=0

# The gtests and rostests run one at a time and mostly wait on their nodes' wall-clock timing:
# they run beside pytest rather than before it.
echo "== gtest + rostest (catkin run_tests, in the background; log: build/run_tests.log)"
make -C "$build/catkin" --no-print-directory run_tests >"$build/run_tests.log" 2>&1 &
catkin_tests=$!

# FULL=1 (make test-full) also plays the scenario runs marked `full`
# (tests/closed_loop/test_scenarios.py).
select=(-m "not full")
[ "${FULL:-0}" = 1 ] && select=()
# One pytest-xdist worker per core, a whole file per worker: a file's module and session
# fixtures (one run_scenario call for all the scenario runs, one fuzz storm) run once.
workers=(-n "$(nproc)" --dist loadfile)
echo "== pytest ${select[*]} ${workers[*]}"
"$venv/bin/python3" -m pytest -q "${select[@]}" "${workers[@]}" harness/test tests \
  --junitxml="$build/test_results/pytest.xml"
rc=$?
if [ $rc -ne 0 ] && [ $rc -ne 1 ]; then  # 1 = some tests failed, counted from the XML below
  echo "pytest broke (exit $rc)"
  status=1
fi

if ! wait $catkin_tests; then
  tail -50 "$build/run_tests.log"
  echo "catkin run_tests broke (see build/run_tests.log)"
  status=1
fi

/usr/bin/python3 "$repo/tools/test_summary.py" \
  catkin="$build/catkin/test_results" pytest="$build/test_results/pytest.xml" ||
  status=1
exit $status
