#!/bin/sh
# Installs the Debian packages meshflow needs, as root; quick when all are there.
# Usage: scripts/install-deps.sh build|test|bench
set -eu
group=${1:-build}

# libcurl4-gnutls-dev, not -openssl-dev: libraptor2-dev (Redland) depends on the GnuTLS flavour.
build="cmake ninja-build g++ pkg-config ccache libcli11-dev nlohmann-json3-dev zlib1g-dev libzstd-dev
  libssl-dev libsqlite3-dev libcgal-dev libgmp-dev libmpfr-dev libeigen3-dev libopenmesh-dev
  libxerces-c-dev librdf0-dev librdf-storage-sqlite libcpp-httplib-dev libcurl4-gnutls-dev
  libsodium-dev libgtest-dev libgmock-dev"
test="$build clang libclang-rt-14-dev zstd python3 curl raptor2-utils rasqal-utils python3-sparqlwrapper python3-rdflib
  virtuoso-opensource
  chromium nodejs"
bench="$test iproute2 time meshlab xvfb xauth libopenmesh-apps libmeshoptimizer-dev libbenchmark-dev"

case "$group" in
  build) want=$build ;;
  test) want=$test ;;
  bench) want=$bench ;;
  *) echo "install-deps: unknown group '$group' (build|test|bench)" >&2; exit 2 ;;
esac

missing=""
for p in $want; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing="$missing $p"
done
[ -z "$missing" ] && exit 0

if [ "$(id -u)" != 0 ]; then
  echo "install-deps: missing Debian packages:$missing (run as root, or install them)" >&2
  exit 1
fi
echo "install-deps: installing$missing"
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
# Name every wanted package, not only the missing ones: a missing one may need a newer
# version of one already installed (libssl-dev for libcpp-httplib-dev on Debian 12's image).
apt-get install -y -qq --no-install-recommends $want >/dev/null
