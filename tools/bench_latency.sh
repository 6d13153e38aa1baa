#!/usr/bin/env bash
# image -> cmd_vel latency of the follower, measured by follow_bot/LatencyProbeNodelet:
#   (a) across processes: `rosrun follow_bot follower` and the probe as a standalone nodelet;
#   (b) between nodelets in one manager (follow_bot/bench/latency_nodelets.launch).
# Runs its own roscore on a free port; needs the devel space sourced (make bench does that).
# LATENCY_FRAMES (600) frames are timed per run at 30 Hz, after 30 warm-up frames.
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
frames=${LATENCY_FRAMES:-600}
logs=$(mktemp -d "${TMPDIR:-/tmp}/bench_latency.XXXXXX")

port=$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
export ROS_MASTER_URI=http://127.0.0.1:$port ROS_IP=127.0.0.1
unset ROS_HOSTNAME

pids=()
cleanup() {
  local pid
  for pid in "${pids[@]}"; do kill -INT "$pid" 2>/dev/null || true; done
  for pid in "${pids[@]}"; do wait "$pid" 2>/dev/null || true; done
}
trap cleanup EXIT

fail() {
  echo "bench_latency: $1 (logs in $logs)" >&2
  tail -n 20 "$logs"/*.log >&2 || true
  exit 1
}

roscore -p "$port" >"$logs/roscore.log" 2>&1 &
pids+=($!)
for _ in $(seq 100); do
  rosparam set /use_sim_time false 2>/dev/null && break
  sleep 0.2
done
[ "$(rosparam get /use_sim_time 2>/dev/null)" = "false" ] || fail "roscore did not start"

# The probe prints one line "latency <label>: ..." when done; show it, or fail.
report() {
  grep -h '^latency ' "$1" || fail "no latency report in $1"
  ! grep -q '^latency .*FAILED' "$1" || fail "probe failed"
}

# (a) The follower in a process of its own (topics /camera/rgb/image_raw -> /cmd_vel).
rosrun follow_bot follower __name:=latency_follower _mode:=pd >"$logs/follower.log" 2>&1 &
follower=$!
pids=("$follower" "${pids[@]}")
timeout 60 rosrun nodelet nodelet standalone follow_bot/LatencyProbeNodelet \
  __name:=latency_probe image:=/camera/rgb/image_raw cmd_vel:=/cmd_vel \
  _frames:="$frames" _label:="across processes" _goal_median_us:=1500 _goal_p99_us:=3000 \
  >"$logs/probe.log" 2>&1 || true
report "$logs/probe.log"
kill -INT "$follower" && wait "$follower" || true
pids=("${pids[@]:1}")

# (b) Both in one nodelet manager; the probe ends the manager, and so the launch.
timeout 60 roslaunch "$repo/follow_bot/bench/latency_nodelets.launch" frames:="$frames" \
  >"$logs/nodelets.log" 2>&1 || true
report "$logs/nodelets.log"
cleanup
pids=()
rm -rf "$logs"
