#!/bin/bash
# Side-by-side timing of the JCGM 101 9.5 gauge-block Monte Carlo: metro (whole process,
# wall clock from the shell) and numpy (its in-process time, generator to interval), each
# run RUNS times alternately; prints every run, then median, min and max of each, the ratio
# of the medians and the load average before and after.
# Usage: bench/uncertainty/run.sh BENCH_EXE [TRIALS=1e7] [RUNS=5]
# BENCH_EXE: the built bench_uncertainty_mc (e.g. build/bench/uncertainty/bench_uncertainty_mc).
set -euo pipefail
exe=${1:?usage: run.sh BENCH_EXE [TRIALS] [RUNS]}
trials=${2:-1e7}
runs=${3:-5}
here=$(cd "$(dirname "$0")" && pwd)
now() { date +%s.%N; }
echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
metro_times=()
numpy_times=()
for ((i = 1; i <= runs; i++)); do
  t0=$(now)
  "$exe" "$trials"
  t1=$(now)
  metro_times+=("$(echo "$t1 - $t0" | bc)")
  line=$(/usr/bin/python3 "$here/numpy_gauge_block.py" "$trials")
  echo "$line"
  numpy_times+=("${line##*time_s=}")
done
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
/usr/bin/python3 "$here/../compare_times.py" "metro whole process wall" "${metro_times[*]}" \
  "numpy in-process" "${numpy_times[*]}"
