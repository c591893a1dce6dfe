#!/bin/bash
# What: `meshflow simplify` (BSP parts, worker pool, merge, seam pass) on generated terrains and
# closed surfaces at --max-error 0.1 (% of the diagonal), with 1, 2 and 4 workers; the physical
# floor `cat IN > /dev/null` and `cp IN` on the same file in the same run.
# Figures: wall time per step (from --report) and in total, peak RSS of the process, the output's
# size. SIZES (triangles, default "10000000 100000000"); BIG=1 adds a 500M-triangle terrain when
# the disk has room (checked first, and said when it has not).
# Note: the input is read into memory (DESIGN §9's out-of-core path is not done yet), so peak RSS
# grows with the input.
set -uo pipefail
MF=$(realpath "${MESHFLOW:-build/meshflow}"); OUT=${BENCH_OUT:-bench/out}/parallel
mkdir -p "$OUT"
SIZES=${SIZES:-"10000000 100000000"}
WORKERS=${WORKERS:-"1 2 4"}
TIMEOUT=${TIMEOUT:-3600}
PY=python3

runs=()
for n in $SIZES; do runs+=("terrain:$n" "sphere:$n"); done
if [ -n "${BIG:-}" ]; then
  need_kb=$((500000000 / 1000 * 13 * 3))  # input (~13 B/triangle) + output + copy for cp
  free_kb=$(df -Pk "$OUT" | awk 'NR==2 {print $4}')
  if [ "$free_kb" -lt "$need_kb" ]; then
    echo "500M run skipped: $((free_kb / 1048576)) GB free in $OUT, about $((need_kb / 1048576)) GB needed"
  else runs+=("terrain:500000000"); fi
fi

printf "%-20s %7s %10s %8s %8s %8s %8s %8s %8s %9s %9s %8s\n" input workers nparts partit_s parts_s merge_s seams_s total_s wall_s peakMB cat_s cp_s
for run in "${runs[@]}"; do
  kind=${run%%:*}; n=${run##*:}; in="$OUT/$kind$n.ply"
  [ -f "$in" ] || "$MF" generate "$kind" --triangles "$n" -o "$in" >/dev/null || { echo "generate $kind $n failed"; continue; }
  cat_s=$( { /usr/bin/time -f "%e" cat "$in" >/dev/null; } 2>&1 )
  cp_s=$( { /usr/bin/time -f "%e" cp "$in" "$OUT/copy.ply"; } 2>&1 ); rm -f "$OUT/copy.ply"
  for w in $WORKERS; do
    rm -f "$OUT/out.ply" "$OUT/report.json"
    if ! /usr/bin/time -f "%e %M" -o "$OUT/time" timeout "$TIMEOUT" "$MF" simplify "$in" -o "$OUT/out.ply" \
        --max-error 0.1 --workers "$w" --report "$OUT/report.json" >/dev/null 2>"$OUT/err"; then
      echo "$kind$n workers $w failed: $(tail -c 200 "$OUT/err")"; continue
    fi
    read wall rss <"$OUT/time"
    $PY - "$OUT/report.json" "$kind$n" "$w" "$wall" "$rss" "$cat_s" "$cp_s" <<'PYEOF'
import json, sys
r = json.load(open(sys.argv[1])); s = r["seconds"]
name, w, wall, rss, cat_s, cp_s = sys.argv[2:]
print("%-20s %7s %10d %8.1f %8.1f %8.1f %8.1f %8.1f %8.1f %9.0f %9s %8s" % (name, w, r["parts"], s["partition"], s["parts"],
      s["merge"], s["seams"], s["total"], float(wall), int(rss) / 1024, cat_s, cp_s))
PYEOF
  done
done
rm -f "$OUT/out.ply"
