#!/usr/bin/env bash
# Interleaved side-by-side runs for the Type A benchmark (issues #2 and #19): each round runs
# every contender once on the same file: the baselines (DuckDB and Polars through Node.js;
# pandas if python3 has it, else it is skipped with a message) and every given characterize
# build, in an order rotated by one each round. Interleaving keeps a machine whose speed
# drifts from favouring one side; the rotation keeps any contender from always following
# the same one. First the baselines' numbers are checked against metro's report.
#
# Prints, per contender, the median, min and max wall time, CPU time and peak memory, and per
# baseline and build the ratio baseline / metro. metro's time is its whole process
# (`characterize FILE --type-a -o REPORT`, start-up, load, Type A with n_eff, JSON); a
# baseline's is its in-process time (read + aggregate, without interpreter start and module
# load), the stricter comparison, with its whole-process ratio beside it.
#
# Usage: bench/type_a/interleave.sh ROUNDS BUILD_DIR [BUILD_DIR...]
#   (the file as in bench/type_a/run.sh; GNU time; Node.js >= 20 for DuckDB and Polars;
#   METRO_BENCH_DIR and METRO_BENCH_CPUS as in bench/type_a/common.sh)
set -euo pipefail
cd "$(dirname "$0")/../.."
rounds="$1"
shift
source bench/type_a/common.sh
bench_make_data "$1/apps/characterize/characterize"
bench_find_baselines
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
log="$work/log"
: > "$log"

bench_check "$1/apps/characterize/characterize" "$work"

# Contenders: "baseline:<index>" or "metro:<build dir>".
contenders=()
for i in "${!baseline_names[@]}"; do contenders+=("baseline:$i"); done
for build in "$@"; do contenders+=("metro:$build"); done
count="${#contenders[@]}"

# Every contender starts from a fully cached file: the file is read through once before each
# run (untimed). Once at the start is not enough where the kernel pages file pages out
# proactively: this project's VM runs DAMON reclaim, and 1 MB of the file left the page
# cache within 5 s of idling; a run then reads it back from disk.
warm() { cat "$data" > /dev/null; }
for round in $(seq 0 $((rounds - 1))); do
  for k in $(seq 0 $((count - 1))); do
    contender="${contenders[$(((round + k) % count))]}"
    warm
    case "$contender" in
      baseline:*)
        i="${contender#baseline:}"
        out="$(eval "/usr/bin/time -o \"\$work/time\" -f '%e %U %S %M' ${pin[*]} \
          ${baseline_cmds[$i]} \"\$data\"")"
        echo "$out" > "$work/version_${baseline_names[$i]}"
        echo "${baseline_names[$i]} $(awk '{print $(NF-2)}' <<< "$out") $(cat "$work/time")" \
          >> "$log"
        ;;
      metro:*)
        build="${contender#metro:}"
        rm -f "$work/report.json"
        /usr/bin/time -o "$work/time" -f '%e %U %S %M' "${pin[@]}" \
          "$build/apps/characterize/characterize" "$data" --type-a -o "$work/report.json" \
          > /dev/null
        echo "metro:$build - $(cat "$work/time")" >> "$log"
        ;;
    esac
  done
done

echo "$rounds rounds, $count contenders, load average $(cut -d' ' -f1-3 /proc/loadavg)," \
  "$cpus cores, file $data ($(stat -c %s "$data" | awk '{printf "%.1f MB", $1 / 1e6}'))"
for name in "${baseline_names[@]}"; do
  echo "$name: $(cut -d: -f1 "$work/version_$name")"
done
/usr/bin/python3 - "$log" <<'PY'
import collections, statistics, sys
runs = collections.defaultdict(list)
order = []
for line in open(sys.argv[1]):
    name, inproc, wall, user, system, rss = line.split()
    if name not in runs:
        order.append(name)
    runs[name].append((float(wall if inproc == "-" else inproc), float(wall),
                       float(user) + float(system), int(rss)))
median = {}
for name in order:
    v = runs[name]
    t = sorted(r[0] for r in v)
    median[name] = (statistics.median(t), statistics.median(r[1] for r in v))
    what = "wall" if name.startswith("metro:") else "in-process"
    line = f"{name}: {what} median {median[name][0]:.3f} s (min {t[0]:.3f}, max {t[-1]:.3f})"
    if not name.startswith("metro:"):
        line += f", whole process {median[name][1]:.3f} s"
    line += (f", CPU median {statistics.median(r[2] for r in v):.2f} s, "
             f"peak RSS {max(r[3] for r in v) / 1024:.0f} MB")
    print(line)
for metro in (n for n in order if n.startswith("metro:")):
    for base in (n for n in order if not n.startswith("metro:")):
        print(f"{base} / {metro}: {median[base][0] / median[metro][0]:.2f} x "
              f"(whole process {median[base][1] / median[metro][0]:.2f} x)")
PY
