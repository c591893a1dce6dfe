#!/bin/bash
# Repository (issue 5): N workflows (default 10,000) in each backend — Redland + sqlite (the
# default) and OpenLink Virtuoso (started on loopback by tests/repository/with_virtuoso.sh) —
# the same workflows, the same 100 mixed searches (text, purpose with reasoning, operation,
# creator, paging: p50/p95) and the same SPARQL queries (queries/s with 8 client threads).
# In-process (bench/repository_load), no HTTP between the hub and its callers.
set -euo pipefail
MF=$(realpath "${MESHFLOW:-build/meshflow}"); BIN=$(dirname "$MF")/bench
HERE=$(cd "$(dirname "$0")" && pwd)
N=${REPOSITORY_BENCH_WORKFLOWS:-10000}
redland=$("$BIN/repository_load" "$N")
virtuoso=$("$HERE/../tests/repository/with_virtuoso.sh" bash -c \
  '"$0" "$1" "$MESHFLOW_VIRTUOSO"' "$BIN/repository_load" "$N" | grep -v '^with_virtuoso:' || true)
get() { echo "$1" | awk -v k="$2" '$1==k {print $2}'; }
cell() { local v; v=$(get "$1" "$2"); echo "${v:-not measured}"; }
# ratio A B: A/B with one decimal, or "-" when either is missing.
ratio() { awk -v a="$1" -v b="$2" 'BEGIN { if (a+0 > 0 && b+0 > 0) printf "%.2f", a/b; else print "-" }'; }
printf "| measure (%s workflows) | Redland+sqlite | Virtuoso | Redland / Virtuoso |\n|---|---|---|---|\n" "$N"
for key in load_s search_p50_ms search_p95_ms sparql_qps_8; do
  case $key in
    load_s) label="load (s)";;
    search_p50_ms) label="search p50 (ms)";;
    search_p95_ms) label="search p95 (ms)";;
    sparql_qps_8) label="SPARQL queries/s, 8 clients";;
  esac
  r=$(cell "$redland" $key); v=$(cell "$virtuoso" $key)
  printf "| %s | %s | %s | %s |\n" "$label" "$r" "$v" "$(ratio "$r" "$v")"
done
for kind in text purpose operation_text creator type_paged; do
  key=search_max_ms_$kind
  r=$(cell "$redland" $key); v=$(cell "$virtuoso" $key)
  printf "| slowest %s search (ms) | %s | %s | %s |\n" "${kind//_/ + }" "$r" "$v" "$(ratio "$r" "$v")"
done
for out in "$redland" "$virtuoso"; do
  failed=$(get "$out" sparql_failed)
  [ -z "$failed" ] || echo "note: $failed SPARQL queries failed in one column" >&2
done
