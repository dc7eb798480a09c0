#!/usr/bin/env bash
# Runs one "Worked examples" section of docs/cli.md (once in the README, hence the name) as
# written: the first ```sh block under the heading "### HEADING", in a scratch directory, with
# the example's `build/` and `datasets/` paths pointing at this build and this checkout. Fails
# when a command fails.
# Usage: tests/readme_example.sh SOURCE_DIR BUILD_DIR HEADING
set -euo pipefail
source_dir="$1"
build_dir="$2"
heading="$3"
doc="docs/cli.md"
block="$(awk -v h="### $heading" '
  $0 == h { inside = 1; next }
  inside && /^##/ { exit }
  inside && /^```sh$/ { code = 1; next }
  inside && code && /^```$/ { exit }
  inside && code { print }
' "$source_dir/$doc")"
if [ -z "$block" ]; then
  echo "readme_example: no \`\`\`sh block under '### $heading' in $doc" >&2
  exit 1
fi
scratch="$(mktemp -d "$build_dir/readme_example.XXXXXX")"
trap 'rm -rf "$scratch"' EXIT
cd "$scratch"
ln -s "$build_dir" build
ln -s "$source_dir/datasets" datasets
printf '%s\n' "== $doc: $heading" "$block"
# The block runs in its own process group, killed as a whole at the end: a program it left
# running (a simulator it started with `&`) would otherwise keep ctest's pipe open until the
# test's timeout.
setsid -w bash -euo pipefail -c "$block" &
block_pid=$!
trap 'kill -- -"$block_pid" 2>/dev/null || true; rm -rf "$scratch"' EXIT
wait "$block_pid"
echo "== $doc example '$heading': all commands succeeded"
