#!/bin/sh
# Renders a generated session report in a real browser (headless Chromium) and checks that it
# renders (rendered_page_check.sh): a non-blank screenshot, no console message, the expected
# sections in the rendered DOM (the result first, the Type A details, the noise table, the
# options as a table, the combined x/y/z Allan plots) and at least 26 plots (six rate
# quantities with four plots each, two combined Allan plots); then that the DOM holds no raw
# options JSON string.
# Usage: browser_check.sh CHROMIUM CHARACTERIZE SESSION WORKDIR
# Exit 0 when the report renders, 1 otherwise (with the reason on stderr).
set -eu
chromium=$1
characterize=$2
session=$3
work=$4
mkdir -p "$work"
work=$(cd "$work" && pwd)
rm -f "$work/report.json" "$work/report.html"

"$characterize" "$session" --type-a --settle auto --allan -o "$work/report.json" \
  --html "$work/report.html" > /dev/null

"$(dirname "$0")/rendered_page_check.sh" "$chromium" "$work/report.html" "$work" \
  "<title>Session report: |<h1>Session report: |<h2>Result</h2>|id=\"result-1-gx_dps\"|Type A summary|<h2>Noise (Allan deviation)</h2>|id=\"noise-1-gx_dps\"|<table id=\"options-table\">|Sensor 1|Allan deviation, x, y and z axes together" 26
if grep -q '"skip_samples"' "$work/dom.html"; then
  echo "the rendered page shows the raw options JSON string" >&2
  exit 1
fi
