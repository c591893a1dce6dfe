#!/bin/bash
# What: `meshflow compare` (Metro-style: area-uniform samples, distance to the other surface by
# an AABB tree) cross-checked against MeshLab's "Hausdorff Distance" filter (meshlabserver) on
# the same pairs, with the same number of face samples, in both directions. Distances in % of
# A's bounding-box diagonal (MeshLab's "Values w.r.t. BBox Diag" of A). Also both wall times.
# Input: pairs made on the spot from the shared meshes (noise, simplification) and a generated
# terrain; written to $BENCH_OUT/compare.
set -euo pipefail
MF=${MESHFLOW:-build/meshflow}; OUT=${BENCH_OUT:-bench/out}/compare
SHARED=$(cd "$(dirname "$0")/../../shared/data/meshes" && pwd)
mkdir -p "$OUT"; rm -f "$OUT/agreement.txt"
if ! command -v meshlabserver >/dev/null; then echo "compare bench: meshlabserver not installed (make bench installs it)"; exit 0; fi

# name A B: B made from A by an operation of meshflow.
pairs=()
make_pair() {
  local name=$1 input=$2; shift 2
  "$MF" convert "$input" "$OUT/$name.a.ply"
  "$MF" op "$@" "$OUT/$name.a.ply" -o "$OUT/$name.b.ply" >/dev/null
  pairs+=("$name")
}
make_pair kitten-noise "$SHARED/real/kitten.off" AddNoise --param maxDistance=0.5 --param seed=3
make_pair bunny-5k "$SHARED/real/stanford-bunny.obj" Simplify --param targetVertices=5000
make_pair dragon-smooth "$SHARED/real/dragon_100k.ply" LaplacianSmoothing --param iterations=3
make_pair igea-1pct "$SHARED/real/igea_tristrips.ply" Simplify --param targetVertices=1343
[ -f "$OUT/terrain.ply" ] || "$MF" generate terrain --triangles 500000 -o "$OUT/terrain.ply" >/dev/null
make_pair terrain-2k "$OUT/terrain.ply" Simplify --param targetVertices=2500

hausdorff() {  # sampled target samples -> the filter's log
  cat >"$OUT/hd.mlx" <<MLX
<!DOCTYPE FilterScript>
<FilterScript>
 <filter name="Hausdorff Distance">
  <Param type="RichMesh" value="$1" name="SampledMesh"/>
  <Param type="RichMesh" value="$2" name="TargetMesh"/>
  <Param type="RichBool" value="false" name="SaveSample"/>
  <Param type="RichBool" value="false" name="SampleVert"/>
  <Param type="RichBool" value="false" name="SampleEdge"/>
  <Param type="RichBool" value="false" name="SampleFauxEdge"/>
  <Param type="RichBool" value="true" name="SampleFace"/>
  <Param type="RichInt" value="$3" name="SampleNum"/>
  <Param type="RichAbsPerc" value="1e9" min="0" max="1e9" name="MaxDist"/>
 </filter>
</FilterScript>
MLX
}

scale_pair() {  # A B A' B': canonical PLYs scaled by 100 / A's diagonal
  python3 - "$@" <<'PY'
import array, math, sys
def read(path):
    data = open(path, "rb").read()
    end = data.index(b"end_header\n") + len("end_header\n")
    n = int(data[:end].split(b"element vertex ")[1].split(b"\n")[0])
    xyz = array.array("f"); xyz.frombytes(data[end:end + 12 * n])
    return data[:end], xyz, data[end + 12 * n:]
def write(path, parts, factor):
    head, xyz, rest = parts
    open(path, "wb").write(head + array.array("f", (v * factor for v in xyz)).tobytes() + rest)
a, b = read(sys.argv[1]), read(sys.argv[2])
lo = [min(a[1][k::3]) for k in range(3)]; hi = [max(a[1][k::3]) for k in range(3)]
factor = 100 / math.dist(lo, hi)
write(sys.argv[3], a, factor); write(sys.argv[4], b, factor)
PY
}

echo "compare vs MeshLab Hausdorff Distance (face samples, same counts; % of A's diagonal)"
echo "| pair | samples A/B | mean A→B meshflow | MeshLab | mean B→A meshflow | MeshLab | max A→B meshflow | MeshLab | max B→A meshflow | MeshLab | meshflow s | MeshLab s |"
echo "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
for name in "${pairs[@]}"; do
  a=$OUT/$name.a.ply; b=$OUT/$name.b.ply
  /usr/bin/time -f "%e" -o "$OUT/mf.time" "$MF" compare "$a" "$b" --json >"$OUT/mf.json"
  read na nb < <(python3 -c "import json; d=json.load(open('$OUT/mf.json')); print(d['samples_a'], d['samples_b'])")
  # MeshLab prints distances with 6 decimals: give it both meshes scaled so that A's diagonal
  # is 100 (the percentages do not change; at 1000 its grid asserts on igea and aborts).
  scale_pair "$a" "$b" "$OUT/ml.a.ply" "$OUT/ml.b.ply"
  hausdorff 0 1 "$na"
  /usr/bin/time -f "%e" -o "$OUT/ml1.time" xvfb-run -a meshlabserver -i "$OUT/ml.a.ply" "$OUT/ml.b.ply" -s "$OUT/hd.mlx" >"$OUT/ml_ab.log" 2>&1
  hausdorff 1 0 "$nb"
  /usr/bin/time -f "%e" -o "$OUT/ml2.time" xvfb-run -a meshlabserver -i "$OUT/ml.a.ply" "$OUT/ml.b.ply" -s "$OUT/hd.mlx" >"$OUT/ml_ba.log" 2>&1
  python3 - "$name" "$OUT" "$na" "$nb" <<'PY'
import json, re, sys
name, out, na, nb = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4]
mf = json.load(open(f"{out}/mf.json"))
def parse(path):
    text = open(path).read()
    rows = re.findall(r"^\s*min : (\S+)\s+max (\S+)\s+mean : (\S+)", text, re.M)
    diag = re.findall(r"Values w.r.t. BBox Diag \((\S+)\)", text)
    if len(rows) < 2 or not diag: sys.exit(f"{name}: no Hausdorff result in {path}")
    return float(rows[0][1]), float(rows[0][2]), float(diag[0])  # absolute max, mean; sampled diag
max_ab, mean_ab, diag_a = parse(f"{out}/ml_ab.log")
max_ba, mean_ba, _ = parse(f"{out}/ml_ba.log")
pct = lambda v: 100 * v / diag_a
t_mf = float(open(f"{out}/mf.time").read().split()[-1])
t_ml = sum(float(open(f"{out}/ml{i}.time").read().split()[-1]) for i in (1, 2))
print(f"| {name} | {na}/{nb} | {mf['mean_ab']:.5f} | {pct(mean_ab):.5f} | {mf['mean_ba']:.5f} | {pct(mean_ba):.5f} "
      f"| {mf['max_ab']:.4f} | {pct(max_ab):.4f} | {mf['max_ba']:.4f} | {pct(max_ba):.4f} | {t_mf:.2f} | {t_ml:.2f} |")
with open(f"{out}/agreement.txt", "a") as f:
    f.write(f"{name} {mf['mean_ab'] / pct(mean_ab):.4f} {mf['mean_ba'] / pct(mean_ba):.4f}\n")
PY
done
python3 - "$OUT" <<'PY'
import sys
rows = [l.split() for l in open(f"{sys.argv[1]}/agreement.txt")]
ratios = [float(r) for row in rows for r in row[1:]]
print(f"mean distances, meshflow / MeshLab: {min(ratios):.3f} .. {max(ratios):.3f} over {len(ratios)} one-way means")
PY
rm -f "$OUT/agreement.txt"
