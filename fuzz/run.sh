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
build-fuzz/fuzz/session_fuzz -max_total_time="$seconds" -max_len=8192 -timeout=10 \
  -print_final_stats=1 "$corpus"
# The push client's answer parser (calibrate push), fed arbitrary tag answers.
mkdir -p build-fuzz/corpus/push
build-fuzz/fuzz/push_client_fuzz -max_total_time="$seconds" -max_len=2048 -timeout=10 \
  -print_final_stats=1 build-fuzz/corpus/push
