#!/usr/bin/env bash
# Interleaved side-by-side runs for the Type A benchmark (issue #2): each round runs the
# pandas baseline, then every given characterize build, on the same file; prints the median,
# min and max wall time of each contender (pandas: its in-process time) and metro's CPU time
# and peak memory. Interleaving keeps a machine whose speed drifts from favouring one side.
# Usage: bench/type_a/interleave.sh ROUNDS BUILD_DIR [BUILD_DIR...]
#   (the file as in bench/type_a/run.sh; needs python3-pandas and GNU time)
set -euo pipefail
cd "$(dirname "$0")/../.."
rounds="$1"
shift
data="${METRO_BENCH_DIR:-/tmp}/metro_bench_1h_15tags_100hz.csv"
if [ ! -f "$data" ]; then
  "$1/apps/characterize/characterize" simulate --seed 42 --tags 15 --columns imu --rate-hz 100 \
    --duration-s 3600 --packet-loss 0 -o "$data"
fi
log="$(mktemp)"
report="$(mktemp -d)/report.json"
trap 'rm -rf "$log" "$(dirname "$report")"' EXIT
# Every contender starts from a fully cached file: the file is read through once before each
# run (untimed). Once at the start is not enough where the kernel pages file pages out
# proactively: this project's VM runs DAMON reclaim, and 1 MB of the file left the page
# cache within 5 s of idling; a run then reads it back from disk.
warm() { cat "$data" > /dev/null; }
for _ in $(seq "$rounds"); do
  warm
  /usr/bin/python3 bench/type_a/pandas_baseline.py "$data" |
    awk '{print "pandas", $(NF-2), 0, 0, 0}' >> "$log"
  for build in "$@"; do
    rm -f "$report"
    warm
    /usr/bin/time -o "$log" -a -f "$build %e %U %S %M" "$build/apps/characterize/characterize" \
      "$data" --type-a -o "$report" > /dev/null
  done
done
echo "$rounds rounds, load average $(cut -d' ' -f1-3 /proc/loadavg), file $data"
/usr/bin/python3 - "$log" <<'PY'
import collections, statistics, sys
runs = collections.defaultdict(list)
order = []
for line in open(sys.argv[1]):
    name, wall, user, system, rss = line.split()
    if name not in runs:
        order.append(name)
    runs[name].append((float(wall), float(user) + float(system), int(rss)))
pandas = statistics.median(r[0] for r in runs["pandas"])
for name in order:
    v = runs[name]
    wall = sorted(r[0] for r in v)
    line = f"{name}: wall median {statistics.median(wall):.3f} s (min {wall[0]:.3f}, max {wall[-1]:.3f})"
    if name != "pandas":
        cpu = statistics.median(r[1] for r in v)
        line += (f", CPU median {cpu:.2f} s, peak RSS {max(r[2] for r in v) / 1024:.0f} MB, "
                 f"pandas / this: {pandas / statistics.median(wall):.1f} x")
    print(line)
PY
