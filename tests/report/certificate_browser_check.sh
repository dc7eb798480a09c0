#!/bin/sh
# Renders a calibration certificate in headless Chromium and checks that it renders and prints:
# a non-blank 1200x2000 screenshot, no console message (the page has no script), the identification
# and traceability in the rendered DOM, and a printed PDF (--print-to-pdf) with at least one
# page. Usage: certificate_browser_check.sh CHROMIUM CALIBRATE SESSION WORKDIR
# Exit 0 when the certificate renders, 1 otherwise (with the reason on stderr).
set -eu
chromium=$1
calibrate=$2
session=$3
work=$4
mkdir -p "$work"
work=$(cd "$work" && pwd)
rm -f "$work/calibration.json" "$work/certificate.html" "$work/certificate.png" \
  "$work/dom.html" "$work/certificate.pdf" "$work/console.log"
printf '{"2": {"name": "Chest", "device_id": "12345678 9ABCDEF0", "profile": "mpu6050"}}\n' \
  > "$work/tags.json"

"$calibrate" fit "$session" --tags "$work/tags.json" --gravity-mps2 9.81 \
  -o "$work/calibration.json" --html "$work/certificate.html" 2> /dev/null

# A throw-away profile, no GPU, no sandbox (containers), no network needed; console messages
# go to stderr with --enable-logging.
run_chromium() {
  timeout 120 "$chromium" --headless --no-sandbox --disable-gpu --no-first-run \
    --user-data-dir="$work/profile" --window-size=1200,2000 --enable-logging=stderr --v=0 "$@"
}
run_chromium --screenshot="$work/certificate.png" "file://$work/certificate.html" \
  > /dev/null 2> "$work/console.log"
run_chromium --dump-dom "file://$work/certificate.html" > "$work/dom.html" 2>> "$work/console.log"
run_chromium --no-pdf-header-footer --print-to-pdf="$work/certificate.pdf" \
  "file://$work/certificate.html" > /dev/null 2>> "$work/console.log"

/usr/bin/python3 - "$work/certificate.png" "$work/dom.html" "$work/certificate.pdf" \
  "$work/console.log" <<'PY'
import re, struct, sys, zlib

png_path, dom_path, pdf_path, console_path = sys.argv[1:5]
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

console = open(console_path, encoding="utf-8", errors="replace").read()
# The page has no script: any console message (Chromium logs console.error at INFO level as
# "INFO:CONSOLE:...") is an error.
errors = [l for l in console.splitlines() if ":CONSOLE" in l]
if errors:
    sys.exit("console messages:\n" + "\n".join(errors[:5]))

dom = open(dom_path, encoding="utf-8").read()
for needle in ("<title>Calibration certificate</title>", "1. Identification", "9ABCDEF012345678",
               "Chest", "9.81 m/s^2, given: calibrate fit --gravity-mps2 9.81",
               "Metrological traceability", "coverage factor k"):
    if needle not in dom:
        sys.exit("rendered DOM lacks %r" % needle)
if dom.count("<svg") < 2:
    sys.exit("rendered DOM has %d plots, expected 2" % dom.count("<svg"))

pdf = open(pdf_path, "rb").read()
if not pdf.startswith(b"%PDF"):
    sys.exit("print-to-pdf wrote no PDF")
pages = len(re.findall(rb"/Type\s*/Page(?!s)", pdf))
if pages < 1:
    sys.exit("the printed PDF has no page")
print("certificate renders: %dx%d screenshot, %.3f non-background, %d plots, %d printed pages"
      % (width, height, other, dom.count("<svg"), pages))
PY
