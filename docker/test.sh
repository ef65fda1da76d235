#!/usr/bin/env bash
# Real build-and-run test of docker/: builds the image, brings the service up with compose,
# checks it from outside the container, stops it with SIGTERM and checks the clean exit.
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
# Beside compose.yaml, so its relative build context still resolves (git-ignored).
HOSTNET_COMPOSE=docker/.compose.hostnet.yaml
export DOCKER_HOST=unix://$WORK/docker.sock
DOCKERD_PID=""
cleanup() {
  local rc=$?
  set +e
  if [ -n "$DOCKERD_PID" ] && kill -0 "$DOCKERD_PID" 2>/dev/null; then
    "${COMPOSE[@]}" -p "$PROJECT" -f "$HOSTNET_COMPOSE" -f docker/compose.test.yaml \
      down --timeout 2 >/dev/null 2>&1
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

# ---- up, healthy, probe -------------------------------------------------------------------------
TUMBLE_TEST_PORT=$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
export TUMBLE_TEST_PORT
# Host networking cannot publish ports, and Compose v1 merges (cannot drop) the base file's
# `ports:` list, so the test runs docker/compose.yaml with that one block removed; everything
# else (image, environment, read-only root, tmpfs, capabilities, healthcheck) is as shipped.
"${COMPOSE[@]}" -f docker/compose.yaml config -q || fail "compose config (docker/compose.yaml)"
python3 - docker/compose.yaml "$HOSTNET_COMPOSE" <<'PY' || fail "deriving the host-network compose file"
import sys
lines, out, skip = open(sys.argv[1]).read().splitlines(), [], False
for line in lines:
    if line.strip() == "ports:":
        skip = True
        continue
    if skip and line.lstrip().startswith("- "):
        continue
    skip = False
    out.append(line)
open(sys.argv[2], "w").write("\n".join(out) + "\n")
PY
compose() { "${COMPOSE[@]}" -p "$PROJECT" -f "$HOSTNET_COMPOSE" -f docker/compose.test.yaml "$@"; }
compose config -q || fail "compose config"
T=$(now)
log "compose up (host network, port $TUMBLE_TEST_PORT)"
compose up -d --no-build >"$WORK/up.log" 2>&1 || { cat "$WORK/up.log"; fail "compose up"; }
cid=$(compose ps -q tumble)
[ -n "$cid" ] || fail "compose up made no container"
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
  fail "the container did not become healthy (state $state, health $health)"
fi
T_HEALTHY=$(since "$T")
log "healthy ${T_HEALTHY} s after 'compose up'"

user=$("$DOCKER" inspect -f '{{.Config.User}}' "$cid")
ro=$("$DOCKER" inspect -f '{{.HostConfig.ReadonlyRootfs}}' "$cid")
uid=$("$DOCKER" exec "$cid" id -u)
[ "$uid" != 0 ] || fail "the server runs as root"
[ "$ro" = true ] || fail "the root file system is not read-only"
log "runs as user '$user' (uid $uid), read-only root fs"

python3 docker/probe.py 127.0.0.1 "$TUMBLE_TEST_PORT" || { compose logs --tail 40; fail "probe"; }

# ---- SIGTERM: a clean exit (code 0) within 2 s ------------------------------------------------
T=$(now)
compose stop --timeout 2 >"$WORK/stop.log" 2>&1 || { cat "$WORK/stop.log"; fail "compose stop"; }
T_STOP=$(since "$T")
code=$("$DOCKER" inspect -f '{{.State.ExitCode}}' "$cid")
oom=$("$DOCKER" inspect -f '{{.State.OOMKilled}}' "$cid")
log "compose stop (SIGTERM): exited with code $code after ${T_STOP} s"
if [ "$code" != 0 ] || [ "$oom" != false ]; then
  compose logs --tail 40
  fail "exit code $code after SIGTERM (137 = killed after the 2 s grace period)"
fi
awk -v t="$T_STOP" 'BEGIN { exit !(t < 2.0) }' || fail "stopping took ${T_STOP} s (limit 2 s)"
compose logs --no-color --tail 5 | sed 's/^/    /'
compose down --timeout 2 >/dev/null 2>&1 || true

awk -v s="$SIZE_MB" -v b="$BUDGET_MB" 'BEGIN { exit !(s <= b) }' \
  || fail "runtime image is ${SIZE_MB} MB, over the ${BUDGET_MB} MB budget"

echo
echo "=== docker/test.sh PASSED ==="
printf '  %-28s %s s (%s)\n' "base images" "$T_BASE" "$BASE_HOW"
printf '  %-28s %s s\n' "dockerd start" "$T_ENGINE"
printf '  %-28s %s s (%s cores; load average %s before, %s after)\n' \
  "docker build (incl. tests)" "$T_BUILD" "$(nproc)" "$LOAD_BEFORE" "$LOAD_AFTER"
printf '  %-28s %s s\n' "compose up -> healthy" "$T_HEALTHY"
printf '  %-28s %s s, exit code %s\n' "SIGTERM -> exited" "$T_STOP" "$code"
printf '  %-28s %s MB (budget %s MB)\n' "runtime image size" "$SIZE_MB" "$BUDGET_MB"
printf '  %-28s %s s\n' "total" "$(since "$T_START")"
