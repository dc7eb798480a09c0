#!/usr/bin/env bash
# Type A benchmark (issues #2 and #19): a 1-hour, 15-tag, 100 Hz session.csv (5.4 M rows x 9
# columns) through `characterize --type-a` (n_eff included) and through the baselines that
# compute each tag's count, mean and sample variance of every column: DuckDB and Polars
# (Node.js, bench/type_a/package.json) and pandas (if python3 has it), side by side, once
# each, with wall time and peak memory. bench/type_a/interleave.sh repeats the runs
# interleaved and prints medians and ratios.
# Usage: bench/type_a/run.sh [build dir]   (GNU time; Node.js >= 20 for DuckDB and Polars;
#   METRO_BENCH_DIR and METRO_BENCH_CPUS as in bench/type_a/common.sh)
set -euo pipefail
cd "$(dirname "$0")/../.."
build="${1:-build}"
exe="$build/apps/characterize/characterize"
source bench/type_a/common.sh
bench_make_data "$exe"
bench_find_baselines
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
stat -c %s "$data" | awk '{printf "file: %.1f MB\n", $1 / 1e6}'
bench_check "$exe" "$work"
cat "$data" > /dev/null  # warm the page cache for every contender
echo "== metro characterize --type-a"
/usr/bin/time -f "wall %e s, peak RSS %M kB" "${pin[@]}" "$exe" "$data" --type-a \
  -o "$work/report.json" > /dev/null
for i in "${!baseline_names[@]}"; do
  echo "== ${baseline_names[$i]} baseline"
  cat "$data" > /dev/null
  eval "/usr/bin/time -f 'wall %e s, peak RSS %M kB' ${pin[*]} ${baseline_cmds[$i]} \"\$data\""
done
