#!/bin/bash
# What: the thesis's repair pipeline (RemoveSmallestComponents -> LaplacianSmoothing ->
# FillHoles -> RemoveDegenerateTriangles, thesis Table 4.3) on the shared scans, step by step:
# the size of each step's output compressed (canonical PLY, zstd -19) against the size of its
# correction (.mfc), and that the correction reproduces the output bit for bit.
# Goal: local steps' corrections under 1% of the compressed output; LaplacianSmoothing's under 35%.
set -uo pipefail
MF=${MESHFLOW:-build/meshflow}; OUT=${BENCH_OUT:-bench/out}/repair
SHARED=$(cd "$(dirname "$0")/../../shared/data/meshes" && pwd)
mkdir -p "$OUT"
echo "| scan | step | output zstd-19 bytes | correction bytes | ratio | bit-exact |"
echo "|---|---|---:|---:|---:|---|"
for scan in real/stanford-bunny.obj real/ogre.obj real/dragon_100k.ply real/igea_tristrips.ply defects/dragon_38k_holes.ply; do
  name=$(basename "${scan%.*}")
  current=$SHARED/$scan
  i=0
  for step in RemoveSmallestComponents "LaplacianSmoothing --param iterations=1" FillHoles RemoveDegenerateTriangles; do
    op=${step%% *}; i=$((i + 1))
    out=$OUT/$name.$i.ply; mfc=$OUT/$name.$i.mfc
    if ! "$MF" op $step "$current" -o "$out" --correction "$mfc" 2>"$OUT/err.txt"; then
      echo "| $name | $op | failed: $(head -c 80 "$OUT/err.txt") | | | |"; break
    fi
    zstd -q -19 -f "$out" -o "$out.zst"
    "$MF" patch "$current" "$mfc" -o "$out.patched.ply" 2>/dev/null && cmp -s "$out" "$out.patched.ply" && exact=yes || exact=NO
    z=$(stat -c %s "$out.zst"); c=$(stat -c %s "$mfc")
    echo "| $name | $op | $z | $c | $(python3 -c "print(f'{100*$c/$z:.2f}%')") | $exact |"
    current=$out
  done
done
