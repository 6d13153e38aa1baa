#!/usr/bin/env bash
# make bench: every benchmark, each reporting against a baseline measured in the same run.
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
echo "== follower line detector vs the lecture's algorithm (same frames, one thread)"
"$repo/build/devel/lib/follow_bot/line_detector_bench"
echo "== parker tag detection + pose vs a bare ViSP vpDetectorAprilTag::detect (same frames, one thread)"
"$repo/build/devel/lib/follow_bot/tag_detector_bench"
echo "== parker sign detector tracking vs searching every frame (same frames, one thread, CPU time)"
"$repo/build/devel/lib/follow_bot/sign_tracking_bench"
echo "== follow_bot.core from Python vs the same C++ call (process CPU time, same frames, one thread)"
"${FOLLOW_BOT_VENV:-$repo/.venv}/bin/python3" "$repo/tools/python_core_bench.py"
echo "== harness"
"$repo/harness/scripts/run_python" harness.bench
echo "== follower image -> cmd_vel latency, across processes and between nodelets (probe nodelet)"
"$repo/tools/bench_latency.sh"
