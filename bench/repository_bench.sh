#!/bin/bash
# Repository (issue 5): N workflows (default 10,000) in the Redland + sqlite store; semantic
# search p50/p95 over 100 mixed searches (text, purpose with reasoning, operation, creator,
# paging) and SPARQL queries/s with 8 client threads. In-process (bench/repository_load), no HTTP.
# The Virtuoso column is not measured yet (no Virtuoso backend in this branch).
set -euo pipefail
MF=$(realpath "${MESHFLOW:-build/meshflow}"); BIN=$(dirname "$MF")/bench
N=${REPOSITORY_BENCH_WORKFLOWS:-10000}
out=$("$BIN/repository_load" "$N")
get() { echo "$out" | awk -v k="$1" '$1==k {print $2}'; }
printf "| measure (%s workflows) | Redland+sqlite | Virtuoso |\n|---|---|---|\n" "$N"
printf "| load (s) | %s | not measured |\n" "$(get load_s)"
printf "| search p50 (ms) | %s | not measured |\n" "$(get search_p50_ms)"
printf "| search p95 (ms) | %s | not measured |\n" "$(get search_p95_ms)"
printf "| SPARQL queries/s, 8 clients | %s | not measured |\n" "$(get sparql_qps_8)"
