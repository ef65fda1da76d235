#!/usr/bin/env bash
# CI, after the README's test command: the engine and server test suites under ASan+UBSan
# (preset asan, -O1) and under TSan (preset tsan, -O1), then each libFuzzer target (preset
# fuzz, clang) for FUZZ_SECONDS on its committed seed corpus. Bench and e2e are not built
# or run here. Any sanitizer report fails the run (halt_on_error), so does any fuzz crash.
#   FUZZ_SECONDS=60 JOBS=2 bash .ci/sanitizers.sh
# Summaries: docs/hardening.md.
set -euo pipefail
cd "$(dirname "$0")/.."
JOBS=${JOBS:-2}
FUZZ_SECONDS=${FUZZ_SECONDS:-60}
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1:strict_string_checks=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
export TSAN_OPTIONS=halt_on_error=1:second_deadlock_stack=1
# The load test measures real-time behaviour, which sanitizers slow by design; e2e needs a
# browser; bench is not built.
EXCLUDE='server_load_ci|e2e_|bench_'

run_preset() {
  local preset=$1 flags=$2
  echo "=== ${preset}: configure, build, ctest"
  cmake --preset "${preset}" -DTUMBLE_BUILD_BENCH=OFF "-DCMAKE_CXX_FLAGS=${flags}" \
        -DTUMBLE_NODE=TUMBLE_NODE-NOTFOUND >/dev/null
  ninja -C "build/${preset}" -j"${JOBS}" engine_tests server_tests tumble-server
  ctest --test-dir "build/${preset}" --output-on-failure -j1 -E "${EXCLUDE}"
}

start=$(date +%s)
run_preset asan "-O1 -g -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=all"
# -Wno-tsan: GCC warns that Asio's atomic_thread_fence is not instrumented (harmless here).
run_preset tsan "-O1 -g -fsanitize=thread -Wno-tsan"
echo "=== sanitizers done in $(( $(date +%s) - start )) s"

echo "=== fuzz: configure, build"
cmake --preset fuzz -DTUMBLE_NODE=TUMBLE_NODE-NOTFOUND >/dev/null
ninja -C build/fuzz -j"${JOBS}" scene_fuzz rest_fuzz frame_fuzz
for target in scene rest frame; do
  echo "=== fuzz: ${target}_fuzz for ${FUZZ_SECONDS} s"
  work=$(mktemp -d)
  cp tests/fuzz/corpus/${target}/* "${work}/"
  (cd build/fuzz && "./tests/fuzz/${target}_fuzz" -max_total_time="${FUZZ_SECONDS}" \
      -max_len=65536 -rss_limit_mb=2048 -print_final_stats=1 "${work}" 2>&1 | tail -n 15)
  rm -rf "${work}"
done
echo "=== sanitizers and fuzz done in $(( $(date +%s) - start )) s"
