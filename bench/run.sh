#!/bin/bash
# `make bench`: runs every benchmark script of bench/ in turn; each prints its own table.
# Generated inputs go to bench/out/ (git-ignored). Pass names to run only some:
#   bench/run.sh build/meshflow stats simplify
set -uo pipefail
mf=$(realpath "${1:-build/meshflow}"); shift || true
here=$(cd "$(dirname "$0")" && pwd)
export MESHFLOW="$mf" BENCH_OUT="$here/out"
mkdir -p "$BENCH_OUT"
status=0
for script in "$here"/*_bench.sh; do
  name=$(basename "$script" _bench.sh)
  if [ $# -gt 0 ] && [[ ! " $* " == *" $name "* ]]; then continue; fi
  echo "== $name =="
  bash "$script" || { echo "bench $name failed"; status=1; }
  echo
done
exit $status
