#!/bin/bash
# What: `meshflow simplify --nodes` (out-of-core partition, parts on 1, 2 and 4 local
# `meshflow node` processes, seam pass, out-of-core merge) on generated terrains and closed
# surfaces at --max-error 0.1 (% of the diagonal); the physical floor `cat IN > /dev/null` and
# `cp IN` on the same file in the same run.
# Figures: wall time per step (from --report) and in total; peak RSS of the coordinator (GNU
# time) and of the busiest node (VmHWM from /proc before it stops); peak disk use of the parts
# folder and the nodes' data (sampled every second) over the input's size; output vertices; the
# one-way error (`compare --one-way`: the input streamed, about 2M of its vertices measured to the
# result, % of the diagonal; not timed); the output's SHA-256 (equal for 1, 2 and 4 nodes: the
# result does not depend on them).
# SIZES (triangles, default "10000000 100000000"), NODES (default "1 2 4"), KINDS (default
# "terrain sphere"); BIG=1 adds a 500M-triangle terrain when the disk has room (checked first).
set -uo pipefail
MF=$(realpath "${MESHFLOW:-build/meshflow}"); OUT=$(realpath -m "${BENCH_OUT:-bench/out}/parallel")
mkdir -p "$OUT"
SIZES=${SIZES-"10000000 100000000"}  # SIZES="" BIG=1: the 500M run alone
NODES=${NODES:-"1 2 4"}
KINDS=${KINDS:-"terrain sphere"}
TIMEOUT=${TIMEOUT:-7200}
PY=python3
PIDS=()
stop_nodes() { for p in "${PIDS[@]}"; do kill "$p" 2>/dev/null; done; for p in "${PIDS[@]}"; do wait "$p" 2>/dev/null; done; PIDS=(); }
trap stop_nodes EXIT

runs=()
for n in $SIZES; do for k in $KINDS; do runs+=("$k:$n"); done; done
if [ -n "${BIG:-}" ]; then
  need_kb=$((500000000 / 1000 * 19 * 4))  # input (~19 B/triangle), parts (~2.3x) and the copy for cp
  free_kb=$(df -Pk "$OUT" | awk 'NR==2 {print $4}')
  if [ "$free_kb" -lt "$need_kb" ]; then
    echo "500M run skipped: $((free_kb / 1048576)) GB free in $OUT, about $((need_kb / 1048576)) GB needed"
  else runs+=("terrain:500000000"); fi
fi

printf "%-18s %5s %6s %9s %8s %8s %8s %8s %8s %8s %8s %7s %7s %7s %9s %9s %12s\n" input nodes parts partit_s parts_s seams_s merge_s total_s wall_s coordMB nodeMB disk_x cat_s cp_s vertices one_way% sha256
for run in "${runs[@]}"; do
  kind=${run%%:*}; n=${run##*:}; in="$OUT/$kind$n.ply"
  [ -f "$in" ] || "$MF" generate "$kind" --triangles "$n" -o "$in" >/dev/null || { echo "generate $kind $n failed"; continue; }
  sync; cat_s=$( { /usr/bin/time -f "%e" cat "$in" >/dev/null; } 2>&1 )
  cp_s=$( { /usr/bin/time -f "%e" cp "$in" "$OUT/copy.ply"; } 2>&1 ); rm -f "$OUT/copy.ply"
  in_bytes=$(stat -c %s "$in")
  for k in $NODES; do
    rm -rf "$OUT/out.ply" "$OUT/report.json" "$OUT/parts" "$OUT"/node*
    echo 0 >"$OUT/disk"
    urls=()
    for i in $(seq 1 "$k"); do
      "$MF" node --listen 127.0.0.1:0 --data "$OUT/node$i" --capacity 100000000 >"$OUT/node$i.out" 2>&1 & PIDS+=("$!")
    done
    for i in $(seq 1 "$k"); do
      for t in $(seq 1 100); do u=$(grep -oE 'http://[0-9.:]+' "$OUT/node$i.out" | head -n1); [ -n "$u" ] && break; sleep 0.1; done
      urls+=("$u")
    done
    ( peak=0; while true; do d=$(du -sb "$OUT/parts" "$OUT"/node? 2>/dev/null | awk '{s+=$1} END {printf "%.0f", s}');
        [ "$d" -gt "$peak" ] && peak=$d && echo "$peak" >"$OUT/disk"; sleep 1; done ) & sampler=$!
    ok=1
    /usr/bin/time -f "%e %M" -o "$OUT/time" timeout "$TIMEOUT" "$MF" simplify "$in" -o "$OUT/out.ply" --max-error 0.1 \
        --nodes "$(IFS=,; echo "${urls[*]}")" --parts-dir "$OUT/parts" --report "$OUT/report.json" >/dev/null 2>"$OUT/err" || ok=0
    kill $sampler 2>/dev/null; wait $sampler 2>/dev/null
    node_kb=0
    for p in "${PIDS[@]}"; do
      h=$(awk '/VmHWM/ {print $2}' /proc/$p/status 2>/dev/null); [ "${h:-0}" -gt "$node_kb" ] && node_kb=$h
    done
    stop_nodes
    if [ $ok = 0 ]; then echo "$kind$n nodes $k failed: $(tail -c 200 "$OUT/err")"; continue; fi
    read wall rss <"$OUT/time"
    one_way=$("$MF" compare "$in" "$OUT/out.ply" --one-way --json | $PY -c 'import json,sys; print("%.5f" % json.load(sys.stdin)["mean_ab"])')
    sha=$(sha256sum "$OUT/out.ply" | cut -c1-12)
    $PY - "$OUT/report.json" "$kind$n" "$k" "$wall" "$rss" "$node_kb" "$(cat "$OUT/disk")" "$in_bytes" "$cat_s" "$cp_s" "$one_way" "$sha" <<'PYEOF'
import json, sys
r = json.load(open(sys.argv[1])); s = r["seconds"]
name, k, wall, rss, node_kb, disk, in_bytes, cat_s, cp_s, one_way, sha = sys.argv[2:]
print("%-18s %5s %6d %9.1f %8.1f %8.1f %8.1f %8.1f %8.1f %8.0f %8.0f %7.2f %7s %7s %9d %9s %12s" % (name, k, r["parts"], s["partition"],
      s["parts"], s["seams"], s["merge"], s["total"], float(wall), int(rss) / 1024, int(node_kb) / 1024,
      int(disk) / int(in_bytes), cat_s, cp_s, r["output_vertices"], one_way, sha))
PYEOF
  done
  rm -rf "$OUT/parts" "$OUT"/node*
done
rm -f "$OUT/out.ply"
