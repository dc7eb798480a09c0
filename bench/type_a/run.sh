#!/usr/bin/env bash
# Type A benchmark (issue #2): a 1-hour, 15-tag, 100 Hz session.csv (5.4 M rows x 9
# columns) through `characterize --type-a` (n_eff included) and through pandas read_csv +
# groupby mean/var, side by side, with wall time and peak memory of each.
# Usage: bench/type_a/run.sh [build dir]   (needs python3-pandas and GNU time)
set -euo pipefail
cd "$(dirname "$0")/../.."
build="${1:-build}"
exe="$build/apps/characterize/characterize"
data="${METRO_BENCH_DIR:-/tmp}/metro_bench_1h_15tags_100hz.csv"
if [ ! -f "$data" ]; then
  "$exe" simulate --seed 42 --tags 15 --columns imu --rate-hz 100 --duration-s 3600 \
    --packet-loss 0 -o "$data"
fi
ls -l "$data" | awk '{printf "file: %.1f MB\n", $5 / 1e6}'
cat "$data" > /dev/null  # warm the page cache for both contenders
echo "== metro characterize --type-a"
/usr/bin/time -f "wall %e s, peak RSS %M kB" "$exe" "$data" --type-a -o /tmp/metro_bench_report.json > /dev/null
echo "== pandas baseline"
/usr/bin/time -f "wall %e s, peak RSS %M kB" /usr/bin/python3 bench/type_a/pandas_baseline.py "$data"
