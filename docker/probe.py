#!/usr/bin/env python3
"""Checks a running Tumble server from outside its container, with the standard library only.

usage: probe.py HOST PORT [WORLD ...]

- GET /api/health is 200 with {"status": "ok"}
- GET /api/state is 200 with time, step and a list of bodies
- GET / serves the viewer's HTML, and every local URL of its import map (three, lil-gui, ...
  from web/node_modules) is served too
- WebSocket /ws: a raw RFC 6455 handshake, then the text scene message, then one binary frame
  whose header and length match docs/protocol.md

- for each WORLD (docker/compose.scale.yaml, through HAProxy): PUT /api/worlds/WORLD with the
  seed scene is 201 (or 200 when it exists), GET /api/worlds/WORLD/state is 200 with bodies,
  and /ws?world=WORLD gives the scene message and a keyframe

Prints one line per check; exits 1 at the first failure.
"""
import base64
import hashlib
import json
import os
import re
import socket
import struct
import sys
import time
import urllib.parse
import urllib.request

HOST, PORT, WORLDS = sys.argv[1], int(sys.argv[2]), sys.argv[3:]
BASE = f"http://{HOST}:{PORT}"
TIMEOUT = 5.0


def fail(msg):
    print(f"probe: FAIL {msg}")
    sys.exit(1)


def ok(msg):
    print(f"probe: ok   {msg}")


def get(path):
    try:
        with urllib.request.urlopen(BASE + path, timeout=TIMEOUT) as r:
            return r.status, r.headers.get("Content-Type", ""), r.read()
    except urllib.error.HTTPError as e:
        return e.code, e.headers.get("Content-Type", ""), e.read()
    except OSError as e:
        fail(f"GET {path}: {e}")


def put_json(path, value):
    req = urllib.request.Request(BASE + path, data=json.dumps(value).encode(), method="PUT",
                                 headers={"Content-Type": "application/json"})
    try:
        with urllib.request.urlopen(req, timeout=TIMEOUT) as r:
            return r.status, r.read()
    except urllib.error.HTTPError as e:
        return e.code, e.read()
    except OSError as e:
        fail(f"PUT {path}: {e}")


def check_world(world):
    status, body = put_json(f"/api/worlds/{world}", {"scene": "seed"})
    if status not in (200, 201):
        fail(f"PUT /api/worlds/{world} -> {status} {body[:200]!r}")
    ok(f"PUT /api/worlds/{world} -> {status}")
    status, _, body = get(f"/api/worlds/{world}/state")
    if status != 200 or not json.loads(body).get("bodies"):
        fail(f"GET /api/worlds/{world}/state -> {status} {body[:200]!r}")
    ok(f"GET /api/worlds/{world}/state -> 200, t={json.loads(body)['time']:.3f} s")
    check_websocket(f"/ws?world={world}")


def check_rest():
    status, _, body = get("/api/health")
    if status != 200 or json.loads(body) != {"status": "ok"}:
        fail(f"GET /api/health -> {status} {body[:200]!r}")
    ok("GET /api/health -> 200 {\"status\":\"ok\"}")

    status, _, body = get("/api/state")
    if status != 200:
        fail(f"GET /api/state -> {status} {body[:200]!r}")
    state = json.loads(body)
    for key in ("time", "step", "bodies"):
        if key not in state:
            fail(f"GET /api/state has no '{key}': {body[:200]!r}")
    if not isinstance(state["bodies"], list) or not state["bodies"]:
        fail(f"GET /api/state has no bodies: {body[:200]!r}")
    ok(f"GET /api/state -> 200, {len(state['bodies'])} bodies, t={state['time']:.3f} s, "
       f"step {state['step']}")


def check_viewer():
    status, ctype, body = get("/")
    if status != 200 or "html" not in ctype.lower():
        fail(f"GET / -> {status} {ctype!r}")
    html = body.decode("utf-8", "replace")
    ok(f"GET / -> 200 {ctype} ({len(body)} bytes)")
    m = re.search(r'<script[^>]*type="importmap"[^>]*>(.*?)</script>', html, re.S)
    if not m:
        print("probe: note no import map in index.html; module URLs not checked")
        return
    imports = json.loads(m.group(1)).get("imports", {})
    local = {k: v for k, v in imports.items() if not re.match(r"^[a-z]+:", v)}
    if not local:
        fail("the import map has no local URLs (web/node_modules not served?)")
    checked = []
    for name, url in sorted(local.items()):
        path = urllib.parse.urljoin("/", url)
        if path.endswith("/"):  # a prefix mapping ("three/addons/") names no single file
            continue
        status, _, body = get(path)
        if status != 200 or not body:
            fail(f"import map '{name}' -> GET {path} -> {status}")
        checked.append(name)
    if not checked:
        fail("the import map names no local module file")
    ok(f"import map: {len(checked)} module files served ({', '.join(checked)})")


def recv_exact(sock, n):
    buf = bytearray()
    while len(buf) < n:
        chunk = sock.recv(n - len(buf))
        if not chunk:
            fail(f"WebSocket closed by the server ({len(buf)} of {n} bytes read)")
        buf += chunk
    return bytes(buf)


def recv_message(sock):
    """One whole message (joins fragments); control frames other than close are skipped."""
    opcode, payload = None, bytearray()
    while True:
        b0, b1 = recv_exact(sock, 2)
        fin, op, masked, n = b0 & 0x80, b0 & 0x0F, b1 & 0x80, b1 & 0x7F
        if n == 126:
            n = struct.unpack("!H", recv_exact(sock, 2))[0]
        elif n == 127:
            n = struct.unpack("!Q", recv_exact(sock, 8))[0]
        if masked:
            fail("the server sent a masked frame")
        data = recv_exact(sock, n)
        if op == 8:
            fail(f"WebSocket close from the server: {data[:2].hex()} {data[2:]!r}")
        if op in (9, 10):  # ping / pong: not needed here
            continue
        if op != 0:
            opcode = op
        payload += data
        if fin:
            return opcode, bytes(payload)


def send_close(sock):
    mask = os.urandom(4)
    code = struct.pack("!H", 1000)
    sock.sendall(bytes([0x88, 0x80 | len(code)]) + mask
                 + bytes(c ^ mask[i % 4] for i, c in enumerate(code)))


def check_websocket(target="/ws"):
    key = base64.b64encode(os.urandom(16)).decode()
    sock = socket.create_connection((HOST, PORT), timeout=TIMEOUT)
    sock.sendall((f"GET {target} HTTP/1.1\r\nHost: {HOST}:{PORT}\r\nUpgrade: websocket\r\n"
                  f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\n"
                  f"Sec-WebSocket-Version: 13\r\n\r\n").encode())
    head = b""
    while b"\r\n\r\n" not in head:
        head += recv_exact(sock, 1)
    lines = head.decode("latin-1").split("\r\n")
    if " 101 " not in lines[0] + " ":
        fail(f"WebSocket handshake: {lines[0]}")
    accept = base64.b64encode(hashlib.sha1(
        (key + "258EAFA5-E914-47DA-95CA-C5AB0DC85B11").encode()).digest()).decode()
    headers = {l.split(":", 1)[0].strip().lower(): l.split(":", 1)[1].strip()
               for l in lines[1:] if ":" in l}
    if headers.get("sec-websocket-accept") != accept:
        fail("WebSocket handshake: wrong Sec-WebSocket-Accept")
    ok(f"WebSocket {target} handshake -> 101")

    op, data = recv_message(sock)
    if op != 1:
        fail(f"first WebSocket message is opcode {op}, not the text scene message")
    scene = json.loads(data)
    if scene.get("type") != "scene":
        fail(f"first WebSocket message is not a scene: {data[:200]!r}")
    ok(f"WebSocket text message: scene with {len(scene.get('bodies', []))} bodies")

    t0 = time.monotonic()
    while True:
        op, data = recv_message(sock)
        if op == 2:
            break
        if time.monotonic() - t0 > TIMEOUT:
            fail("no binary frame within 5 s")
    if len(data) < 40 or data[:4] != b"TMBL":
        fail(f"binary frame has no TMBL header: {data[:40]!r}")
    # docs/protocol.md, version 2: the first frame a viewer gets is a keyframe.
    version, flags, frame, base, n, m = struct.unpack_from("<HHIIII", data, 4)
    sim_time, energy = struct.unpack_from("<dd", data, 24)
    if version != 2:
        fail(f"binary frame format version {version}, expected 2")
    if not flags & 4 or m != n or base != frame:
        fail(f"first binary frame is not a keyframe (flags {flags}, base {base}, frame {frame}, "
             f"{m} of {n} bodies)")
    offset = 40
    for _ in range(m):  # format byte, centre (i32 or i16 ×3), axes (i32 or i16 ×9)
        if offset >= len(data):
            fail(f"keyframe ends inside its records ({len(data)} bytes)")
        fmt = data[offset]
        offset += 1 + (12 if fmt & 4 else 6) + (36 if fmt & 8 else 18)
    if offset != len(data):
        fail(f"keyframe is {len(data)} bytes, its {m} records end at {offset}")
    ok(f"WebSocket keyframe: {len(data)} bytes, version {version}, frame {frame}, "
       f"{n} bodies, t={sim_time:.3f} s, {1000 * (time.monotonic() - t0):.0f} ms after the scene")
    send_close(sock)
    sock.close()


if __name__ == "__main__":
    check_rest()
    check_viewer()
    check_websocket()
    for w in WORLDS:
        check_world(w)
    print("probe: all checks passed")
