#!/bin/bash
# What: the thesis's experiment of its Tables 4.3-4.5 (mesh transfer protocol, ch. 4.4) on this
# machine. A hub and 3 nodes, each in its own network namespace (ip netns + veth + a bridge in
# a namespace of its own), every link limited to 5 Mbit/s in both directions with tc tbf
# (GROUND §5, §11). Like the thesis's servers, each node offers some of the operations:
#   n1: the checks (NumberOfComponents, NumberOfBoundaryLoops, AverageNormalInstability),
#       RemoveSmallestComponents, RemoveDegenerateTriangles
#   n2: LaplacianSmoothing            n3: FillHoles, FillHolesHeightField
# Each workflow runs on each scan twice, as two jobs: with the protocol (after each step later
# nodes get the correction or the output, whichever is smaller) and with whole meshes
# (the job's `transfer=output`), every job on freshly started nodes with empty caches.
# Input: the shared scans (../shared/data/meshes/real; SCANS to choose) and the shared terrain
# (*, large/), with the thesis's height-field hole filling.
#   Table 4.3: RSC -> LS -> HF -> RDT.
#   Table 4.4: if |C| > 1 then RSC; if |B| > 0 (terrain: > 1) then HF.
#   Table 4.5: the scan with AddNoise (0.2 % of the diagonal, seed 1), then LS while AVG_NI is
#              above the noise-free scan's AVG_NI.
# Per step: the operation's run time on its node, T (later nodes fetching what was sent, the
# slowest of them) and U (applying a correction, or loading a whole mesh), in seconds; IB = the
# input broadcast until every node has it; "-": the step did not run, or sent nothing (its
# output is its input). "sum" adds the columns as the thesis does; "wall" is the job's elapsed
# time on the hub (also the nodes writing their outputs, HTTP calls, and the result's one trip
# to the hub, the same both ways). Benefit = whole / protocol - 1, on the sums (the thesis's
# 50-100 % on 4.3) and on the wall times.
# Both runs must give the same output (SHA-256 of the canonical PLY).
# Needs root (namespaces, tc). Cleans up after itself, also when interrupted.
set -euo pipefail
MF=$(realpath "${MESHFLOW:-build/meshflow}"); OUT=$(realpath -m "${BENCH_OUT:-bench/out}/transfer")
HERE=$(cd "$(dirname "$0")" && pwd)
SHARED=$(cd "$HERE/../../shared/data/meshes" && pwd)
RATE=${RATE:-5mbit}
SCANS=${SCANS:-"real/kitten.off real/spot_vt_vn.obj real/stanford-bunny.obj real/ogre.obj real/beast_quads.obj real/dragon_100k.ply real/igea_tristrips.ply large/terrain_fuji_512.ply"}
TABLES=${TABLES:-"4.3 4.4 4.5"}
if [ "$(id -u)" != 0 ]; then echo "transfer bench: needs root (ip netns, tc); skipped"; exit 0; fi
command -v ip >/dev/null && command -v tc >/dev/null || { echo "transfer bench: needs iproute2"; exit 1; }

P=mfb   # namespace prefix
HUB_IP=10.77.0.1
declare -A NODE_IP=([n1]=10.77.0.11 [n2]=10.77.0.12 [n3]=10.77.0.13)
declare -A OFFER=(
  [n1]=NumberOfComponents,NumberOfBoundaryLoops,AverageNormalInstability,RemoveSmallestComponents,RemoveDegenerateTriangles
  [n2]=LaplacianSmoothing
  [n3]=FillHoles,FillHolesHeightField)
HUB_URL=http://$HUB_IP:8080
PIDS=()

teardown() {
  for pid in "${PIDS[@]}"; do kill "$pid" 2>/dev/null || true; done
  for pid in "${PIDS[@]}"; do wait "$pid" 2>/dev/null || true; done
  PIDS=()
  for ns in hub n1 n2 n3 br; do ip netns del $P-$ns 2>/dev/null || true; done
}
trap teardown EXIT
trap 'exit 130' INT TERM

network() {
  teardown
  ip netns add $P-br
  ip -n $P-br link add br0 type bridge
  ip -n $P-br link set lo up
  ip -n $P-br link set br0 up
  local ns ip
  for ns in hub n1 n2 n3; do
    ip=$([ $ns = hub ] && echo $HUB_IP || echo "${NODE_IP[$ns]}")
    ip netns add $P-$ns
    ip link add v0 netns $P-$ns type veth peer name p-$ns netns $P-br
    ip -n $P-br link set p-$ns master br0
    ip -n $P-br link set p-$ns up
    ip -n $P-$ns addr add $ip/24 dev v0
    ip -n $P-$ns link set lo up
    ip -n $P-$ns link set v0 up
    # Both directions: the namespace's egress, and the bridge port's egress towards it.
    ip netns exec $P-$ns tc qdisc add dev v0 root handle 1: tbf rate $RATE burst 32kbit latency 400ms
    ip netns exec $P-br tc qdisc add dev p-$ns root handle 1: tbf rate $RATE burst 32kbit latency 400ms
  done
}

wait_line() {  # FILE PATTERN: wait up to 30 s for a line
  for _ in $(seq 1 300); do grep -q "$2" "$1" 2>/dev/null && return 0; sleep 0.1; done
  echo "transfer bench: no '$2' in $1:"; cat "$1" "${1%.out}.err" 2>/dev/null | tail -5; return 1
}

NODE_PIDS=()
start_nodes() {  # fresh data directories: no node has anything cached
  local ns
  NODE_PIDS=()
  for ns in n1 n2 n3; do
    rm -rf "$OUT/nodes/$ns"; mkdir -p "$OUT/nodes"
    ip netns exec $P-$ns "$MF" node --hub $HUB_URL --token-file "$OUT/hub/node.token" \
      --listen "${NODE_IP[$ns]}:8081" --data "$OUT/nodes/$ns" --offer "${OFFER[$ns]}" \
      >"$OUT/nodes/$ns.out" 2>"$OUT/nodes/$ns.err" &
    NODE_PIDS+=($!); PIDS+=($!)
  done
  for ns in n1 n2 n3; do wait_line "$OUT/nodes/$ns.out" "ready at"; done
}
stop_nodes() {
  local pid
  for pid in "${NODE_PIDS[@]}"; do kill "$pid" 2>/dev/null || true; wait "$pid" 2>/dev/null || true; done
  NODE_PIDS=()
}

rm -rf "$OUT"; mkdir -p "$OUT/in" "$OUT/jobs" "$OUT/hub"
network
# The links really are limited: 1 MB from a node to the hub.
ip netns exec $P-hub python3 -m http.server --bind $HUB_IP 8099 --directory "$OUT/in" >/dev/null 2>&1 &
PIDS+=($!)
head -c 1000000 /dev/urandom >"$OUT/in/probe.bin"
probe=
for _ in $(seq 1 100); do
  probe=$(ip netns exec $P-n1 curl -sf -o /dev/null -w '%{time_total}' http://$HUB_IP:8099/probe.bin) && break
  sleep 0.2
done
[ -n "$probe" ] || { echo "transfer bench: the namespaces cannot reach each other"; exit 1; }
kill "${PIDS[-1]}"; wait "${PIDS[-1]}" 2>/dev/null || true; unset 'PIDS[-1]'
echo "links: tbf $RATE; 1 MB hub -> n1 took ${probe} s ($(python3 -c "print(f'{8/$probe:.2f}')") Mbit/s)"

ip netns exec $P-hub "$MF" hub --host $HUB_IP --port 8080 --data "$OUT/hub" >"$OUT/hub.out" 2>"$OUT/hub.err" &
PIDS+=($!)
wait_line "$OUT/hub.out" "ready at"

run_job() {  # NAME WORKFLOW MESH MODE -> jobs/NAME.MODE.json
  local name=$1 workflow=$2 mesh=$3 mode=$4
  start_nodes
  ip netns exec $P-hub python3 "$HERE/hub_jobs.py" run $HUB_URL "$workflow" "$mesh" --transfer "$mode" \
    >"$OUT/jobs/$name.$mode.json" 2>"$OUT/jobs/$name.$mode.err" ||
    { echo "job $name ($mode) failed: $(tail -c 300 "$OUT/jobs/$name.$mode.err")"; stop_nodes; return 1; }
  stop_nodes
}

value() { "$MF" op "$1" "$2" 2>/dev/null; }

for table in $TABLES; do
  for scan in $SCANS; do
    name=$(basename "${scan%.*}")
    mesh=$SHARED/$scan
    terrain=$([[ $scan == large/terrain* ]] && echo 1 || echo 0)
    fill=$([ $terrain = 1 ] && echo FillHolesHeightField || echo FillHoles)
    wf=$OUT/$table-$name.xml
    case $table in
      4.3) cat >"$wf" <<EOF
<workflow><body>
  <atomic><name>RemoveSmallestComponents</name></atomic>
  <atomic><name>LaplacianSmoothing</name><parameters><parameter>1</parameter></parameters></atomic>
  <atomic><name>$fill</name></atomic>
  <atomic><name>RemoveDegenerateTriangles</name></atomic>
</body></workflow>
EOF
      ;;
      4.4) cat >"$wf" <<EOF
<workflow><body>
  <if><condition><analysis><name>NumberOfComponents</name><operator>GT</operator><value>1</value></analysis></condition>
    <body><atomic><name>RemoveSmallestComponents</name></atomic></body></if>
  <if><condition><analysis><name>NumberOfBoundaryLoops</name><operator>GT</operator><value>$terrain</value></analysis></condition>
    <body><atomic><name>$fill</name></atomic></body></if>
</body></workflow>
EOF
      ;;
      4.5)
        noisy=$OUT/in/$name.noisy.ply
        [ -f "$noisy" ] || "$MF" op AddNoise "$mesh" -o "$noisy" --param maxDistance=0.2 --param seed=1 >/dev/null
        threshold=$(value AverageNormalInstability "$mesh")
        cat >"$wf" <<EOF
<workflow><body>
  <while><condition><analysis><name>AverageNormalInstability</name><operator>GT</operator><value>$threshold</value></analysis></condition>
    <body><atomic><name>LaplacianSmoothing</name></atomic></body></while>
</body></workflow>
EOF
        mesh=$noisy
      ;;
    esac
    for mode in smaller output; do run_job "$table-$name" "$wf" "$mesh" $mode || true; done
  done
done

python3 - "$OUT" "$TABLES" "$SCANS" <<'PY'
import json, os, sys
out, tables, scans = sys.argv[1], sys.argv[2].split(), sys.argv[3].split()
ABBREV = {"RemoveSmallestComponents": "RSC", "LaplacianSmoothing": "LS", "FillHoles": "HF",
          "FillHolesHeightField": "HF", "RemoveDegenerateTriangles": "RDT", "NumberOfComponents": "|C|",
          "NumberOfBoundaryLoops": "|B|", "AverageNormalInstability": "AVG_NI"}
# The thesis's columns: an operation's run time, then T and U of what its step sent on.
SCHEMA = {"4.3": ["RSC", "T:RSC", "U:RSC", "LS", "T:LS", "U:LS", "HF", "T:HF", "U:HF", "RDT"],
          "4.4": ["|C|", "RSC", "T:RSC", "U:RSC", "|B|", "HF"],
          "4.5": ["AVG_NI", "LS", "T:LS", "U:LS"]}
def sec(ms): return f"{ms / 1000:.2f}"
def load(name, mode):
    path = f"{out}/jobs/{name}.{mode}.json"
    return json.load(open(path)) if os.path.exists(path) and os.path.getsize(path) else None
def cells(table, job):
    by_op = {}
    for st in job["steps"]:
        by_op.setdefault(ABBREV.get(st["operation"], st["operation"]), []).append(st)
    row = [sec(job["broadcast_ms"])]
    for column in SCHEMA[table]:
        kind, op = column.split(":") if ":" in column else ("run", column)
        steps = by_op.get(op, [])
        key = {"run": "run_ms", "T": "transfer_ms", "U": "update_ms"}[kind]
        if kind != "run": steps = [st for st in steps if st.get("sent")]
        if not steps: row.append("-"); continue
        mean = sum(st[key] for st in steps) / len(steps)
        row.append(sec(mean) + (f" ({len(steps)})" if table == "4.5" else ""))
    total = job["broadcast_ms"] + sum(st["run_ms"] + st["transfer_ms"] + st["update_ms"] for st in job["steps"])
    return row, total
benefits, all_same = {}, {}
for table in tables:
    columns = ["IB"] + [c.replace("T:", "T ").replace("U:", "U ") for c in SCHEMA[table]]
    print(f"\n### Table {table} (seconds; first row with the protocol, second with whole meshes)\n")
    print("| scan | " + " | ".join(columns) + " | sum | wall | benefit (sum) | benefit (wall) | output SHA-256 |")
    print("|---|" + "---:|" * (len(columns) + 4) + "---|")
    sizes = []
    for scan in scans:
        name = os.path.basename(scan).rsplit(".", 1)[0]
        star = "*" if scan.startswith("large/terrain") else ""
        smaller, whole = load(f"{table}-{name}", "smaller"), load(f"{table}-{name}", "output")
        if not smaller or not whole:
            print(f"| {name}{star} | failed: see {out}/jobs/{table}-{name}.*.err |")
            continue
        same = smaller["output_sha256"] == whole["output_sha256"]
        all_same[table] = all_same.get(table, True) and same
        row, total = cells(table, smaller)
        whole_row, whole_total = cells(table, whole)
        benefit_sum = whole_total / total - 1
        benefit_wall = whole["elapsed_ms"] / smaller["elapsed_ms"] - 1
        benefits.setdefault(table, []).append((benefit_sum, benefit_wall))
        print(f"| {name}{star} | " + " | ".join(row) + f" | {sec(total)} | {sec(smaller['elapsed_ms'])} | "
              f"{100 * benefit_sum:.0f}% | {100 * benefit_wall:.0f}% | {smaller['output_sha256'][:12]} "
              f"{'same' if same else 'DIFFERENT'} |")
        print(f"| | " + " | ".join(whole_row) + f" | {sec(whole_total)} | {sec(whole['elapsed_ms'])} | | | "
              f"{whole['output_sha256'][:12]} |")
        for st in smaller["steps"]:
            if st["kind"] == "atomic":
                sizes.append(f"| {name}{star} | {ABBREV.get(st['operation'], st['operation'])} | "
                             f"{st['output_bytes'] / 1024:.1f} | {st['correction_bytes'] / 1024:.1f} | {st['sent'] or '-'} |")
    if table == "4.3" and sizes:
        print("\nSizes (KB; canonical PLY + zstd, and the .mfc correction) of each step's result (Table 4.2):\n")
        print("| scan | step | output | correction | sent |\n|---|---|---:|---:|---|")
        for r in sizes: print(r)
print()
for table, values in benefits.items():
    sums, walls = [v[0] for v in values], [v[1] for v in values]
    print(f"Table {table}: benefit {100 * min(sums):.0f}% to {100 * max(sums):.0f}% on the sums, "
          f"{100 * min(walls):.0f}% to {100 * max(walls):.0f}% on the wall times ({len(values)} scans; all outputs "
          f"{'identical' if all_same.get(table, True) else 'NOT identical'} both ways)")
PY
echo
echo "measured node bandwidth (hub's estimate from the jobs' transfers, Mbit/s):"
ip netns exec $P-hub curl -s $HUB_URL/api/services | python3 -c '
import json, sys
for s in json.load(sys.stdin)["services"]: print("  %s: %.2f" % (s["url"], s["bandwidth_mbps"]))'
