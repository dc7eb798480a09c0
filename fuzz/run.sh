#!/usr/bin/env bash
# Builds the host-side parser fuzz targets (session loaders, push client) with clang + libFuzzer + ASan/UBSan and runs each for a
# bounded time. Usage: fuzz/run.sh [seconds per target, default 60]
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-60}"
CC=clang CXX=clang++ cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DMETRO_FUZZ=ON -DMETRO_SANITIZE=ON -DMETRO_BUILD_TESTS=OFF -DMETRO_BUILD_APPS=OFF \
  -DMETRO_BUILD_BENCH=OFF -DMETRO_BUILD_FIRMWARE=OFF -DMETRO_MODULES="core;io;stats;uncertainty;noise;calibration;blob" > /dev/null
cmake --build build-fuzz --target session_fuzz push_client_fuzz
corpus=build-fuzz/corpus/session
mkdir -p "$corpus"
cp datasets/static_chest.csv "$corpus/" 2>/dev/null || true
head -c 4000 datasets/capture_15tags_receiver.txt > "$corpus/receiver.txt"
head -c 4000 datasets/static_imu_100hz.csv > "$corpus/imu.csv"
# The other dialects and named formats (docs/formats.md).
printf '#timestamp [ns],w_RS_S_x [rad s^-1],a_RS_S_z [m s^-2]\n1403636579758555392,0.1,9.8\n1.40363657976356E+018,0.2,9.7\n,,\nStep: 0.005,,\n' > "$corpus/euroc.csv"
printf '\xef\xbb\xbfT_MS;GYRO_X (deg/s)\r\n0;1,5\r\n10;2,5\r\n' > "$corpus/semicolon.csv"
printf 'Fs,100\nLogging Type,1\nax,ay,az,gx,gy,gz\n2508,-604,14684,-429,140,-53\n2744,-692,14772,-433,168,-75\n' > "$corpus/raw.csv"
printf '"Time (s)"\t"Gyroscope x (rad/s)"\t"Absolute (rad/s)"\n2.35E-2\t1.25E-1\t1.25E-1\n' > "$corpus/phyphox.csv"
printf 'time,seconds_elapsed,z,y,x\n1700000000000000000,0,0.3,0.2,0.1\n1700000000010000000,0.01,0.3,0.2,0.1\n' > "$corpus/sensorlogger.csv"
build-fuzz/fuzz/session_fuzz -max_total_time="$seconds" -max_len=8192 -timeout=10 \
  -print_final_stats=1 "$corpus"
# The push client's answer parser (calibrate push), fed arbitrary tag answers.
mkdir -p build-fuzz/corpus/push
build-fuzz/fuzz/push_client_fuzz -max_total_time="$seconds" -max_len=2048 -timeout=10 \
  -print_final_stats=1 build-fuzz/corpus/push
