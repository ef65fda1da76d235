#!/usr/bin/env bash
# Container healthcheck: GET /api/health on the server's own port through bash's /dev/tcp,
# because debian:bookworm-slim has no curl or wget (and installing one costs image size).
# Healthy means a "200" status line and {"status":"ok"} in the body, within 2 s.
set -u
port=${TUMBLE_PORT:-8080}
exec 3<>"/dev/tcp/127.0.0.1/${port}" || { echo "health: cannot connect to port ${port}"; exit 1; }
printf 'GET /api/health HTTP/1.1\r\nHost: localhost\r\nConnection: close\r\n\r\n' >&3
# Connection: close ends the read; the timeout covers a server that keeps the connection open.
reply=$(timeout 2 cat <&3)
exec 3<&-
status=${reply%%$'\r'*}
case $status in
  "HTTP/1."?" 200"*) ;;
  *) echo "health: unexpected status line: ${status:-<none>}"; exit 1 ;;
esac
if [[ $reply =~ \"status\"[[:space:]]*:[[:space:]]*\"ok\" ]]; then
  exit 0
fi
echo "health: body has no \"status\":\"ok\""
exit 1
