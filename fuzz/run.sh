#!/usr/bin/env bash
# Builds the host-side fuzz targets with clang + libFuzzer + ASan/UBSan, the whole metro
# library with coverage instrumentation (fuzz/CMakeLists.txt), and runs each target for a
# bounded time from its seeds. Prints libFuzzer's INITED/DONE lines and final stats, then one
# summary line per target, and fails when a target crashes, leaks, times out, trips a
# sanitizer, or counts fewer edges than its floor (a library built without coverage again).
#
# Usage: fuzz/run.sh [seconds per target, default 15] [target...]     (default: all targets)
# Environment: METRO_FUZZ_JOBS build jobs (default nproc); METRO_FUZZ_BUILD_DIR a build tree
# already configured with clang, -DMETRO_FUZZ=ON and -DMETRO_SANITIZE=ON to build the targets in
# (CI's sanitizer tree, so the library is compiled once for the tests and the fuzzers; default:
# build-fuzz/, configured here).
# Corpora grow in <build dir>/corpus/<target>/, crash reproducers land in
# <build dir>/artifacts/<target>/ (commit a reproducer under fuzz/crashes/<target>/).
# docs/security.md section 9 says what each target covers and how the floors were measured.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-15}"
shift || true

# target  max_len  edge floor. The floor applies to the larger of libFuzzer's cov: after
# the seeds (INITED) and at the end (DONE); it is about half of what the seeds alone reached
# with the instrumented library (docs/security.md section 9). The same targets linked to an
# uninstrumented library counted 39-73.
table="
session_fuzz       8192  1600
tag_registry_fuzz  4096   400
budget_fuzz       16384  1500
calibration_fuzz  32768  1200
report_fuzz       32768  2500
push_client_fuzz   2048   100
intel_hex_fuzz     4096   110
inspect_fuzz       4096   550
registry_fuzz     40960  1000
ros_log_fuzz      16384   850
dataflash_fuzz    16384   440
noise_config_fuzz  8192  1150
"
all_targets=$(awk 'NF {print $1}' <<<"$table")
targets="${*:-$all_targets}"

dir="${METRO_FUZZ_BUILD_DIR:-build-fuzz}"
if [ -n "${METRO_FUZZ_BUILD_DIR:-}" ]; then
  # A tree configured elsewhere: only one that instruments the library as build-fuzz/ does.
  for want in 'METRO_FUZZ:BOOL=ON' 'METRO_SANITIZE:BOOL=ON' 'CMAKE_CXX_COMPILER:.*clang'; do
    if ! grep -q "^$want" "$dir/CMakeCache.txt" 2>/dev/null; then
      echo "fuzz/run.sh: $dir/CMakeCache.txt lacks $want (configure it with clang," \
        "-DMETRO_FUZZ=ON and -DMETRO_SANITIZE=ON, or leave METRO_FUZZ_BUILD_DIR unset)" >&2
      exit 2
    fi
  done
else
  CC=clang CXX=clang++ cmake -S . -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" \
    -DMETRO_FUZZ=ON -DMETRO_SANITIZE=ON -DMETRO_BUILD_TESTS=OFF -DMETRO_BUILD_APPS=OFF \
    -DMETRO_BUILD_BENCH=OFF -DMETRO_BUILD_FIRMWARE=OFF \
    -DMETRO_MODULES="core;io;stats;uncertainty;noise;calibration;blob;sim;accuracy;report" > /dev/null
fi
# shellcheck disable=SC2086
cmake --build "$dir" -j"${METRO_FUZZ_JOBS:-$(nproc)}" --target $targets

# Seeds: the committed ones (fuzz/seeds/<target>/, hostile files from issue #20) plus
# datasets/.
seed() {
  local target=$1 corpus=$dir/corpus/$1
  mkdir -p "$corpus"
  if [ -d "fuzz/seeds/$target" ]; then cp fuzz/seeds/"$target"/* "$corpus/"; fi
  case "$target" in
    session_fuzz)
      cp datasets/static_chest.csv "$corpus/"
      head -c 4000 datasets/capture_15tags_receiver.txt > "$corpus/receiver.txt"
      head -c 4000 datasets/static_imu_100hz.csv > "$corpus/imu.csv"
      head -c 4000 datasets/table_sweep.csv > "$corpus/table_sweep.csv"
      # The other dialects and named formats (docs/formats.md).
      printf '#timestamp [ns],w_RS_S_x [rad s^-1],a_RS_S_z [m s^-2]\n1403636579758555392,0.1,9.8\n1.40363657976356E+018,0.2,9.7\n,,\nStep: 0.005,,\n' > "$corpus/euroc.csv"
      printf '\xef\xbb\xbfT_MS;GYRO_X (deg/s)\r\n0;1,5\r\n10;2,5\r\n' > "$corpus/semicolon.csv"
      printf 'Fs,100\nLogging Type,1\nax,ay,az,gx,gy,gz\n2508,-604,14684,-429,140,-53\n2744,-692,14772,-433,168,-75\n' > "$corpus/raw.csv"
      printf '"Time (s)"\t"Gyroscope x (rad/s)"\t"Absolute (rad/s)"\n2.35E-2\t1.25E-1\t1.25E-1\n' > "$corpus/phyphox.csv"
      printf 'time,seconds_elapsed,z,y,x\n1700000000000000000,0,0.3,0.2,0.1\n1700000000010000000,0.01,0.3,0.2,0.1\n' > "$corpus/sensorlogger.csv"
      ;;
    budget_fuzz) cp datasets/budgets/*.json "$corpus/" ;;
    # MCAP and ROS 1 samples of independent writers (datasets/external/ros_samples/SOURCE.md).
    ros_log_fuzz) cp datasets/external/ros_samples/*.mcap datasets/external/ros_samples/*.bag "$corpus/" ;;
    # A real ArduPlane log (datasets/external/ardupilot_pymavlink_test_bin/SOURCE.md).
    dataflash_fuzz) cp datasets/external/ardupilot_pymavlink_test_bin/test.BIN "$corpus/" ;;
    intel_hex_fuzz) cp datasets/golden/tag_sensor2.hex "$corpus/" ;;
    noise_config_fuzz) cp datasets/specs/specs.json "$corpus/" ;;
    # and the firmware blob fuzzer's sections v2.0 (issue #25, firmware/fuzz/make_seeds.py)
    inspect_fuzz) cp datasets/golden/tag_sensor2.hex datasets/golden/tag_sensor2.bin \
      firmware/fuzz/seeds/*.bin "$corpus/" ;;
  esac
}

export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1}"
# CLN (under GiNaC) keeps one small allocation it never frees: tests/lsan.supp.
export LSAN_OPTIONS="${LSAN_OPTIONS:-suppressions=$PWD/tests/lsan.supp:print_suppressions=0}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
mkdir -p "$dir/logs"
summary=()
failed=0
for target in $targets; do
  read -r max_len floor < <(awk -v t="$target" '$1 == t {print $2, $3}' <<<"$table")
  if [ -z "${floor:-}" ]; then
    echo "fuzz/run.sh: unknown target $target" >&2
    exit 2
  fi
  seed "$target"
  corpus=$dir/corpus/$target
  log=$dir/logs/$target.log
  mkdir -p "$dir/artifacts/$target"
  echo "== $target for ${seconds} s (seeds: $(find "$corpus" -type f | wc -l) files)"
  status=0
  "$dir"/fuzz/"$target" -max_total_time="$seconds" -max_len="$max_len" -timeout=10 \
    -rss_limit_mb=4096 -print_final_stats=1 -artifact_prefix="$dir/artifacts/$target/" \
    "$corpus" > "$log" 2>&1 || status=$?
  # The CI log shows the edges at start and end and the final stats.
  grep -E '^#[0-9]+[[:space:]]+(INITED|DONE)|^stat::' "$log" || true
  done_line=$(grep -E '^#[0-9]+[[:space:]]+DONE' "$log" | tail -n 1 || true)
  inited_cov=$( (grep -E '^#[0-9]+[[:space:]]+INITED' "$log" || true) | sed -n 's/.* cov: \([0-9]*\).*/\1/p')
  cov=$(sed -n 's/.* cov: \([0-9]*\).*/\1/p' <<<"$done_line")
  ft=$(sed -n 's/.* ft: \([0-9]*\).*/\1/p' <<<"$done_line")
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -n 1)
  files=$(find "$corpus" -type f | wc -l)
  seen=${cov:-0}
  if [ -n "$inited_cov" ] && [ "$inited_cov" -gt "$seen" ]; then seen=$inited_cov; fi
  verdict=""
  if [ "$status" -ne 0 ]; then
    verdict="FAILED (exit $status, see $log)"
    tail -n 60 "$log"
  fi
  if [ "$seen" -lt "$floor" ]; then
    verdict="${verdict:+$verdict; }FAILED (cov $seen below the floor $floor: is the library instrumented?)"
  fi
  verdict=${verdict:-ok}
  [ "$verdict" = ok ] || failed=1
  summary+=("$(printf 'fuzz: %-18s %3s s  cov %5s (inited %5s, floor %4s)  ft %6s  execs %8s  corpus %5s files  %s' \
    "$target" "$seconds" "${cov:--}" "${inited_cov:--}" "$floor" "${ft:--}" "${execs:--}" "$files" "$verdict")")
done
echo "== fuzz summary"
printf '%s\n' "${summary[@]}"
if [ "$failed" -ne 0 ]; then
  echo "fuzz/run.sh: a target failed; reproducers in $dir/artifacts/<target>/" >&2
  exit 1
fi
echo "fuzzing finished without findings"
