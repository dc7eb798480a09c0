#!/usr/bin/env bash
# Issue #41 benchmark: a 3 h, 400 Hz sensor_msgs/Imu bag (4.32 M messages) in MCAP with zstd
# chunks, written at bench time by npm @mcap/core (write_imu_bag.mjs; never committed), then
# `characterize BAG --type-a --allan -o r.json` RUNS times under /usr/bin/time: wall time [s]
# and peak RSS [KB] of each run. Target (docs/benchmarks.md): <= 10 s on 2 cores.
# Usage: bench/ros/run.sh [BUILD_DIR=build] [RUNS=3] [HOURS=3] [WORK_DIR=a new temp dir]
# The npm packages (package-lock.json here) are installed with `npm ci` in WORK_DIR, outside
# the repository; the bag is written there too (about 1 GB for 3 h) and left for reuse.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
build="${1:-build}"
runs="${2:-3}"
hours="${3:-3}"
work="${4:-$(mktemp -d)}"
characterize="$build/apps/characterize/characterize"
[ -x "$characterize" ] || { echo "$characterize: not built (cmake --build $build --target characterize)" >&2; exit 2; }
mkdir -p "$work"
cp "$here/package.json" "$here/package-lock.json" "$here/write_imu_bag.mjs" "$work/"
bag="$work/imu_${hours}h_400hz_zstd.mcap"
if [ ! -s "$bag" ]; then
  (cd "$work" && [ -d node_modules ] || npm ci --no-audit --no-fund --loglevel=error >&2)
  echo "writing $bag" >&2
  (cd "$work" && /usr/bin/time -f "writer: %e s %M KB" node write_imu_bag.mjs "$bag" "$hours")
fi
ls -l "$bag" >&2
echo "date: $(date -u +%Y-%m-%dT%H:%M:%SZ), load: $(cut -d' ' -f1-3 /proc/loadavg), cores: $(nproc)"
for i in $(seq 1 "$runs"); do
  /usr/bin/time -f "run $i: %e s %M KB (user %U s, sys %S s)" \
    "$characterize" "$bag" --type-a --allan -o "$work/r.json" > /dev/null
done
