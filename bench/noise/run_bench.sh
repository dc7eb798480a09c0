#!/bin/bash
# Side-by-side: metro (whole process, CSV -> octave OADEV with noise id, EDF and CI) vs numpy
# (in-memory octave OADEV after a pandas read), each run RUNS times alternately; prints
# median, min and max of each and the ratio of the medians, with the load average. Then
# metro's all-tau (Stable32-thinned) sweep at N = 1e6 and the agreement of the curves.
#   bench/noise/run_bench.sh BUILD_DIR [WORK_DIR=/tmp/metro_bench_noise] [RUNS=5]
set -euo pipefail
build=${1:?usage: run_bench.sh BUILD_DIR [WORK_DIR] [RUNS]}
work=${2:-/tmp/metro_bench_noise}
runs=${3:-5}
here=$(cd "$(dirname "$0")" && pwd)
bench=$(find "$build" -name metro_bench_noise_oadev -type f | head -1)
gen=$(find "$build" -name metro_bench_noise_gen -type f | head -1)
mkdir -p "$work"
csv="$work/rate_1e7.csv"
[ -s "$csv" ] || "$gen" "$csv" 10000000 1
cat "$csv" > /dev/null  # page cache warm for both contenders
now() { date +%s.%N; }
echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
metro_times=()
numpy_times=()
for ((i = 1; i <= runs; i++)); do
  t0=$(now)
  "$bench" "$csv" > "$work/metro_octave.csv"
  t1=$(now)
  metro_times+=("$(echo "$t1 - $t0" | bc)")
  /usr/bin/python3 "$here/numpy_oadev.py" "$csv" > "$work/numpy_octave.csv" 2> "$work/numpy.err"
  cat "$work/numpy.err"
  line=$(cat "$work/numpy.err")
  numpy_times+=("$(echo "$line" | sed -n 's/.*in-memory OADEV \([0-9.]*\) s.*/\1/p')")
done
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
/usr/bin/python3 "$here/../compare_times.py" "metro whole process wall" "${metro_times[*]}" \
  "numpy in-memory OADEV" "${numpy_times[*]}"
echo "== metro all-tau (Stable32 thinning) at N = 1e6, whole process"
/usr/bin/time -f "metro wall %e s" "$bench" "$csv" --taus all --limit 1000000 > "$work/metro_all.csv"
echo "== agreement of the octave curves (max relative difference)"
/usr/bin/python3 - "$work/metro_octave.csv" "$work/numpy_octave.csv" <<'PY'
import sys
a = [l.split(',') for l in open(sys.argv[1]).read().split('\n')[1:] if l]
b = [l.split(',') for l in open(sys.argv[2]).read().split('\n') if l]
print(max(abs(float(x[1]) / float(y[1]) - 1) for x, y in zip(a, b)), "over", len(b), "taus")
PY
