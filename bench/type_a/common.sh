# shellcheck shell=bash
# Shared by bench/type_a/run.sh and bench/type_a/interleave.sh (sourced from the repository
# root): the session file, the baselines that can run here, the core limit and the check of
# the baselines' numbers against metro's report.
#
# Environment: METRO_BENCH_DIR (default /tmp) holds the session file; METRO_BENCH_CPUS
# (default 2, the project machine's cores) is the number of cores every contender may use:
# each runs under `taskset -c 0-(N-1)` and the baselines get N worker threads.

bench_dir="${METRO_BENCH_DIR:-/tmp}"
data="$bench_dir/metro_bench_1h_15tags_100hz.csv"
cpus="${METRO_BENCH_CPUS:-2}"
type_a_dir="bench/type_a"

# The 1-hour, 15-tag, 100 Hz session: 5.4 M rows x 9 columns, about 389 MB.
bench_make_data() {  # characterize executable
  if [ ! -f "$data" ]; then
    "$1" simulate --seed 42 --tags 15 --columns imu --rate-hz 100 --duration-s 3600 \
      --packet-loss 0 -o "$data"
  fi
}

pin=()
if command -v taskset > /dev/null; then
  pin=(taskset -c "0-$((cpus - 1))")
else
  echo "taskset not found: contenders are not pinned to $cpus cores" >&2
fi

# Fills baseline_names and baseline_cmds (one command line per name, run through eval with
# the file appended). DuckDB and Polars need Node.js (>= 20) and the pinned packages of
# package-lock.json, installed here with `npm ci` when node_modules is missing.
baseline_names=()
baseline_cmds=()
bench_find_baselines() {
  if command -v node > /dev/null && command -v npm > /dev/null; then
    if [ ! -d "$type_a_dir/node_modules" ]; then
      echo "installing the DuckDB and Polars packages (npm ci in $type_a_dir)" >&2
      (cd "$type_a_dir" && npm ci --no-audit --no-fund --loglevel=error >&2)
    fi
    baseline_names+=(duckdb polars)
    baseline_cmds+=("node $type_a_dir/duckdb_baseline.mjs --threads $cpus"
                    "node $type_a_dir/polars_baseline.mjs --threads $cpus")
  else
    echo "DuckDB, Polars: skipped (Node.js and npm not found)" >&2
  fi
  if /usr/bin/python3 -c 'import pandas' 2> /dev/null; then
    baseline_names+=(pandas)
    baseline_cmds+=("/usr/bin/python3 $type_a_dir/pandas_baseline.py")
  else
    echo "pandas: skipped (python3 has no pandas module; apt-get install python3-pandas)" >&2
  fi
}

# Runs metro and the Node.js baselines once each (untimed), writing their numbers, and
# compares them: one "check:" line per baseline; returns 1 on a mismatch.
bench_check() {  # characterize executable, scratch directory
  local exe="$1" work="$2" specs=()
  "${pin[@]}" "$exe" "$data" --type-a -o "$work/check_report.json" > /dev/null
  for i in "${!baseline_names[@]}"; do
    case "${baseline_names[$i]}" in
      duckdb | polars)
        eval "${pin[*]} ${baseline_cmds[$i]} \"\$data\" --json \"\$work/${baseline_names[$i]}.json\"" \
          > /dev/null
        specs+=("${baseline_names[$i]}=$work/${baseline_names[$i]}.json")
        ;;
    esac
  done
  if [ "${#specs[@]}" -gt 0 ]; then
    node "$type_a_dir/check.mjs" "$work/check_report.json" "${specs[@]}"
  fi
}
