#!/bin/bash
# What: Simplify (QEM edge collapse, meshflow) against the peers available from Debian on the same
# inputs and output vertex counts: MeshLab's Quadric Edge Collapse Decimation (meshlabserver,
# optimal placement, preserve boundary), OpenMesh's commandline decimater (quadric module),
# CGAL's edge_collapse with Garland-Heckbert plane policies and meshoptimizer's simplifier
# (bench/cgal_simplify, bench/meshopt_simplify). Inputs: the shared scans at 5k/10k/20k vertices,
# a generated 2M-triangle terrain and 5M-triangle sphere at 1% of their vertices.
# Figures: wall time and peak RSS of each whole process; mean error = the mean of meshflow
# compare's mean_ab and mean_ba (% of the input's diagonal). SMALL=1 runs the scans only, BIG=1
# the generated meshes only.
set -uo pipefail
MF=$(realpath "${MESHFLOW:-build/meshflow}"); OUT=${BENCH_OUT:-bench/out}/simplify; BIN=$(dirname "$MF")/bench
SHARED=$(cd "$(dirname "$0")/../../shared/data/meshes" && pwd)
mkdir -p "$OUT"
TIMEOUT=${TIMEOUT:-900}

inputs=()
scans=(real/stanford-bunny.obj real/dragon_100k.ply real/igea_tristrips.ply)
[ -n "${BIG:-}" ] && scans=()
for scan in "${scans[@]}"; do
  name=$(basename "${scan%.*}")
  [ -f "$OUT/$name.ply" ] || "$MF" convert "$SHARED/$scan" "$OUT/$name.ply"
  for v in 5000 10000 20000; do inputs+=("$name:$v"); done
done
if [ -z "${SMALL:-}" ]; then
  [ -f "$OUT/terrain2m.ply" ] || "$MF" generate terrain --triangles 2000000 -o "$OUT/terrain2m.ply" >/dev/null
  [ -f "$OUT/sphere5m.ply" ] || "$MF" generate sphere --triangles 5000000 -o "$OUT/sphere5m.ply" >/dev/null
  for big in terrain2m sphere5m; do
    nv=$("$MF" op NumberOfVertices "$OUT/$big.ply"); inputs+=("$big:$((nv / 100))")
  done
fi

source "$(dirname "$0")/simplify_peers.sh"

echo "| input | target v | program | wall s | peak MB | vertices | mean error % |"
echo "|---|---:|---|---:|---:|---:|---:|"
for item in "${inputs[@]}"; do
  name=${item%%:*}; v=${item##*:}; IN=$OUT/$name.ply
  tris=$("$MF" op NumberOfTriangles "$IN")
  declare -A res=()
  res[meshflow]=$(run "$OUT/mf.ply" "$MF" op Simplify "$IN" -o "$OUT/mf.ply" --param targetVertices=$v)
  while read -r p r; do res[$p]=$r; done < <(peers "$v")
  res[meshoptimizer]=$(run "$OUT/mo.ply" "$BIN/meshopt_simplify" "$IN" "$OUT/mo.ply" $v)
  for p in meshflow meshlab openmesh cgal meshoptimizer; do
    read s mb nv err <<<"${res[$p]}"
    echo "| $name | $v | $p | $s | $mb | $nv | $err |"
  done
  python3 - "$tris" "${res[meshflow]}" "${res[meshlab]}" "${res[openmesh]}" "${res[cgal]}" "${res[meshoptimizer]}" <<'PY'
import sys
def parse(s):
    f = s.split()
    try: return float(f[0]), float(f[3])
    except Exception: return None
tris = int(sys.argv[1])
mf, ml, om, cg, mo = map(parse, sys.argv[2:])
mf_mb = float(sys.argv[2].split()[1]) if mf else None
best = [r[1] for r in (ml, om, cg) if r]
parts = []
if mf and best: parts.append(f"error vs best of MeshLab/OpenMesh/CGAL: {mf[1] / min(best):.3f}x (goal <= 1.05)")
if mf and mo: parts.append(f"time vs meshoptimizer: {mf[0] / max(mo[0], 0.01):.2f}x (goal <= 3)")
if mf_mb is not None: parts.append(f"meshflow peak: {mf_mb * 1048576 / tris:.0f} B per input triangle (goal < 150)")
print("|  |  | **ratios** | " + "; ".join(parts) + " | | | |")
PY
done
