#!/bin/bash
# What: `meshflow generate` streams synthetic meshes to disk in memory that does not grow with
# their size. Input: none; writes a terrain and a sphere of TRIANGLES (default 100M) triangles to
# $BENCH_OUT, reports wall time, peak RSS and file size, then deletes them (they are ~2.5 GB each).
# The floor beside it: `cat FILE > /dev/null` and `cp` of the same file in the same run.
set -euo pipefail
MF=${MESHFLOW:-build/meshflow}; OUT=${BENCH_OUT:-bench/out}; N=${TRIANGLES:-100000000}
mkdir -p "$OUT"
need=$(( N * 13 / 1000000 * 2 + N * 6 / 1000000 ))  # MB: triangles + vertices, file and copy
free=$(df -Pm "$OUT" | awk 'NR==2 {print $4}')
if [ "$free" -lt "$need" ]; then echo "generate bench: needs ~${need} MB free in $OUT, has ${free} MB; skipped"; exit 0; fi
echo "generate, $N triangles"
echo "| shape | wall s | peak RSS MB | file MB | cat s | cp s |"
echo "|---|---:|---:|---:|---:|---:|"
for shape in terrain sphere; do
  f=$OUT/gen_$shape.ply
  /usr/bin/time -f "%e %M" -o "$OUT/gen.time" "$MF" generate $shape --triangles "$N" -o "$f" >/dev/null
  read s kb <"$OUT/gen.time"
  c=$( { /usr/bin/time -f "%e" cat "$f" >/dev/null; } 2>&1 )
  p=$( { /usr/bin/time -f "%e" cp "$f" "$f.copy"; } 2>&1 )
  echo "| $shape | $s | $((kb/1024)) | $(( $(stat -c %s "$f") / 1048576 )) | $c | $p |"
  rm -f "$f" "$f.copy"
done
echo "goal: peak RSS under 256 MB at 100M triangles"
