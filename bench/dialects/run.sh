#!/usr/bin/env bash
# Throughput of the general loader on session files that are not canonical (issue #19: at
# least 100 MB/s): the same 15-tag, 100 Hz data written as (a) canonical session.csv (the
# clean path, for reference), (b) ';'-separated with decimal commas and CRLF, (c) integer
# epoch-nanosecond time (t_ns), (d) tab-separated with a BOM and upper-case names. Each is
# loaded and evaluated (characterize --type-a) RUNS times; the median wall time and MB/s
# (file bytes / wall time of the whole process) are printed.
# Usage: bench/dialects/run.sh [BUILD_DIR] [RUNS] [DURATION_S]
set -euo pipefail
cd "$(dirname "$0")/../.."
build=${1:-build}
runs=${2:-5}
duration=${3:-600}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
characterize="$build/apps/characterize/characterize"

"$characterize" simulate -o "$work/canonical.csv" --seed 42 --tags 15 --columns imu \
  --rate-hz 100 --duration-s "$duration" --packet-loss 0 >/dev/null 2>&1
# The variants, derived from the canonical file (comments dropped; every number as written).
awk -F, 'BEGIN{OFS=";"} /^#/ {next} {for(i=1;i<=NF;i++) gsub(/\./, ",", $i); $1=$1; printf "%s\r\n", $0}' \
  "$work/canonical.csv" > "$work/semicolon_decimal_comma.csv"
awk -F, 'BEGIN{OFS=","} /^#/ {next}
  NR==1 || header==0 {if ($1=="t_s") {$1="t_ns"; header=1; print; next}}
  {split($1, p, "."); frac=substr(p[2] "000000000", 1, 9); $1=(1700000000 + p[1]) frac; print}' \
  "$work/canonical.csv" > "$work/integer_ns.csv"
awk -F, 'BEGIN{OFS="\t"; printf "\xef\xbb\xbf"} /^#/ {next} NR==1 || h==0 {h=1; $0=toupper($0)} {$1=$1; print}' \
  "$work/canonical.csv" > "$work/tab_bom_upper.csv"

median() { sort -n | awk '{a[NR]=$1} END{print a[int((NR+1)/2)]}'; }
printf '%-28s %10s %10s %10s\n' file MB "wall s" "MB/s"
for f in canonical semicolon_decimal_comma integer_ns tab_bom_upper; do
  path="$work/$f.csv"
  cat "$path" >/dev/null
  times=()
  for _ in $(seq "$runs"); do
    start=$(date +%s.%N)
    "$characterize" "$path" --type-a -o "$work/report.json" >/dev/null 2>&1
    end=$(date +%s.%N)
    times+=("$(echo "$end - $start" | bc -l)")
  done
  wall=$(printf '%s\n' "${times[@]}" | median)
  bytes=$(stat -c %s "$path")
  awk -v n="$f" -v b="$bytes" -v w="$wall" 'BEGIN{printf "%-28s %10.1f %10.3f %10.0f\n", n, b/1e6, w, b/1e6/w}'
done
