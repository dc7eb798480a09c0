#!/bin/sh
# Renders a calibration certificate in headless Chromium and checks that it renders and prints
# (rendered_page_check.sh): a non-blank 1200x2000 screenshot, no console message (the page has
# no script), the identification and traceability in the rendered DOM, and a printed PDF
# (--print-to-pdf) with at least one page.
# Usage: certificate_browser_check.sh CHROMIUM CALIBRATE SESSION WORKDIR
# Exit 0 when the certificate renders, 1 otherwise (with the reason on stderr).
set -eu
chromium=$1
calibrate=$2
session=$3
work=$4
mkdir -p "$work"
work=$(cd "$work" && pwd)
rm -f "$work/calibration.json" "$work/certificate.html"
printf '{"2": {"name": "Chest", "device_id": "12345678 9ABCDEF0", "profile": "mpu6050"}}\n' \
  > "$work/tags.json"

"$calibrate" fit "$session" --tags "$work/tags.json" --gravity-mps2 9.81 \
  -o "$work/calibration.json" --html "$work/certificate.html" 2> /dev/null

exec "$(dirname "$0")/rendered_page_check.sh" "$chromium" "$work/certificate.html" "$work" \
  "<title>Calibration certificate</title>|1. Identification|9ABCDEF012345678|Chest|\
9.81 m/s^2, given: calibrate fit --gravity-mps2 9.81|Metrological traceability|\
coverage factor k" 2 --pdf
