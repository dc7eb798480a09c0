#!/bin/sh
# Side-by-side timing of the JCGM 101 9.5 gauge-block Monte Carlo: metro (whole process,
# wall clock) and numpy (in-process time printed by the script, plus its whole process).
# Usage: bench/uncertainty/run.sh BENCH_EXE [TRIALS]
# BENCH_EXE: the built bench_uncertainty_mc (e.g. build/bench/uncertainty/bench_uncertainty_mc).
set -eu
exe=${1:?usage: run.sh BENCH_EXE [TRIALS]}
trials=${2:-1e7}
here=$(cd "$(dirname "$0")" && pwd)
now() { date +%s.%N; }
t0=$(now)
"$exe" "$trials"
t1=$(now)
/usr/bin/python3 "$here/numpy_gauge_block.py" "$trials"
t2=$(now)
echo "metro whole process wall: $(echo "$t1 - $t0" | bc) s"
echo "numpy whole process wall: $(echo "$t2 - $t1" | bc) s (in-process time: numpy line above)"
