#!/usr/bin/env bash
# The README's "test" command: set up what is missing, build, then run every test: the engine
# and server GoogleTest suites, the headless-browser test, the short benchmark run (all
# through ctest) and, when a Docker engine can be started here, the container test.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh
ctest --preset release --output-on-failure -j1
if [ -x docker/test.sh ]; then
  bash docker/test.sh
fi
