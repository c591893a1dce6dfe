#!/bin/bash
# What: `meshflow generate` streams synthetic meshes to disk in memory that does not grow with
# their size. Input: none; writes a terrain and a sphere of 1M, 10M and TRIANGLES (default 100M)
# triangles to $BENCH_OUT, reports wall time, peak RSS, the counts its header declares and the
# file size, then deletes them (~1.8 GB each at 100M). The floor beside it: `cp` of the same
# file in the same run (reading it back from the page cache and writing it again).
# Goal: peak RSS under 256 MB at 100M triangles.
set -euo pipefail
MF=${MESHFLOW:-build/meshflow}; OUT=${BENCH_OUT:-bench/out}; N=${TRIANGLES:-100000000}
mkdir -p "$OUT"
need=$(( N * 13 / 1000000 * 2 + N * 6 / 1000000 ))  # MB: triangles + vertices, file and copy
free=$(df -Pm "$OUT" | awk 'NR==2 {print $4}')
if [ "$free" -lt "$need" ]; then echo "generate bench: needs ~${need} MB free in $OUT, has ${free} MB; skipped"; exit 0; fi
echo "generate (streamed to disk)"
echo "| shape | triangles asked | vertices written | triangles written | wall s | peak RSS MB | file MB | cp s |"
echo "|---|---:|---:|---:|---:|---:|---:|---:|"
for n in 1000000 10000000 "$N"; do
  for shape in terrain sphere; do
    f=$OUT/gen_$shape.ply
    /usr/bin/time -f "%e %M" -o "$OUT/gen.time" "$MF" generate $shape --triangles "$n" -o "$f" >/dev/null
    read s kb < <(tail -n1 "$OUT/gen.time")
    # The counts the canonical header declares, checked against the file's size.
    read hlen v t < <(python3 -c "
h = open('$f', 'rb').read(400); h = h[:h.index(b'end_header\\n') + 11].decode()
print(len(h), h.split('element vertex ')[1].split()[0], h.split('element face ')[1].split()[0])")
    [ "$(stat -c %s "$f")" -eq $(( hlen + 12 * v + 13 * t )) ] || { echo "$f: size does not match its header"; exit 1; }
    p=$( { /usr/bin/time -f "%e" cp "$f" "$f.copy"; } 2>&1 )
    echo "| $shape | $n | $v | $t | $s | $((kb / 1024)) | $(( $(stat -c %s "$f") / 1048576 )) | $p |"
    rm -f "$f" "$f.copy"
  done
done
echo "goal: peak RSS under 256 MB at 100M triangles"
