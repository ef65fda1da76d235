#!/bin/sh
# Measures cadence, paused CPU and RTF of a fresh tumble-server (for the closing note).
# Usage: tests/server/measure.sh [BUILD_DIR]   (default build/srv; needs tumble-server and
# server_measure built). Prints the numbers; takes about a minute.
set -eu
BUILD=${1:-build/srv}
[ $# -gt 0 ] && shift
PORT=${TUMBLE_MEASURE_PORT:-18090}
"$BUILD/server/tumble-server" --port "$PORT" &
PID=$!
trap 'kill -TERM $PID 2>/dev/null || true' EXIT
sleep 1
"$BUILD/tests/server/server_measure" --port "$PORT" --pid "$PID" "$@"
kill -TERM $PID
wait $PID
echo "tumble-server exit status: $?"
trap - EXIT
