#!/bin/bash
# Runs every fuzz target in DIR for SECONDS each, seeded from tests/fuzz/corpus/<name> (and
# the shared meshes for the mesh readers). Fails on the first crash; the crashing input is
# kept under DIR/crashes/ to become a named regression case.
set -euo pipefail
dir=${1:?usage: run.sh BUILD_DIR SECONDS}
seconds=${2:-20}
here=$(cd "$(dirname "$0")" && pwd)
shopt -s nullglob
status=0
for fuzzer in "$dir"/fuzz_*; do
  [ -x "$fuzzer" ] || continue
  name=${fuzzer##*/fuzz_}
  work=$dir/corpus-work/$name; mkdir -p "$work" "$dir/crashes"
  seeds=("$work")
  [ -d "$here/corpus/$name" ] && seeds+=("$here/corpus/$name")
  # Small shared meshes of the reader's format seed it too (binary layouts included).
  shared="$here/../../../shared/data/meshes"
  if [ -d "$shared" ]; then
    mkdir -p "$work/shared"
    find "$shared" -type f -size -64k \( -iname "*.$name" -o -name "*" -a -path "*$name*" \) \
      -exec cp -f {} "$work/shared/" \; 2>/dev/null || true
    [ "$name" = mesh ] && find "$shared" -type f -size -64k -exec cp -f {} "$work/shared/" \; 2>/dev/null
  fi
  echo "fuzz: $name for ${seconds}s"
  if ! timeout $((seconds + 120)) "$fuzzer" -max_total_time="$seconds" -max_len=65536 -rss_limit_mb=2048 \
       -artifact_prefix="$dir/crashes/$name-" -print_final_stats=0 "${seeds[@]}" >"$dir/$name.log" 2>&1; then
    echo "fuzz: $name FAILED; see $dir/$name.log"; tail -n 30 "$dir/$name.log"; status=1
  fi
done
exit $status
