#!/usr/bin/env bash
# Regenerates the bundled sample sessions from the simulator (docs/simulator.md).
# Usage: datasets/regenerate.sh [path/to/characterize] [path/to/calibrate]
set -euo pipefail
cd "$(dirname "$0")/.."
characterize="${1:-build/apps/characterize/characterize}"
here=datasets

# Thesis-like static chest tag (Table 8.3 experiment): sensor 2, ~10 Hz, 500 s.
"$characterize" simulate --seed 8 --sensor 2 --duration-s 500 \
  -o "$here/static_chest.csv"
"$characterize" simulate --seed 8 --sensor 2 --duration-s 500 --format receiver \
  -o "$here/static_chest_receiver.txt"
# A 15-tag capture as the central prints it; tag 13 never connects.
"$characterize" simulate --seed 15 --tags 15 --never 13 --duration-s 30 --packet-loss 0.05 \
  --format receiver -o "$here/capture_15tags_receiver.txt"
"$characterize" convert "$here/capture_15tags_receiver.txt" -o "$here/capture_15tags.csv"
# Raw IMU columns at 100 Hz (accelerometer, gyroscope, temperature), 60 s.
"$characterize" simulate --seed 3 --sensor 1 --columns imu --rate-hz 100 --duration-s 60 \
  --packet-loss 0   -o "$here/static_imu_100hz.csv"
# Golden calibration blob of sensor 2 (docs/calibration-blob.md): the C++ writer's output that the
# firmware host tests parse with the tag's C code. calibration_sensor2.json was fitted once by
# `calibrate fit` on a simulated session (datasets/golden/SOURCE.md) and is kept as is.
calibrate="${2:-build/apps/calibrate/calibrate}"
"$calibrate" blob "$here/golden/calibration_sensor2.json" --sensor 2 \
  --device-id 9ABCDEF012345678 --seq 3 \
  -o "$here/golden/tag_sensor2.bin" --hex "$here/golden/tag_sensor2.hex"
# Rotation-table sweep (accuracy, docs/accuracy.md): yaw 0..315 deg by 45, two sweeps.
"$characterize" simulate --kind table --seed 8 --sensor 2 --table-step-deg 45 --table-end-deg 315 \
  -o "$here/table_sweep.csv"
# Multi-pose calibration session in raw LSB (docs/simulator.md "Calibration sessions"): 26 poses,
# hand rotations, a 90 deg/s table run at every pose, 22 -> 34 degC; truth in the .truth.json.
"$characterize" simulate --kind calibration --seed 25 --sensor 2 \
  -o "$here/calibration_session.csv"
# Thermal session (docs/thermal.md, docs/simulator.md "Thermal sessions"): one pose, ramp
# -10 -> 35 -> -10 degC at 1 Hz, order-3 bias truth, hysteresis, three temperature read errors.
"$characterize" simulate --kind thermal --seed 42 --sensor 2 --rate-hz 1 --thermal-profile ramp \
  --ramp-s 1800 --cooling-leg --bias-order 3 --accel-hysteresis-g 0.004 \
  --gyro-hysteresis-dps 0.15 --temp-glitches 3 -o "$here/thermal_session.csv"
