#!/bin/sh
# Renders the budget page or the batch page in a real browser (headless Chromium) and checks
# that it renders (rendered_page_check.sh): a non-blank screenshot, no console message, and
# the expected headings and plots in the rendered DOM.
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

exec "$(dirname "$0")/rendered_page_check.sh" "$chromium" "$work/page.html" "$work" "$needles" \
  "$min_svgs"
