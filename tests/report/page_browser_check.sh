#!/bin/sh
# Renders the budget page or the batch page in a real browser (headless Chromium) and checks
# that it renders: a non-blank screenshot, no console message, and the expected headings and
# plots in the rendered DOM.
# Usage: page_browser_check.sh CHROMIUM CHARACTERIZE budget|batch SOURCE_DIR WORKDIR
# Exit 0 when the page renders, 1 otherwise (with the reason on stderr).
set -eu
chromium=$1
characterize=$2
kind=$3
source_dir=$4
work=$5
rm -rf "$work"
mkdir -p "$work"
work=$(cd "$work" && pwd)

case "$kind" in
budget)
  "$characterize" budget "$source_dir/datasets/budgets/gum_h1_end_gauge.json" -q \
    -o "$work/budget.report.json" --html "$work/page.html" > /dev/null
  needles="<h2>Result</h2>|id=\"statement\"|GUF NOT validated|Distribution for l|<h2>Contributions</h2>"
  min_svgs=2
  ;;
batch)
  "$characterize" batch "$source_dir/datasets/static_chest.csv" \
    "$source_dir/datasets/static_imu_100hz.csv" "$source_dir/datasets/capture_15tags.csv" -q \
    -o "$work/out" --html "$work/page.html" > /dev/null
  needles="<h1>Batch summary</h1>|Sessions and tags|Spread across sessions|href=\"out/static_chest.report.html\""
  min_svgs=10
  ;;
*)
  echo "unknown page kind $kind" >&2
  exit 1
  ;;
esac

# A throw-away profile, no GPU, no sandbox (containers), no network needed; console messages
# go to the log (--enable-logging=stderr).
run_chromium() {
  timeout 120 "$chromium" --headless --no-sandbox --disable-gpu --no-first-run \
    --enable-logging=stderr --v=0 --user-data-dir="$work/profile" --window-size=1200,2000 \
    "$@" 2>> "$work/chromium.log"
}
run_chromium --screenshot="$work/page.png" "file://$work/page.html" > /dev/null
run_chromium --dump-dom "file://$work/page.html" > "$work/dom.html"

/usr/bin/python3 - "$work/page.png" "$work/dom.html" "$work/chromium.log" "$needles" \
  "$min_svgs" <<'PY'
import struct, sys, zlib

png_path, dom_path, log_path, needles, min_svgs = sys.argv[1:6]
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
counts = [0] * 256
for b in raw[::7]:
    counts[b] += 1
other = 1.0 - max(counts) / sum(counts)
distinct = sum(1 for c in counts if c)
if other < 0.02 or distinct < 64:
    sys.exit("screenshot looks blank: %.4f of the bytes differ from the commonest, %d distinct"
             % (other, distinct))
console = [l for l in open(log_path, encoding="utf-8", errors="replace") if ":CONSOLE" in l]
if console:
    sys.exit("the page wrote to the console:\n" + "".join(console[:5]))
dom = open(dom_path, encoding="utf-8").read()
for needle in needles.split("|"):
    if needle not in dom:
        sys.exit("rendered DOM lacks %r" % needle)
svgs = dom.count("<svg")
if svgs < int(min_svgs):
    sys.exit("rendered DOM has %d plots, expected at least %s" % (svgs, min_svgs))
print("page renders: %dx%d screenshot, %.3f non-background, %d plots, no console message"
      % (width, height, other, svgs))
PY
