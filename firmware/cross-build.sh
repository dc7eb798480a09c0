#!/bin/sh
# Cross-compiles metro_fw for the tag (nRF51802, Cortex-M0) and checks its size.
#
# Usage: firmware/cross-build.sh [out_dir]     (default: a temporary directory)
#
# Flags: -mcpu=cortex-m0 -mthumb -Os plus -ffunction-sections -fdata-sections (so the
# link drops what the tag does not call), -fno-tree-loop-distribute-patterns (byte loops
# stay loops instead of calls to newlib's memcpy/memset: 300 bytes on the M0) and
# -fno-jump-tables (the push request dispatch as compares instead of a byte table and
# libgcc's __gnu_thumb1_case_uqi: 28 bytes). The tag's firmware build uses the same flags.
#
# Figures (docs/calibration-blob.md section 3.3), from the link map of a probe whose table
# references every public function, linked with --gc-sections, no startup files:
#   own       the library's code + data;
#   runtime   libgcc integer helpers and newlib-nano routines the library pulls in (none
#             since issue #6's fourth step: the 64-bit products go through the library's own
#             metro_fw_mul instead of __aeabi_lmul, and -fno-jump-tables drops the switch
#             helper);
#   softfloat libgcc's binary32 routines (only the float apply and float temperature use them;
#             the limit checks at load work on fixed-point integers converted from the bits).
# Gates: (1) the boot/update core (le + crc + blob + update objects) < 4096 bytes;
#        (2) the integer-only library (every public function but the float apply and float
#            temperature), own + runtime + soft-float (0), below METRO_FW_LIMIT (4608: issue
#            #6 set 4096; issue #20's sensor checks in the validator cost 176 bytes more, see
#            docs/calibration-blob.md section 3.3; issue #23's plausibility limits 64 more;
#            issue #25's sections v2.0 (declared s_nom and input) 196 more, limit 4608)
#            and not above METRO_FW_WHOLE_LIMIT (a ratchet, the last measured figure);
#        (3) the float build of a tag (every public function but the fixed-point apply and
#            Q12 temperature): the library's own code + data below METRO_FW_LIMIT (libgcc's
#            binary32 routines, which any float code on the M0 links, are printed beside it).
set -eu

here=$(cd "$(dirname "$0")" && pwd)
out=${1:-$(mktemp -d)}
mkdir -p "$out"
cc=${CC_ARM:-arm-none-eabi-gcc}
arch="-mcpu=cortex-m0 -mthumb -Os -ffunction-sections -fdata-sections"
arch="$arch -fno-tree-loop-distribute-patterns -fno-jump-tables"
flags="-std=c99 $arch -Wall -Wextra -pedantic -Werror"
whole_limit=${METRO_FW_WHOLE_LIMIT:-4496}
limit=${METRO_FW_LIMIT:-4608}

objs=""
for src in le crc blob update push fixed; do
  $cc $flags -I"$here/include" -c "$here/src/$src.c" -o "$out/$src.o"
  objs="$objs $out/$src.o"
done
rm -f "$out/libmetro_fw.a"
arm-none-eabi-ar rcs "$out/libmetro_fw.a" $objs

echo "== metro_fw objects ($arch)"
arm-none-eabi-size -t $objs

# Links a probe whose table `keep` holds the functions given; prints the map summary.
probe() {
  name=$1
  shift
  {
    echo '#include "metro_fw/blob.h"'
    echo '#include "metro_fw/crc.h"'
    echo '#include "metro_fw/fixed.h"'
    echo '#include "metro_fw/push.h"'
    echo '#include "metro_fw/update.h"'
    echo 'typedef void (*fn)(void);'
    echo 'void Reset_Handler(void);'
    printf '__attribute__((used)) const fn keep[] = {'
    for f in "$@"; do printf '(fn)%s, ' "$f"; done
    echo '0};'
    echo 'void Reset_Handler(void) { for (;;) { } }'
  } > "$out/size_probe.c"
  # -pedantic is dropped for the probe only: ISO C forbids converting function pointers.
  $cc -std=c99 $arch -Wall -Wextra -Werror -I"$here/include" -c "$out/size_probe.c" \
      -o "$out/size_probe.o"
  $cc -mcpu=cortex-m0 -mthumb --specs=nano.specs -nostartfiles -Wl,--gc-sections \
      -Wl,-e,Reset_Handler -Wl,--undefined=keep -Wl,-Map="$out/$name.map" \
      -o "$out/$name.elf" "$out/size_probe.o" "$out/libmetro_fw.a" -lc -lgcc
  awk -f "$here/size_map.awk" "$out/$name.map"
}

common="metro_fw_crc32 metro_fw_crc16 metro_fw_buffer_read
  metro_fw_blob_validate
  metro_fw_sensor_defaults metro_fw_sensor_decode metro_fw_load metro_fw_update
  metro_fw_push_init metro_fw_push_rx metro_fw_frame_encode metro_fw_frame_parse"
fixed="metro_fw_fixed_from_cal metro_fw_apply_fixed metro_fw_mpu6050_temp_q12"
float="metro_fw_apply metro_fw_mpu6050_temp_c"

# shellcheck disable=SC2086
whole=$(probe whole $common $fixed $float)
# shellcheck disable=SC2086
nofloat=$(probe nofloat $common $fixed)
# shellcheck disable=SC2086
floattag=$(probe floattag $common $float)
echo "== linked, every public function:              $whole"
echo "== linked, without the float apply/temperature: $nofloat"
echo "== linked, without the fixed-point apply:       $floattag"
get() { echo "$1" | tr ' ' '\n' | sed -n "s/^$2=//p"; }
whole_fig=$(($(get "$whole" own) + $(get "$whole" runtime)))
int_fig=$(($(get "$nofloat" own) + $(get "$nofloat" runtime) + $(get "$nofloat" softfloat)))
echo "whole library own + runtime = $whole_fig bytes;" \
  "the float apply/temperature add $(get "$whole" softfloat) bytes of soft-float"
echo "integer-only library own + runtime + soft-float = $int_fig bytes" \
  "(limit $limit, ratchet $whole_limit)"
float_fig=$(($(get "$floattag" own) + $(get "$floattag" runtime)))
echo "float library own + integer runtime = $float_fig bytes (limit $limit;" \
  "plus $(get "$floattag" softfloat) bytes of libgcc soft-float)"

core=$(arm-none-eabi-size -t "$out/le.o" "$out/crc.o" "$out/blob.o" "$out/update.o" |
  awk 'END { print $1 + $2 }')
echo "core (le + crc + blob + update) code + data = $core bytes (limit 4096)"
status=0
if [ "$core" -ge 4096 ]; then
  echo "FAIL: metro_fw core code + data is $core bytes, must stay below 4096" >&2
  status=1
fi
if [ "$int_fig" -ge "$limit" ]; then
  echo "FAIL: integer-only metro_fw is $int_fig bytes, must stay below $limit" >&2
  status=1
fi
if [ "$float_fig" -ge "$limit" ]; then
  echo "FAIL: the float build of metro_fw is $float_fig bytes of its own, must stay below $limit" >&2
  status=1
fi
if [ "$int_fig" -gt "$whole_limit" ]; then
  echo "FAIL: integer-only metro_fw is $int_fig bytes, ratchet is $whole_limit" >&2
  status=1
fi
[ "$status" -eq 0 ] && echo "OK"
exit "$status"
