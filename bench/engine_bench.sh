#!/bin/bash
# What: the engine's own cost. A 10-step workflow of cheap analysis operations (each one an
# `if` whose condition calls a node) on a small mesh (kitten, 5000 triangles), run as a job on
# `meshflow up` (hub + 2 nodes over loopback). Engine time = the job's elapsed time on the hub
# (placing operations, broadcasting the input, one HTTP call per step, the journal, fetching
# the result) minus the time the nodes spent in the operations themselves (sum of run_ms).
# Goal: under 100 ms. Runs 1 warm-up job and RUNS measured jobs (default 15); prints each
# figure's median, p25 and max, and the in-process `meshflow run` of the same workflow for scale.
set -euo pipefail
MF=$(realpath "${MESHFLOW:-build/meshflow}"); OUT=${BENCH_OUT:-bench/out}/engine; RUNS=${RUNS:-15}
HERE=$(cd "$(dirname "$0")" && pwd)
SHARED=$(cd "$HERE/../../shared/data/meshes" && pwd)
IN=$SHARED/real/kitten.off
rm -rf "$OUT"; mkdir -p "$OUT"
{
  echo '<workflow><body>'
  for op in NumberOfVertices NumberOfTriangles NumberOfEdges NumberOfBoundaryLoops NumberOfComponents \
            MinimumAngle MaximumAngle SurfaceArea AverageNormalInstability IsManifold; do
    echo "  <if><condition><analysis><name>$op</name><operator>NEQ</operator><value>$([ $op = IsManifold ] && echo false || echo 0)</value></analysis></condition><body/></if>"
  done
  echo '</body></workflow>'
} >"$OUT/ten.xml"

"$MF" up --port 0 --nodes 2 --data "$OUT/data" >"$OUT/up.out" 2>"$OUT/up.err" &
UP=$!
trap 'kill $UP 2>/dev/null; wait $UP 2>/dev/null || true' EXIT
for _ in $(seq 1 300); do grep -q "ready at" "$OUT/up.out" 2>/dev/null && break; sleep 0.1; done
HUB=$(grep -o 'http://[0-9.:]*' "$OUT/up.out" | head -1)
[ -n "$HUB" ] || { echo "meshflow up did not start:"; cat "$OUT/up.err"; exit 1; }

python3 - "$HUB" "$OUT/ten.xml" "$IN" "$RUNS" "$HERE" <<'PY' | tee "$OUT/jobs.txt"
import statistics, sys
hub, workflow, mesh, runs, here = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4]), sys.argv[5]
sys.path.insert(0, here)
import hub_jobs
hub_jobs.run(hub, workflow, mesh)  # warm-up
rows = []
for _ in range(runs):
    job = hub_jobs.run(hub, workflow, mesh)
    steps = job["steps"]
    assert len(steps) == 10, job
    ops = sum(s["run_ms"] for s in steps)
    wait = sum(s["wait_ms"] for s in steps)
    rows.append((job["elapsed_ms"], ops, job["elapsed_ms"] - ops, wait))
def stat(i):
    values = sorted(r[i] for r in rows)
    p25 = values[max(0, (len(values) + 3) // 4 - 1)]
    return f"{statistics.median(values):.0f} | {p25} | {values[-1]}"
print(f"{len(rows)} jobs of 10 analysis steps on {mesh.rsplit('/', 1)[-1]}, hub + 2 nodes on loopback")
print()
print("| ms per job | median | p25 | max |")
print("|---|---:|---:|---:|")
print(f"| elapsed on the hub | {stat(0)} |")
print(f"| operations (sum of run_ms) | {stat(1)} |")
print(f"| **engine time** (elapsed - operations) | {stat(2)} |")
print(f"| of which nodes waiting for the input (sum of wait_ms) | {stat(3)} |")
median = statistics.median(r[2] for r in rows)
print()
print(f"engine time median {median:.0f} ms: {'under' if median < 100 else 'NOT under'} the 100 ms goal")
PY
start=$(date +%s%N)
"$MF" run "$OUT/ten.xml" "$IN" -o "$OUT/local.ply" 2>"$OUT/local.err"
end=$(date +%s%N)
echo "in-process \`meshflow run\` of the same workflow (whole process, reading and writing the mesh): $(( (end - start) / 1000000 )) ms"
