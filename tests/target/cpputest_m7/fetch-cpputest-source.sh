#!/usr/bin/env bash
# fetch-cpputest-source.sh [<dest>]
#
# CppUTest is not packaged for arm-none-eabi, so the qemu-m7 build compiles
# Debian's CppUTest SOURCES with the cross compiler (tests/target/cpputest_m7).
# This fetches them with `apt-get source cpputest` (Debian's own source
# package; nothing is committed) into <dest> (default build/deps/cpputest),
# adding a deb-src entry that mirrors the system's deb entries if none exists.
# Idempotent: does nothing when the sources are already unpacked.
# Called by cmake/setup-debian.sh.
set -euo pipefail

repo_root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../../.." && pwd)
dest=${1:-$repo_root/build/deps/cpputest}

if compgen -G "$dest/cpputest-*/src/CppUTest/Utest.cpp" >/dev/null; then
  echo "fetch-cpputest-source.sh: CppUTest sources already in $dest"
  exit 0
fi

SUDO=()
if [[ $(id -u) -ne 0 ]]; then
  SUDO=(sudo)
fi
export DEBIAN_FRONTEND=noninteractive

# dpkg-source (dpkg-dev) unpacks the source package.
if ! command -v dpkg-source >/dev/null 2>&1; then
  "${SUDO[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends dpkg-dev
fi

if ! apt-get source --print-uris cpputest >/dev/null 2>&1; then
  echo "fetch-cpputest-source.sh: adding deb-src entries (mirroring the deb ones) and running apt-get update"
  if [[ -r /etc/apt/sources.list.d/debian.sources ]]; then
    sed 's/^Types: deb$/Types: deb-src/' /etc/apt/sources.list.d/debian.sources |
      "${SUDO[@]}" tee /etc/apt/sources.list.d/maglev-deb-src.sources >/dev/null
  elif [[ -r /etc/apt/sources.list ]]; then
    grep -E '^deb ' /etc/apt/sources.list | sed 's/^deb /deb-src /' |
      "${SUDO[@]}" tee /etc/apt/sources.list.d/maglev-deb-src.list >/dev/null
  else
    echo "fetch-cpputest-source.sh: no Debian apt sources found" >&2
    exit 1
  fi
  "${SUDO[@]}" env DEBIAN_FRONTEND=noninteractive apt-get update
fi

mkdir -p "$dest"
cd "$dest"
apt-get source cpputest
compgen -G "$dest/cpputest-*/src/CppUTest/Utest.cpp" >/dev/null
echo "fetch-cpputest-source.sh: CppUTest sources unpacked in $dest"
