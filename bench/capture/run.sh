#!/usr/bin/env bash
# Benchmark (issue #26): `characterize capture` against the simulated central receiver with
# 15 tags at 100 Hz (1500 lines/s, about 83 kB/s). Reports the capture's CPU use (user +
# system time of the process / wall time, from /proc), lines sent and captured (lost = the
# difference), torn lines, and how far the receiver fell behind its frame schedule (a
# reader that does not keep up makes the pty's writes wait). Not a test: figures for
# docs/benchmarks.md.
#
#   bench/capture/run.sh [BUILD_DIR] [DURATION_S]      (defaults: build, 60)
#   LIVE=1 bench/capture/run.sh ...   the same with stderr on a terminal (script(1) gives the
#                                     capture a pty), i.e. with the live view redrawn at 2 Hz
set -euo pipefail
cd "$(dirname "$0")/../.."
build=${1:-build}
duration=${2:-60}
sim=$build/apps/sim_receiver/metro_sim_receiver
cap=$build/apps/characterize/characterize
work=$build/bench-capture
rm -rf "$work"
mkdir -p "$work"

"$sim" --port-link "$work/port" --tags 15 --frame-period-s 0.01 --duration-s "$duration" \
  --packet-loss 0.02 --seed 1 --record "$work/sent.txt" >"$work/sim.out" 2>"$work/sim.err" &
sim_pid=$!
trap 'kill $sim_pid 2>/dev/null || true; kill $cap_pid 2>/dev/null || true' EXIT
for _ in $(seq 100); do grep -q '^pty:' "$work/sim.out" 2>/dev/null && break; sleep 0.1; done

if [ "${LIVE:-0}" = 1 ]; then
  script -qfec "$cap capture --port $work/port -o $work/capture.txt" "$work/capture.tty" \
    >/dev/null </dev/null &
  wrapper=$!
  cap_pid=
  for _ in $(seq 100); do
    cap_pid=$(pgrep -P "$(pgrep -P $wrapper | head -1)" 2>/dev/null | head -1 || true)
    [ -z "$cap_pid" ] && cap_pid=$(pgrep -P $wrapper 2>/dev/null | head -1 || true)
    [ -n "$cap_pid" ] && grep -q capture "/proc/$cap_pid/cmdline" 2>/dev/null && break
    sleep 0.1
  done
else
  "$cap" capture --port "$work/port" -o "$work/capture.txt" >"$work/capture.out" 2>"$work/capture.err" &
  cap_pid=$!
fi
t0=$(date +%s.%N)
for _ in $(seq $((duration * 10 + 600))); do grep -q '^done' "$work/sim.out" && break; sleep 0.1; done
sent=$(wc -l <"$work/sent.txt")
for _ in $(seq 100); do
  [ "$(grep -vc '^#' "$work/capture.txt")" -ge "$sent" ] && break
  sleep 0.1
done
read -r utime stime < <(awk '{print $14, $15}' "/proc/$cap_pid/stat")
t1=$(date +%s.%N)
kill -TERM "$cap_pid"
wait "${wrapper:-$cap_pid}" || true
for _ in $(seq 100); do kill -0 "$cap_pid" 2>/dev/null || break; sleep 0.1; done
captured=$(grep -vc '^#' "$work/capture.txt")
torn=$(grep -v '^#' "$work/capture.txt" | awk 'length($0) != 54' | wc -l)
same=no
cmp -s <(grep -v '^#' "$work/capture.txt") "$work/sent.txt" && same=yes
tck=$(getconf CLK_TCK)
awk -v u="$utime" -v s="$stime" -v t0="$t0" -v t1="$t1" -v tck="$tck" -v sent="$sent" \
  -v got="$captured" -v torn="$torn" -v same="$same" -v live="$([ "${LIVE:-0}" = 1 ] && echo ', live view on a terminal')" -v lag="$(grep -o 'at most [0-9.]* ms' "$work/sim.err")" \
  'BEGIN {
     wall = t1 - t0; cpu = (u + s) / tck;
     printf "capture: 15 tags at 100 Hz for %.1f s wall%s\n", wall, live;
     printf "  lines sent %d, captured %d, lost %d, torn %d, body identical to what was sent: %s\n",
            sent, got, sent - got, torn, same;
     printf "  CPU: user %.2f s + system %.2f s = %.2f s, %.2f %% of one core\n",
            u / tck, s / tck, cpu, 100 * cpu / wall;
     printf "  receiver: %s behind its frame schedule\n", lag;
   }'
