#!/bin/bash
# with_virtuoso.sh CMD [ARG...]: starts OpenLink Virtuoso (Debian's virtuoso-opensource) on
# loopback, on free ports, in a temporary folder; runs CMD with MESHFLOW_VIRTUOSO set to its
# SPARQL endpoint; stops the server (isql-vt shutdown, then kill) and removes the folder, even
# when CMD fails. Exits 77 when virtuoso-opensource is not installed (ctest SKIP_RETURN_CODE).
set -uo pipefail
if ! command -v virtuoso-t >/dev/null || ! command -v isql-vt >/dev/null; then
  echo "skipped: virtuoso-opensource not installed"
  exit 77
fi
ini_template=/etc/virtuoso-opensource-7/virtuoso.ini
[ -r "$ini_template" ] || { echo "with_virtuoso: cannot read $ini_template" >&2; exit 1; }

dir=$(mktemp -d /tmp/mf-virtuoso-XXXXXX)
free_port() { python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])'; }
sql_port=$(free_port)
http_port=$(free_port)
while [ "$http_port" = "$sql_port" ]; do http_port=$(free_port); done
pid=""

stop() {
  if [ -n "$pid" ] && kill -0 "$pid" 2>/dev/null; then
    timeout 20 isql-vt "127.0.0.1:$sql_port" dba dba exec="shutdown;" >/dev/null 2>&1
    for _ in $(seq 1 100); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill "$pid" 2>/dev/null
    for _ in $(seq 1 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -9 "$pid" 2>/dev/null
    wait "$pid" 2>/dev/null
  fi
  rm -rf "$dir"
}
trap stop EXIT
trap 'exit 130' INT TERM

# GROUND.md §2: our own database folder, loopback ports, our folder allowed; no row cap that
# would cut results silently (the store bounds rows itself and says so).
sed -e "s|/var/lib/virtuoso-opensource-7/db/|$dir/|g" \
    -e "s|^ServerPort *= *1111|ServerPort = 127.0.0.1:$sql_port|" \
    -e "s|^ServerPort *= *8890|ServerPort = 127.0.0.1:$http_port|" \
    -e "s|^DirsAllowed *=.*|DirsAllowed = ., $dir, /usr/share/virtuoso-opensource-7/vad|" \
    -e "s|^ResultSetMaxRows *=.*|ResultSetMaxRows = 10000000|" \
    -e "s|^MaxQueryCostEstimationTime *=.*|MaxQueryCostEstimationTime = 0|" \
    -e "s|^NumberOfBuffers *=.*|NumberOfBuffers = 170000|" \
    -e "s|^MaxDirtyBuffers *=.*|MaxDirtyBuffers = 130000|" \
    -e "s|^ServerRoot *=.*|ServerRoot = $dir|" \
    -e "s|^\(Load[0-9]\+ *=\)|;\1|" \
    "$ini_template" > "$dir/virtuoso.ini"

(cd "$dir" && exec virtuoso-t -f -c "$dir/virtuoso.ini") >"$dir/stdout.log" 2>&1 &
pid=$!
endpoint="http://127.0.0.1:$http_port/sparql"
ready=""
for _ in $(seq 1 1200); do
  kill -0 "$pid" 2>/dev/null || break
  if curl -sf -o /dev/null --max-time 2 "$endpoint?query=ASK%7B%7D"; then ready=1; break; fi
  sleep 0.1
done
if [ -z "$ready" ]; then
  echo "with_virtuoso: virtuoso-t did not answer on $endpoint within 120 s; its log:" >&2
  tail -20 "$dir/virtuoso.log" "$dir/stdout.log" >&2 2>/dev/null
  exit 1
fi
echo "with_virtuoso: virtuoso-t (pid $pid) at $endpoint"
MESHFLOW_VIRTUOSO="$endpoint" MESHFLOW_VIRTUOSO_ISQL="127.0.0.1:$sql_port" "$@"
