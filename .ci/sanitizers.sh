#!/usr/bin/env bash
# CI, after the README's test command: the engine and server test suites under ASan+UBSan and
# under TSan, then each libFuzzer target for FUZZ_SECONDS on its committed seed corpus.
#   FUZZ_SECONDS=60 JOBS=2 bash .ci/sanitizers.sh          summaries: docs/hardening.md
#
# Both presets use Debian's clang (installed here if missing): it builds the Beast-heavy server
# faster than GCC at -O1, and it lets one build serve two purposes: the `asan` preset compiles
# everything with `-fsanitize=fuzzer-no-link` (coverage hooks, inert without libFuzzer), so the
# fuzz targets it links are the same ASan+UBSan objects the test suites ran on — one build
# instead of two. (The `fuzz` preset, -O2, is for long runs by hand.) Both build as unity builds
# (CMake merges each target's sources, eight to a file, so the Beast and Asio templates the
# server and its tests share are compiled once per batch instead of once per file) with line
# tables only for debug information (CMAKE_CXX_FLAGS_DEBUG: what a sanitizer's stack trace
# prints): the two builds took 7.4 min instead of 17.3 in clean-clone CI on 2 cores. The
# release preset stays one object per source, so each file still compiles on its own.
# Any sanitizer report fails the run (halt_on_error / -fno-sanitize-recover), so does any crash
# or leak found by a fuzzer; bench and e2e are neither built nor run.
set -euo pipefail
cd "$(dirname "$0")/.."
JOBS=${JOBS:-2}
FUZZ_SECONDS=${FUZZ_SECONDS:-60}
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1:strict_string_checks=1:detect_stack_use_after_return=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
export TSAN_OPTIONS=halt_on_error=1:second_deadlock_stack=1
# server_load_ci measures real-time behaviour, which sanitizers slow by design (it runs in the
# release suite). The 10^6-step orthonormality tests check rounding, not memory or threads:
# one integrator of the six runs here, for 10^6 steps like the others. The pile's settling
# (300 boxes for 10 s of simulated time: physics, 48 s under ASan) runs in release only; the
# tests that step the pile in a sanitizer build cut it to 300 boxes (tests/sanitized.hpp).
EXCLUDE='server_load_ci|e2e_|bench_|Stack.PyramidLargeStandsAndSleeps|PileHistoryTest|CheckpointEstimateCoversTheHeap|Pile.ThreeHundredBoxesSettle|Pile.PilesWithABoxRockingInPlaceSleep|Orthonormality.*/(euler|midpoint|rk4|symplectic_euler|splitting)( |$)'

missing=()
for p in clang libclang-rt-dev; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "sanitizers: installing ${missing[*]}"
  SUDO=""; [ "$(id -u)" = 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

start=$(date +%s)
stamp() { echo "=== $* ($(( $(date +%s) - start )) s)"; }

run_preset() {
  local preset=$1; shift
  stamp "${preset}: configure, build $*"
  cmake --preset "${preset}" -DTUMBLE_NODE=TUMBLE_NODE-NOTFOUND >/dev/null
  ninja -C "build/${preset}" -j"${JOBS}" "$@"
  # Engine tests are pure computation: both cores. Server tests measure real-time behaviour
  # (frame cadence, real-time factor): one at a time.
  stamp "${preset}: ctest, engine suite"
  ctest --preset "${preset}" -j"${JOBS}" -L engine -E "${EXCLUDE}"
  stamp "${preset}: ctest, server suite"
  ctest --preset "${preset}" -j1 -L server -E "${EXCLUDE}"
}

run_preset asan engine_tests server_tests tumble-server scene_fuzz rest_fuzz frame_fuzz chunked_fuzz
run_preset tsan engine_tests server_tests tumble-server

for target in scene rest frame chunked; do
  stamp "fuzz: ${target}_fuzz for ${FUZZ_SECONDS} s"
  work=$(mktemp -d)
  cp tests/fuzz/corpus/${target}/* "${work}/"
  # Crash inputs land in build/asan/fuzz-artifacts/ (a crash fails this script: set -e, pipefail).
  mkdir -p build/asan/fuzz-artifacts
  (cd build/asan && "./tests/fuzz/${target}_fuzz" -max_total_time="${FUZZ_SECONDS}" \
      -max_len=65536 -rss_limit_mb=2048 -print_final_stats=1 \
      -artifact_prefix=fuzz-artifacts/ "${work}" 2>&1 | tail -n 12)
  rm -rf "${work}"
done
stamp "sanitizers and fuzz: done"
