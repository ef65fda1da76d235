#!/usr/bin/env bash
# The README's "run" command: set up what the server lacks, build the server alone (the test
# command builds the tests and benchmarks), then start it with its default scene (seed) and
# print the viewer URL. Extra arguments go to tumble-server (e.g. --scene many --port 8081).
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh server
exec build/release/server/tumble-server "$@"
