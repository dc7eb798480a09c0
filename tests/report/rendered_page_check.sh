#!/bin/sh
# The one check that a metro page renders in a real browser (headless Chromium), used by the
# session, budget, batch and certificate checks: a non-blank 1200x2000 screenshot, no console
# message (Chromium logs console.error at INFO level as "INFO:CONSOLE:..."; metro's pages have
# no script), the expected text in the rendered DOM, at least MIN_SVGS plots, and with --pdf
# a printed PDF with at least one page.
# Usage: rendered_page_check.sh CHROMIUM PAGE.html WORKDIR 'NEEDLE|NEEDLE|...' MIN_SVGS [--pdf]
# Exit 0 when the page renders (one line on stdout), 1 otherwise (the reason on stderr).
set -eu
chromium=$1
page=$2
work=$3
needles=$4
min_svgs=$5
pdf=${6:-}
mkdir -p "$work"
work=$(cd "$work" && pwd)
rm -rf "$work/profile" "$work/page.png" "$work/dom.html" "$work/page.pdf" "$work/chromium.log"

# A throw-away profile, no GPU, no sandbox (containers), no network needed; console messages
# go to the log.
run_chromium() {
  timeout 120 "$chromium" --headless --no-sandbox --disable-gpu --no-first-run \
    --enable-logging=stderr --v=0 --user-data-dir="$work/profile" --window-size=1200,2000 \
    "$@" 2>> "$work/chromium.log"
}
run_chromium --screenshot="$work/page.png" "file://$page" > /dev/null
run_chromium --dump-dom "file://$page" > "$work/dom.html"
if [ "$pdf" = "--pdf" ]; then
  run_chromium --no-pdf-header-footer --print-to-pdf="$work/page.pdf" "file://$page" > /dev/null
fi

/usr/bin/python3 - "$work/page.png" "$work/dom.html" "$work/chromium.log" "$needles" \
  "$min_svgs" "$work/page.pdf" "$pdf" <<'PY'
import re, struct, sys, zlib

png_path, dom_path, log_path, needles, min_svgs, pdf_path, want_pdf = sys.argv[1:8]
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
# rendered page (header bar, tables, plots, text) is far from that.
counts = [0] * 256
for b in raw[::7]:  # A sample is plenty and keeps this fast.
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
pages = ""
if want_pdf == "--pdf":
    pdf = open(pdf_path, "rb").read()
    if not pdf.startswith(b"%PDF"):
        sys.exit("print-to-pdf wrote no PDF")
    n = len(re.findall(rb"/Type\s*/Page(?!s)", pdf))
    if n < 1:
        sys.exit("the printed PDF has no page")
    pages = ", %d printed pages" % n
print("page renders: %dx%d screenshot, %.3f non-background, %d plots, no console message%s"
      % (width, height, other, svgs, pages))
PY
