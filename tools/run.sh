#!/usr/bin/env bash
# The README's "run" command: set up what is missing, build, then start the server with its
# default scene (seed) and print the viewer URL. Extra arguments go to tumble-server
# (e.g. --scene many --port 8081).
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh
exec build/release/server/tumble-server "$@"
