#!/bin/sh
# `make up`: starts what exists of the embedded default (DESIGN §1).
set -eu
mf=${1:-build/meshflow}
if "$mf" up --help >/dev/null 2>&1; then
  exec "$mf" up
fi
echo "meshflow: the hub and nodes ('meshflow up') are not built yet; the command-line tools are:"
"$mf" --help
