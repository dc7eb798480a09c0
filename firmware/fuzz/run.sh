#!/bin/sh
# Builds the metro_fw libFuzzer targets with clang-14 (-fsanitize=fuzzer,address,undefined)
# and runs each for a bounded time; fuzz_blob starts from the golden blob and the committed
# seeds of firmware/fuzz/seeds/ (python3 firmware/fuzz/make_seeds.py).
#
# Usage: firmware/fuzz/run.sh [seconds_per_target] [out_dir]     (defaults: 60, a temp dir)
# Exit status: non-zero if a target crashes, leaks or trips a sanitizer.
set -eu

here=$(cd "$(dirname "$0")" && pwd)
fw="$here/.."
seconds=${1:-60}
out=${2:-$(mktemp -d)}
mkdir -p "$out"
cc=${CLANG:-/usr/bin/clang-14}
flags="-std=c99 -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined"
srcs="$fw/src/le.c $fw/src/crc.c $fw/src/blob.c $fw/src/update.c $fw/src/push.c $fw/src/fixed.c"

for target in fuzz_blob fuzz_frame; do
  $cc $flags -I"$fw/include" "$here/$target.c" $srcs -o "$out/$target"
  mkdir -p "$out/corpus_$target"
  if [ "$target" = fuzz_blob ]; then
    # seeds: the golden blob (C++ writer) and sections v2.0 (firmware/fuzz/make_seeds.py)
    cp "$fw/../datasets/golden/tag_sensor2.bin" "$here"/seeds/*.bin "$out/corpus_$target/"
  fi
  echo "== $target for ${seconds} s"
  "$out/$target" -max_total_time="$seconds" -max_len=2048 -print_final_stats=1 \
    "$out/corpus_$target"
done
echo "fuzzing finished without findings"
