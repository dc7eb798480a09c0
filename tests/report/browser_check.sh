#!/bin/sh
# Renders a generated HTML report in a real browser (headless Chromium) and checks that
# it renders: a non-blank screenshot, and the expected titles and plots in the rendered DOM.
# Usage: browser_check.sh CHROMIUM CHARACTERIZE SESSION WORKDIR
# Exit 0 when the report renders, 1 otherwise (with the reason on stderr).
set -eu
chromium=$1
characterize=$2
session=$3
work=$4
mkdir -p "$work"
work=$(cd "$work" && pwd)
rm -f "$work/report.json" "$work/report.html" "$work/report.png" "$work/dom.html"

"$characterize" "$session" --type-a --settle auto --allan -o "$work/report.json" \
  --html "$work/report.html" > /dev/null

# A throw-away profile, no GPU, no sandbox (containers), no network needed.
run_chromium() {
  timeout 120 "$chromium" --headless --no-sandbox --disable-gpu --no-first-run \
    --user-data-dir="$work/profile" --window-size=1200,2000 "$@" 2> "$work/chromium.log"
}
run_chromium --screenshot="$work/report.png" "file://$work/report.html" > /dev/null
run_chromium --dump-dom "file://$work/report.html" > "$work/dom.html"

/usr/bin/python3 - "$work/report.png" "$work/dom.html" <<'PY'
import struct, sys, zlib

png_path, dom_path = sys.argv[1], sys.argv[2]
data = open(png_path, "rb").read()
if data[:8] != b"\x89PNG\r\n\x1a\n":
    sys.exit("screenshot is not a PNG")
pos, idat, width, height = 8, b"", 0, 0
while pos < len(data):
    length, kind = struct.unpack(">I4s", data[pos:pos + 8])
    body = data[pos + 8:pos + 8 + length]
    if kind == b"IHDR":
        width, height = struct.unpack(">II", body[:8])
    elif kind == b"IDAT":
        idat += body
    pos += 12 + length
if (width, height) != (1200, 2000):
    sys.exit("screenshot is %dx%d, expected 1200x2000" % (width, height))
raw = zlib.decompress(idat)
# A blank page is one colour: its filtered scanlines are almost all one byte value. A
# rendered report (header bar, tables, plots, text) is far from that.
counts = [0] * 256
for b in raw[::7]:  # A sample is plenty and keeps this fast.
    counts[b] += 1
total = sum(counts)
other = 1.0 - max(counts) / total
distinct = sum(1 for c in counts if c)
if other < 0.02 or distinct < 64:
    sys.exit("screenshot looks blank: %.4f of the bytes differ from the commonest, %d distinct"
             % (other, distinct))

dom = open(dom_path, encoding="utf-8").read()
for needle in ("<title>Session report: ", "<h1>Session report: ", "Type A summary",
               "Sensor 1", "Allan deviation"):
    if needle not in dom:
        sys.exit("rendered DOM lacks %r" % needle)
svgs = dom.count("<svg")
if svgs < 10:
    sys.exit("rendered DOM has %d plots, expected at least 10" % svgs)
print("report renders: %dx%d screenshot, %.3f non-background, %d plots in the DOM"
      % (width, height, other, svgs))
PY
