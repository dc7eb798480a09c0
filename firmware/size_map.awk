# Sums the flash bytes (.text, .rodata, .data input sections) of a GNU ld map by origin:
#   own       = libmetro_fw.a; probe = size_probe.o (the reference table and entry);
#   softfloat = libgcc's binary32 routines (add/sub/mul, compares, int-to-float, clz);
#   runtime   = everything else linked (libgcc integer helpers, newlib-nano).
# Usage: awk [-v verbose=1] -f size_map.awk probe.map   (POSIX awk; mawk has no strtonum)
/^Linker script and memory map/ { on = 1; next }
!on { next }
/^ \.[A-Za-z_.0-9$-]+ *$/ { pending = $1; next }
{
  if (pending != "" && $1 ~ /^0x/ && NF >= 3) { name = pending; addr = $1; size = $2; file = $3 }
  else if ($1 ~ /^\./ && $2 ~ /^0x/ && NF >= 4) { name = $1; addr = $2; size = $3; file = $4 }
  else { pending = ""; next }
  pending = ""
  if (name !~ /^\.(text|rodata|data)/) next
  n = Hex(size); if (n == 0) next
  if (file ~ /size_probe\.o/) cls = "probe"
  else if (file ~ /libmetro_fw\.a/) cls = "own"
  else if (file ~ /(sf[0-9]|sisf|sfsi|cmpsf|_clzsi2)/) cls = "softfloat"
  else cls = "runtime"
  sum[cls] += n
  sub(/.*\(/, "", file); sub(/\)$/, "", file)
  if (verbose) printf "  %-10s %5d  %s %s\n", cls, n, name, file
}
END { printf "own=%d runtime=%d softfloat=%d probe=%d\n", sum["own"], sum["runtime"], sum["softfloat"], sum["probe"] }
function Hex(s,   i, c, v) {
  v = 0; s = tolower(substr(s, 3))
  for (i = 1; i <= length(s); ++i) { c = index("0123456789abcdef", substr(s, i, 1)) - 1; v = v * 16 + c }
  return v
}
