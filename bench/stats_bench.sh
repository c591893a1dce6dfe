#!/bin/bash
# What: reading a large binary PLY and computing every analysis measure (DESIGN §5), meshflow
# `stats` against MeshLab's meshlabserver loading the same file and running its "Compute
# Topological Measures" and "Compute Geometric Measures" filters. Both whole processes, same run.
# Input: a generated 10M-triangle fractal terrain (TRIANGLES to change), binary PLY.
# Prints wall time, peak RSS, bytes of peak memory per triangle, and the ratio.
set -euo pipefail
MF=${MESHFLOW:-build/meshflow}; OUT=${BENCH_OUT:-bench/out}; N=${TRIANGLES:-10000000}
mkdir -p "$OUT"
IN=$OUT/terrain_$N.ply
[ -f "$IN" ] || "$MF" generate terrain --triangles "$N" -o "$IN" >/dev/null
T=$("$MF" stats --json "$IN" | python3 -c 'import json,sys; print(json.load(sys.stdin)["NumberOfTriangles"])')

run() { local label=$1; shift; /usr/bin/time -f "%e %M" -o "$OUT/$label.time" "$@" >"$OUT/$label.log" 2>&1 || { echo "$label failed:"; tail -5 "$OUT/$label.log"; return 1; }; cat "$OUT/$label.time"; }

read mf_s mf_kb < <(run meshflow "$MF" stats "$IN")
cat >"$OUT/measures.mlx" <<'MLX'
<!DOCTYPE FilterScript>
<FilterScript>
 <filter name="Compute Topological Measures"/>
 <filter name="Compute Geometric Measures"/>
</FilterScript>
MLX
if command -v meshlabserver >/dev/null; then
  read ml_s ml_kb < <(run meshlab xvfb-run -a meshlabserver -i "$IN" -s "$OUT/measures.mlx")
else
  ml_s=nan; ml_kb=0; echo "meshlabserver not installed (make bench installs it)"
fi
python3 - "$T" "$mf_s" "$mf_kb" "$ml_s" "$ml_kb" <<'PY'
import sys
t, mf_s, mf_kb, ml_s, ml_kb = int(sys.argv[1]), float(sys.argv[2]), int(sys.argv[3]), float(sys.argv[4]), int(sys.argv[5])
print(f"read + all measures, {t:,} triangles (binary PLY)")
print(f"| program | wall s | peak RSS MB | bytes/triangle |")
print(f"|---|---:|---:|---:|")
print(f"| meshflow stats | {mf_s:.2f} | {mf_kb/1024:.0f} | {mf_kb*1024/t:.1f} |")
if ml_kb: print(f"| meshlabserver topological + geometric measures | {ml_s:.2f} | {ml_kb/1024:.0f} | {ml_kb*1024/t:.1f} |")
if ml_kb: print(f"speed-up: {ml_s/mf_s:.2f}x (goal >= 3x); meshflow memory {mf_kb*1024/t:.1f} B/triangle (goal < 60)")
PY
