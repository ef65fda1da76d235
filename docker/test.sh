#!/usr/bin/env bash
# Real build-and-run test of docker/: builds the server image and the HAProxy image, brings up
# docker/compose.scale.yaml with 3 replicas behind HAProxy, checks it from outside (the default
# world, then two worlds created through HAProxy, each with REST and a WebSocket), stops it with
# SIGTERM and checks the clean exit. (docker/compose.yaml, the single server, is validated with
# `compose config`: the scale run exercises the same image and settings.)
#
# It needs no Docker installation of its own: it installs Debian's docker.io, containerd, runc,
# debootstrap and docker-compose if missing, starts a private Docker engine (state under a temp
# dir, no bridge, no iptables) and stops it again on every exit path. With no registry to pull
# from, the base images debian:bookworm and debian:bookworm-slim are made locally with
# debootstrap; the root file systems are cached as tarballs in $TUMBLE_DOCKER_CACHE
# (default /var/cache/tumble-docker) and reused on later runs.
#
# If Docker cannot run here (not root, no overlay file system, the engine does not start, or it
# cannot start a container) it prints SKIPPED and exits 0. Any failure after that exits 1.
#
# usage: docker/test.sh          env: TUMBLE_DOCKER_CACHE, TUMBLE_IMAGE_BUDGET_MB (150),
#                                     TUMBLE_DOCKER_KEEP=1 (keep the temp dir for debugging)
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
CACHE=${TUMBLE_DOCKER_CACHE:-/var/cache/tumble-docker}
BUDGET_MB=${TUMBLE_IMAGE_BUDGET_MB:-150}
IMAGE=tumble:latest
PROXY_IMAGE=tumble-haproxy:latest
REPLICAS=3
PROJECT=tumbletest
T_START=$(date +%s.%N)

now() { date +%s.%N; }
since() { awk -v a="$1" -v b="$(now)" 'BEGIN { printf "%.1f", b - a }'; }
log() { printf '[docker-test %6ss] %s\n' "$(since "$T_START")" "$*"; }
skip() {
  echo
  echo "######################################################################"
  echo "### docker/test.sh SKIPPED: $*"
  echo "### (Docker cannot run on this machine; nothing about docker/ was tested)"
  echo "######################################################################"
  exit 0
}
fail() {
  echo
  echo "### docker/test.sh FAILED: $*"
  exit 1
}

# ---- preconditions: root (dockerd needs it), packages, overlay --------------------------------
[ "$(id -u)" = 0 ] || skip "not root (a private dockerd needs root)"
need=()
for p in docker.io containerd runc debootstrap docker-compose; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || need+=("$p")
done
if ((${#need[@]})); then
  log "installing ${need[*]}"
  { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq \
      --no-install-recommends "${need[@]}"; } >/tmp/tumble-docker-apt.log 2>&1 \
    || skip "apt-get install ${need[*]} failed (see /tmp/tumble-docker-apt.log)"
fi
grep -qw overlay /proc/filesystems || modprobe overlay 2>/dev/null || true
grep -qw overlay /proc/filesystems || skip "the kernel has no overlay file system"

# Debian's dockerd and client (the docker in /usr/local/bin, if any, may be another version).
DOCKERD=/usr/sbin/dockerd
DOCKER=/usr/bin/docker
export PATH=/usr/sbin:/usr/bin:$PATH
if command -v docker-compose >/dev/null; then
  COMPOSE=(docker-compose)
elif "$DOCKER" compose version >/dev/null 2>&1; then
  COMPOSE=("$DOCKER" compose)
else
  fail "neither docker-compose nor the docker compose plugin is installed"
fi

# ---- private Docker engine ------------------------------------------------------------------
# Not under /tmp if that is a tmpfs or overlay: overlay2 needs a real file system below it.
WORK=$(mktemp -d /var/tmp/tumble-docker.XXXXXX)
export DOCKER_HOST=unix://$WORK/docker.sock
DOCKERD_PID=""
cleanup() {
  local rc=$?
  set +e
  if [ -n "$DOCKERD_PID" ] && kill -0 "$DOCKERD_PID" 2>/dev/null; then
    "${COMPOSE[@]}" -p "$PROJECT" -f docker/compose.scale.yaml down --timeout 2 >/dev/null 2>&1
    kill -TERM "$DOCKERD_PID" 2>/dev/null
    for _ in $(seq 1 150); do kill -0 "$DOCKERD_PID" 2>/dev/null || break; sleep 0.1; done
    kill -0 "$DOCKERD_PID" 2>/dev/null && kill -KILL "$DOCKERD_PID" 2>/dev/null
    wait "$DOCKERD_PID" 2>/dev/null
  fi
  # Whatever the engine left mounted under the temp dir, deepest first, before removing it.
  awk -v w="$WORK" '$2 ~ "^"w { print $2 }' /proc/mounts | sort -r | xargs -r -n1 umount -l
  if [ "${TUMBLE_DOCKER_KEEP:-0}" = 1 ]; then
    echo "docker-test: kept $WORK (dockerd.log, build.log)"
  else
    rm -rf "$WORK"
  fi
  exit "$rc"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

T=$(now)
log "starting a private dockerd (state in $WORK)"
"$DOCKERD" --data-root "$WORK/data" --exec-root "$WORK/exec" --pidfile "$WORK/dockerd.pid" \
  -H "$DOCKER_HOST" --bridge=none --iptables=false --ip6tables=false \
  --storage-driver overlay2 >"$WORK/dockerd.log" 2>&1 &
DOCKERD_PID=$!
for _ in $(seq 1 120); do
  "$DOCKER" version >/dev/null 2>&1 && break
  kill -0 "$DOCKERD_PID" 2>/dev/null || break
  sleep 0.5
done
if ! "$DOCKER" version >/dev/null 2>&1; then
  tail -n 15 "$WORK/dockerd.log"
  skip "dockerd did not start (log above)"
fi
driver=$("$DOCKER" info -f '{{.Driver}}')
[ "$driver" = overlay2 ] || skip "dockerd runs with storage driver '$driver', not overlay2"
T_ENGINE=$(since "$T")
log "dockerd ready in ${T_ENGINE} s (pid $DOCKERD_PID, $("$DOCKER" version -f '{{.Server.Version}}'))"

# ---- base images: debootstrap once, cached; docker import every run -------------------------
T=$(now)
mkdir -p "$CACHE"
FULL_TAR=$CACHE/debian-bookworm-minbase-v1.tar
SLIM_TAR=$CACHE/debian-bookworm-slim-v1.tar
if [ -s "$FULL_TAR" ] && [ -s "$SLIM_TAR" ]; then
  BASE_HOW="from cache $CACHE"
else
  BASE_HOW="debootstrap, cached in $CACHE"
  rootfs=$WORK/rootfs
  log "making the bookworm root fs with debootstrap --variant=minbase (once; cached)"
  debootstrap --variant=minbase bookworm "$rootfs" http://deb.debian.org/debian \
    >"$WORK/debootstrap.log" 2>&1 || { tail -n 20 "$WORK/debootstrap.log"; fail "debootstrap"; }
  # The official images' package sources (with updates and security) in place of debootstrap's.
  rm -f "$rootfs/etc/apt/sources.list"
  cat >"$rootfs/etc/apt/sources.list.d/debian.sources" <<'EOF'
Types: deb
URIs: http://deb.debian.org/debian
Suites: bookworm bookworm-updates
Components: main
Signed-By: /usr/share/keyrings/debian-archive-keyring.gpg

Types: deb
URIs: http://deb.debian.org/debian-security
Suites: bookworm-security
Components: main
Signed-By: /usr/share/keyrings/debian-archive-keyring.gpg
EOF
  rm -rf "$rootfs"/var/lib/apt/lists/* "$rootfs"/var/cache/apt/*.bin \
    "$rootfs"/var/cache/apt/archives/*.deb "$rootfs"/var/log/* 2>/dev/null || true
  tar --numeric-owner -C "$rootfs" -cf "$FULL_TAR.part" . && mv "$FULL_TAR.part" "$FULL_TAR"
  # -slim as the official one is made: no docs (but copyrights), man pages, info, locales;
  # dpkg keeps them out of later installs too.
  cat >"$rootfs/etc/dpkg/dpkg.cfg.d/docker-slim" <<'EOF'
path-exclude /usr/share/doc/*
path-include /usr/share/doc/*/copyright
path-exclude /usr/share/man/*
path-exclude /usr/share/info/*
path-exclude /usr/share/locale/*
path-include /usr/share/locale/locale.alias
path-exclude /usr/share/lintian/*
path-exclude /usr/share/groff/*
path-exclude /usr/share/linda/*
EOF
  find "$rootfs/usr/share/doc" -mindepth 1 -not -name copyright -not -type d -delete
  find "$rootfs/usr/share/doc" -mindepth 1 -type d -empty -delete
  rm -rf "$rootfs"/usr/share/man/* "$rootfs"/usr/share/info/* "$rootfs"/usr/share/lintian/* \
    "$rootfs"/usr/share/groff/* "$rootfs"/usr/share/linda/*
  find "$rootfs/usr/share/locale" -mindepth 1 -maxdepth 1 -not -name locale.alias \
    -exec rm -rf {} +
  tar --numeric-owner -C "$rootfs" -cf "$SLIM_TAR.part" . && mv "$SLIM_TAR.part" "$SLIM_TAR"
  rm -rf "$rootfs"
fi
"$DOCKER" import -c 'CMD ["bash"]' - debian:bookworm <"$FULL_TAR" >/dev/null
"$DOCKER" import -c 'CMD ["bash"]' - debian:bookworm-slim <"$SLIM_TAR" >/dev/null
T_BASE=$(since "$T")
log "base images debian:bookworm and debian:bookworm-slim ready in ${T_BASE} s ($BASE_HOW)"

"$DOCKER" run --rm --network host debian:bookworm-slim true >"$WORK/smoke.log" 2>&1 \
  || { cat "$WORK/smoke.log"; skip "the engine cannot start a container (output above)"; }

# ---- build ------------------------------------------------------------------------------------
# A host with a TLS-intercepting proxy has its CA in /usr/local/share/ca-certificates: the build
# needs it for npm (see EXTRA_CA_CERTS in the Dockerfile); the runtime image never sees it.
ca_args=()
shopt -s nullglob
cas=(/usr/local/share/ca-certificates/*.crt)
shopt -u nullglob
((${#cas[@]})) && ca_args=(--build-arg "EXTRA_CA_CERTS=$(cat "${cas[@]}")")
T=$(now)
LOAD_BEFORE=$(cut -d' ' -f1-3 /proc/loadavg)
log "docker build with BuildKit (the C++ build and the unit tests run inside; $(nproc) cores, load $LOAD_BEFORE)"
if ! DOCKER_BUILDKIT=1 "$DOCKER" build --progress plain --network host "${ca_args[@]}" \
    -t "$IMAGE" -f docker/Dockerfile . >"$WORK/build.log" 2>&1; then
  grep -v '^#[0-9]* sha256:' "$WORK/build.log" | tail -n 60
  fail "docker build (last lines above)"
fi
T_BUILD=$(since "$T")
size=$("$DOCKER" image inspect -f '{{.Size}}' "$IMAGE")
SIZE_MB=$(awk -v s="$size" 'BEGIN { printf "%.1f", s / 1e6 }')
LOAD_AFTER=$(cut -d' ' -f1-3 /proc/loadavg)
log "image $IMAGE built in ${T_BUILD} s, ${SIZE_MB} MB (load now $LOAD_AFTER); the slowest steps:"
# BuildKit's plain log: "#7 [build 3/10] RUN ..." names a step, "#7 DONE 81.2s" times it.
awk '/^#[0-9]+ \[/ { id = $1; sub(/^#[0-9]+ /, ""); name[id] = substr($0, 1, 90) }
     /^#[0-9]+ DONE / && ($1 in name) { t = $3; sub(/s$/, "", t); printf "%8.1f s  %s\n", t, name[$1] }' \
  "$WORK/build.log" | sort -rn | head -n 6
grep -E 'tests passed|tests failed' "$WORK/build.log" | tail -n 1 | sed 's/^#[0-9]* [0-9.]* /    ctest in the build: /' || true

# ---- the HAProxy image: a stage of the same Dockerfile on the same base ------------------------
T=$(now)
if ! DOCKER_BUILDKIT=1 "$DOCKER" build --progress plain --network host --target haproxy \
    -t "$PROXY_IMAGE" -f docker/Dockerfile . >"$WORK/build-haproxy.log" 2>&1; then
  tail -n 30 "$WORK/build-haproxy.log"
  fail "docker build --target haproxy (last lines above)"
fi
T_PROXY_BUILD=$(since "$T")
PROXY_MB=$("$DOCKER" image inspect -f '{{.Size}}' "$PROXY_IMAGE" | awk '{ printf "%.1f", $1 / 1e6 }')
log "image $PROXY_IMAGE built in ${T_PROXY_BUILD} s, ${PROXY_MB} MB"

# ---- up: 3 replicas + HAProxy, healthy, probe ---------------------------------------------------
# The private engine has no default bridge (--bridge=none), but compose's own network is a
# user-defined bridge with Docker's DNS, which is what HAProxy finds the replicas through.
# HAProxy alone publishes a port: a free one on 127.0.0.1.
TUMBLE_TEST_PORT=$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
export TUMBLE_PUBLISH=127.0.0.1:$TUMBLE_TEST_PORT TUMBLE_REPLICAS=$REPLICAS
"${COMPOSE[@]}" -f docker/compose.yaml config -q || fail "compose config (docker/compose.yaml)"
compose() { "${COMPOSE[@]}" -p "$PROJECT" -f docker/compose.scale.yaml "$@"; }
compose config -q || fail "compose config (docker/compose.scale.yaml)"
T=$(now)
log "compose up --scale tumble=$REPLICAS (HAProxy on 127.0.0.1:$TUMBLE_TEST_PORT)"
compose up -d --no-build --scale tumble=$REPLICAS >"$WORK/up.log" 2>&1 \
  || { cat "$WORK/up.log"; fail "compose up"; }
mapfile -t cids < <(compose ps -q tumble)
proxy_cid=$(compose ps -q haproxy)
[ "${#cids[@]}" = "$REPLICAS" ] || fail "compose up made ${#cids[@]} tumble containers, not $REPLICAS"
[ -n "$proxy_cid" ] || fail "compose up made no haproxy container"
for cid in "${cids[@]}"; do
  health=""
  for _ in $(seq 1 120); do
    health=$("$DOCKER" inspect -f '{{.State.Health.Status}}' "$cid")
    state=$("$DOCKER" inspect -f '{{.State.Status}}' "$cid")
    [ "$health" = healthy ] && break
    [ "$state" = running ] || break
    sleep 0.25
  done
  if [ "$health" != healthy ]; then
    compose logs --tail 40
    "$DOCKER" inspect -f '{{json .State}}' "$cid"
    fail "replica ${cid:0:12} did not become healthy (state $state, health $health)"
  fi
done
T_HEALTHY=$(since "$T")
log "$REPLICAS replicas healthy ${T_HEALTHY} s after 'compose up'"

cid=${cids[0]}
user=$("$DOCKER" inspect -f '{{.Config.User}}' "$cid")
ro=$("$DOCKER" inspect -f '{{.HostConfig.ReadonlyRootfs}}' "$cid")
uid=$("$DOCKER" exec "$cid" id -u)
[ "$uid" != 0 ] || fail "the server runs as root"
[ "$ro" = true ] || fail "the root file system is not read-only"
puid=$("$DOCKER" exec "$proxy_cid" id -u)
[ "$puid" != 0 ] || fail "haproxy runs as root"
log "servers run as user '$user' (uid $uid), read-only root fs; haproxy as uid $puid"

# HAProxy answers once it listens; its slots fill from Docker's DNS within a second of that
# (the replicas were in the DNS before they were healthy).
for _ in $(seq 1 40); do
  python3 -c 'import sys, urllib.request; urllib.request.urlopen(sys.argv[1], timeout=1)' \
    "http://127.0.0.1:$TUMBLE_TEST_PORT/haproxy-health" 2>/dev/null && break
  sleep 0.25
done
sleep 1
python3 docker/probe.py 127.0.0.1 "$TUMBLE_TEST_PORT" probe-a probe-b \
  || { compose logs --tail 40; fail "probe through HAProxy"; }

# Each probed world is on exactly one replica (asked directly, inside its container).
worlds_on() {
  "$DOCKER" exec "$1" bash -c 'exec 3<>/dev/tcp/127.0.0.1/8080
    printf "GET /api/worlds HTTP/1.1\r\nHost: localhost\r\nConnection: close\r\n\r\n" >&3
    timeout 2 cat <&3'
}
placement=""
for world in probe-a probe-b; do
  on=()
  for i in "${!cids[@]}"; do
    worlds_on "${cids[$i]}" | grep -q "\"id\": *\"$world\"" && on+=("$((i + 1))")
  done
  [ "${#on[@]}" = 1 ] || fail "world $world is on replicas [${on[*]}], expected exactly one"
  placement+=" $world on replica ${on[0]};"
done
log "placement:${placement%;}"

# ---- SIGTERM: a clean exit (code 0) of every replica within the 2 s grace period --------------
T=$(now)
compose stop --timeout 2 >"$WORK/stop.log" 2>&1 || { cat "$WORK/stop.log"; fail "compose stop"; }
T_STOP=$(since "$T")
codes=""
for cid in "${cids[@]}"; do
  code=$("$DOCKER" inspect -f '{{.State.ExitCode}}' "$cid")
  oom=$("$DOCKER" inspect -f '{{.State.OOMKilled}}' "$cid")
  codes+="$code "
  if [ "$code" != 0 ] || [ "$oom" != false ]; then
    compose logs --tail 40
    fail "replica exit code $code after SIGTERM (137 = killed after the 2 s grace period)"
  fi
done
proxy_code=$("$DOCKER" inspect -f '{{.State.ExitCode}}' "$proxy_cid")
log "compose stop (SIGTERM): replicas exited with codes ${codes% }, haproxy with $proxy_code, after ${T_STOP} s"
[ "$proxy_code" = 0 ] || fail "haproxy exit code $proxy_code after SIGTERM (137: it ignored SIGTERM as PID 1)"
# Four containers stop side by side on 2 cores: 3 s for all (each one is bounded by the grace).
awk -v t="$T_STOP" 'BEGIN { exit !(t < 3.0) }' || fail "stopping took ${T_STOP} s (limit 3 s)"
compose logs --no-color --tail 3 tumble | sed 's/^/    /'
compose down --timeout 2 >/dev/null 2>&1 || true

awk -v s="$SIZE_MB" -v b="$BUDGET_MB" 'BEGIN { exit !(s <= b) }' \
  || fail "runtime image is ${SIZE_MB} MB, over the ${BUDGET_MB} MB budget"

echo
echo "=== docker/test.sh PASSED ==="
printf '  %-28s %s s (%s)\n' "base images" "$T_BASE" "$BASE_HOW"
printf '  %-28s %s s\n' "dockerd start" "$T_ENGINE"
printf '  %-28s %s s (%s cores; load average %s before, %s after)\n' \
  "docker build (incl. tests)" "$T_BUILD" "$(nproc)" "$LOAD_BEFORE" "$LOAD_AFTER"
printf '  %-28s %s s, %s MB\n' "haproxy image build" "$T_PROXY_BUILD" "$PROXY_MB"
printf '  %-28s %s s\n' "up -> $REPLICAS replicas healthy" "$T_HEALTHY"
printf '  %-28s%s\n' "worlds through HAProxy" "$placement"
printf '  %-28s %s s, exit codes %s\n' "SIGTERM -> exited" "$T_STOP" "${codes% }"
printf '  %-28s %s MB (budget %s MB)\n' "runtime image size" "$SIZE_MB" "$BUDGET_MB"
printf '  %-28s %s s\n' "total" "$(since "$T_START")"
