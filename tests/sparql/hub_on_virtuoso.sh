#!/bin/bash
# hub_on_virtuoso.sh MESHFLOW: `meshflow hub --store virtuoso=...` against the Virtuoso that
# with_virtuoso.sh starts: search with reasoning, /sparql answering a property path (which
# rasqal cannot), a syntax error as 400, updates refused. Run through with_virtuoso.sh; the hub
# is stopped on every exit.
set -uo pipefail
mf=${1:?usage: hub_on_virtuoso.sh MESHFLOW}
: "${MESHFLOW_VIRTUOSO:?run me through tests/repository/with_virtuoso.sh}"
data=$(mktemp -d /tmp/mf-hub-virtuoso-XXXXXX)
hub=""
cleanup() {
  if [ -n "$hub" ]; then kill "$hub" 2>/dev/null; wait "$hub" 2>/dev/null; fi
  rm -rf "$data"
}
trap cleanup EXIT
fail() { echo "FAIL $*"; exit 1; }
"$mf" hub --port 0 --data "$data" --store "virtuoso=$MESHFLOW_VIRTUOSO" >"$data/out" 2>"$data/err" &
hub=$!
for _ in $(seq 1 600); do grep -q 'ready at' "$data/out" && break; kill -0 "$hub" 2>/dev/null || break; sleep 0.1; done
url=$(grep -o 'http://[^ ]*' "$data/out" | head -n1)
[ -n "$url" ] || fail "the hub did not start: $(tail -n3 "$data/err")"
names=$(curl -sf "$url/api/workflows?domain=Repair" | python3 -c 'import json,sys; print(sorted(w["name"] for w in json.load(sys.stdin)["workflows"]))')
[[ $names == *"Mesh Repairing"* && $names != *"simplification"* ]] || fail "domain=Repair: $names"
echo "ok   domain=Repair on Virtuoso: $names"
up=$(curl -sf --get -H 'Accept: text/csv' --data-urlencode \
  'query=SELECT ?p WHERE { <http://meshflow.org/ontology/wo#HoleFilling> <http://www.w3.org/2000/01/rdf-schema#subClassOf>+ ?p }' \
  "$url/sparql")
[[ $up == *"wo#Repair"* ]] || fail "property path on Virtuoso: $up"
echo "ok   a property path answers on Virtuoso"
code=$(curl -s -o /dev/null -w '%{http_code}' --get --data-urlencode 'query=SELEC ?x' "$url/sparql")
[ "$code" = 400 ] || fail "syntax error -> $code, want 400"
echo "ok   syntax error -> 400"
code=$(curl -s -o /dev/null -w '%{http_code}' -X POST -H 'Content-Type: application/sparql-update' \
  --data 'INSERT DATA { <urn:a> <urn:b> <urn:c> }' "$url/sparql")
[ "$code" = 403 ] || fail "update -> $code, want 403"
echo "ok   update refused"
