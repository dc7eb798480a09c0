#!/bin/sh
# Renders a generated session report in a real browser (headless Chromium) and checks that it
# renders (rendered_page_check.sh): a non-blank screenshot, no console message, the expected
# titles and at least 10 plots in the rendered DOM.
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

exec "$(dirname "$0")/rendered_page_check.sh" "$chromium" "$work/report.html" "$work" \
  "<title>Session report: |<h1>Session report: |Type A summary|Sensor 1|Allan deviation" 10
