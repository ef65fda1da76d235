#!/usr/bin/env bash
# Installs what a fresh Debian 12 machine lacks (as root), installs the viewer's npm modules,
# then configures and builds the release preset. Idempotent: a second run only rebuilds.
#
# usage: tools/setup.sh          everything: the tests' and benchmarks' packages, every target
#        tools/setup.sh server   only what tumble-server needs (tools/run.sh): fewer packages,
#                                and the server target alone (42 of 114 build steps)
set -euo pipefail
cd "$(dirname "$0")/.."
mode=${1:-all}
case "$mode" in all | server) ;; *) echo "usage: tools/setup.sh [server]" >&2; exit 2 ;; esac

packages=(build-essential clang cmake ninja-build pkg-config git ca-certificates
  libboost1.81-dev libboost-program-options1.81-dev libeigen3-dev nlohmann-json3-dev
  zlib1g-dev nodejs)
if [ "$mode" = all ]; then
  # haproxy and python3-yaml are for tests only (tests/deploy: the loopback HAProxy test and the
  # manifest check); Debian's default haproxy.cfg has no listener, so its service binds nothing.
  packages+=(libgtest-dev libgmock-dev libbenchmark-dev chromium gnuplot-nox
    libbullet-dev libode-dev libmujoco-dev haproxy python3-yaml)
fi
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
command -v npm >/dev/null || missing+=(npm)
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}"
  SUDO=""; [ "$(id -u)" = 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

if [ -f web/package-lock.json ] && [ ! -d web/node_modules ] || [ web/package-lock.json -nt web/node_modules ]; then
  (cd web && npm ci --no-audit --no-fund)
fi

if [ "$mode" = server ]; then
  # A first configure leaves the tests and benchmarks out (their packages are not installed);
  # a build directory the test command already configured is kept as it is.
  [ -f build/release/CMakeCache.txt ] ||
    cmake --preset release -DTUMBLE_BUILD_TESTS=OFF -DTUMBLE_BUILD_BENCH=OFF >/dev/null
  cmake --build --preset release --target tumble-server
else
  cmake --preset release -DTUMBLE_BUILD_TESTS=ON -DTUMBLE_BUILD_BENCH=ON >/dev/null
  cmake --build --preset release
fi
