#!/bin/bash
# Side-by-side: metro (whole process, CSV -> octave OADEV with EDF/CI) vs numpy (in-memory
# octave OADEV after loading), plus metro's all-tau (Stable32-thinned) sweep at N = 1e6.
#   bench/noise/run_bench.sh BUILD_DIR [WORK_DIR=/tmp/metro_bench_noise]
set -euo pipefail
build=${1:?usage: run_bench.sh BUILD_DIR [WORK_DIR]}
work=${2:-/tmp/metro_bench_noise}
here=$(cd "$(dirname "$0")" && pwd)
bench=$(find "$build" -name metro_bench_noise_oadev -type f | head -1)
gen=$(find "$build" -name metro_bench_noise_gen -type f | head -1)
mkdir -p "$work"
csv="$work/rate_1e7.csv"
[ -s "$csv" ] || "$gen" "$csv" 10000000 1
cat "$csv" > /dev/null  # page cache warm for both contenders
echo "== metro, whole process (3 runs; wall clock from the shell)"
for i in 1 2 3; do
  /usr/bin/time -f "metro wall %e s, max RSS %M kB" "$bench" "$csv" > "$work/metro_octave.csv"
done
echo "== numpy cumulative-sum baseline (3 runs)"
for i in 1 2 3; do
  /usr/bin/python3 "$here/numpy_oadev.py" "$csv" > "$work/numpy_octave.csv"
done
echo "== metro all-tau (Stable32 thinning) at N = 1e6, whole process"
/usr/bin/time -f "metro wall %e s" "$bench" "$csv" --taus all --limit 1000000 > "$work/metro_all.csv"
echo "== agreement of the octave curves (max relative difference)"
/usr/bin/python3 - "$work/metro_octave.csv" "$work/numpy_octave.csv" <<'PY'
import sys
a = [l.split(',') for l in open(sys.argv[1]).read().split('\n')[1:] if l]
b = [l.split(',') for l in open(sys.argv[2]).read().split('\n') if l]
print(max(abs(float(x[1]) / float(y[1]) - 1) for x, y in zip(a, b)), "over", len(b), "taus")
PY
