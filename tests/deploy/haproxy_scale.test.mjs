// Loopback test of deploy/haproxy/haproxy.cfg: three real tumble-server processes behind one real
// HAProxy, all on 127.0.0.1 (docs/scaling.md).
//
//   node --experimental-websocket tests/deploy/haproxy_scale.test.mjs
//
// 30 worlds are created through the proxy; each world's REST and its /ws?world= socket must
// reach the one backend that lists it (GET /api/worlds on each backend directly, viewers >= 1
// while the socket is open), and the worlds must spread over all three. Then one backend gets
// SIGTERM: its worlds must answer 503 through the proxy, the others 200 with their sim time
// still advancing.
//
// Run directly by node (not `node --test`), so that a missing haproxy can exit with 77, which
// ctest reports as skipped (SKIP_RETURN_CODE). Every child is killed on every exit path.
//
// Env: TUMBLE_SERVER   path of tumble-server (default build/release/server/tumble-server)
//      TUMBLE_HAPROXY  path of haproxy (default: PATH, then /usr/sbin/haproxy)
import { test, after } from 'node:test';
import assert from 'node:assert/strict';
import { spawn } from 'node:child_process';
import fs from 'node:fs';
import net from 'node:net';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

const kRepo = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '..', '..');
const kServer = process.env.TUMBLE_SERVER || path.join(kRepo, 'build/release/server/tumble-server');
const kConfig = path.join(kRepo, 'deploy/haproxy/haproxy.cfg');
const kBackends = 3;
const kWorlds = 30;
const kDeadline = Date.now() + 55000; // the whole run; ctest's TIMEOUT is the backstop

/** The haproxy binary, or null: $TUMBLE_HAPROXY, then PATH, then Debian's /usr/sbin. */
function findHaproxy() {
  if (process.env.TUMBLE_HAPROXY) return process.env.TUMBLE_HAPROXY;
  const dirs = (process.env.PATH || '').split(':').concat(['/usr/sbin', '/usr/local/sbin']);
  for (const dir of dirs) {
    const candidate = path.join(dir || '.', 'haproxy');
    try {
      fs.accessSync(candidate, fs.constants.X_OK);
      return candidate;
    } catch { /* not here */ }
  }
  return null;
}

const kHaproxy = findHaproxy();
if (!kHaproxy) {
  console.log('SKIPPED: haproxy not found (Debian\'s `haproxy` package; tools/setup.sh installs it)');
  process.exit(77);
}
if (typeof WebSocket !== 'function') {
  console.log('FAILED: no WebSocket in this node: run it with --experimental-websocket (node 20)');
  process.exit(1);
}

// ---- children: killed on every exit path -------------------------------------------------------
const children = [];
const tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'tumble-haproxy-'));
function killAll() {
  for (const c of children) if (c.exitCode === null && c.signalCode === null) c.kill('SIGKILL');
  fs.rmSync(tmp, { recursive: true, force: true });
}
process.on('exit', killAll);
for (const sig of ['SIGINT', 'SIGTERM', 'SIGHUP']) process.on(sig, () => process.exit(130));
setTimeout(() => {
  console.log('FAILED: over the 55 s budget');
  process.exit(1);
}, kDeadline - Date.now()).unref();

/** Spawns a child whose output is collected (printed when the test fails). */
function spawnChild(name, argv, env = {}) {
  const clean = Object.fromEntries(Object.entries(process.env).filter(([k]) => !k.startsWith('TUMBLE_')));
  const child = spawn(argv[0], argv.slice(1), { env: { ...clean, ...env }, stdio: ['ignore', 'pipe', 'pipe'] });
  child.name = name;
  child.output = '';
  child.stdout.on('data', (d) => { child.output += d; });
  child.stderr.on('data', (d) => { child.output += d; });
  children.push(child);
  return child;
}

const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));

/** Polls `probe` until it returns a truthy value; fails with `what` after `timeoutMs`. */
async function until(what, probe, timeoutMs = 10000, everyMs = 100) {
  const end = Math.min(Date.now() + timeoutMs, kDeadline);
  let last;
  for (;;) {
    try {
      last = await probe();
      if (last) return last;
    } catch (e) {
      last = e;
    }
    if (Date.now() > end) assert.fail(`timed out after ${timeoutMs} ms waiting for ${what} (last: ${last})`);
    await sleep(everyMs);
  }
}

/** Starts tumble-server on port 0; resolves with {child, port} once it prints its URL. */
async function startServer(index) {
  const child = spawnChild(`tumble-server ${index}`, [kServer, '--port', '0', '--bind', '127.0.0.1',
    '--scene', 'seed', '--web-root', path.join(kRepo, 'web')]);
  const port = await until(`tumble-server ${index} to print its URL`, () => {
    if (child.exitCode !== null) throw new Error(`exited ${child.exitCode}: ${child.output}`);
    const match = /http:\/\/127\.0\.0\.1:(\d+)\//.exec(child.output);
    return match && Number(match[1]);
  });
  return { child, port };
}

/** A port that was free a moment ago (haproxy cannot report an ephemeral port it bound). */
function freePort() {
  return new Promise((resolve, reject) => {
    const s = net.createServer();
    s.on('error', reject);
    s.listen(0, '127.0.0.1', () => {
      const { port } = s.address();
      s.close(() => resolve(port));
    });
  });
}

/** fetch with a 10 s timeout; resolves {status, json} (json null when the body is not JSON). */
async function request(url, init = {}) {
  const res = await fetch(url, { ...init, signal: AbortSignal.timeout(10000) });
  const text = await res.text();
  let json = null;
  try { json = JSON.parse(text); } catch { /* not JSON */ }
  return { status: res.status, json, text };
}

/** Opens ws://.../ws?world=id; resolves once it has had a text (scene) and a binary frame. */
function openViewer(proxyPort, id) {
  return new Promise((resolve, reject) => {
    const ws = new WebSocket(`ws://127.0.0.1:${proxyPort}/ws?world=${id}`);
    ws.binaryType = 'arraybuffer';
    const got = { text: 0, binary: 0 };
    const timer = setTimeout(() => reject(new Error(`/ws?world=${id}: no scene and frame in 10 s`)), 10000);
    ws.onmessage = (m) => {
      if (typeof m.data === 'string') got.text++; else got.binary++;
      if (got.text && got.binary) {
        clearTimeout(timer);
        resolve(ws);
      }
    };
    ws.onerror = () => { clearTimeout(timer); reject(new Error(`/ws?world=${id}: socket error`)); };
    ws.onclose = (e) => { clearTimeout(timer); reject(new Error(`/ws?world=${id}: closed (${e.code})`)); };
  });
}

/** GET /api/worlds on a backend directly: Map id -> entry. */
async function worldsOn(port) {
  const r = await request(`http://127.0.0.1:${port}/api/worlds`);
  assert.equal(r.status, 200, `GET /api/worlds on :${port}: ${r.text}`);
  return new Map(r.json.worlds.map((w) => [w.id, w]));
}

const ids = Array.from({ length: kWorlds }, (_, i) => `w-${i}`);

/** One stage of the test: runs `body` and logs its name and time (a failure ends the test). */
async function step(name, body) {
  const t0 = Date.now();
  await body();
  console.log(`ok   ${name} (${Date.now() - t0} ms)`);
}

/** Runs `body`; on failure prints the end of every child's output, then fails. */
async function showingOutput(body) {
  try {
    await body();
  } catch (e) {
    for (const c of children) console.log(`--- output of ${c.name}:\n${c.output.slice(-3000)}`);
    throw e;
  }
}

test('worlds behind HAProxy: placement by world id, 503 only for a stopped server', () => showingOutput(async () => {
  const backends = await Promise.all(Array.from({ length: kBackends }, (_, i) => startServer(i)));
  const proxyPort = await freePort();
  const backendFile = path.join(tmp, 'backend.cfg');
  fs.writeFileSync(backendFile, ['backend tumble',
    ...backends.map((b, i) => `  server s${i} 127.0.0.1:${b.port}`), ''].join('\n'));
  const proxy = spawnChild('haproxy', [kHaproxy, '-db', '-f', kConfig, '-f', backendFile],
    { TUMBLE_PROXY_BIND: `127.0.0.1:${proxyPort}` });
  const base = `http://127.0.0.1:${proxyPort}`;
  await until('haproxy to answer /haproxy-health', async () => {
    if (proxy.exitCode !== null) throw new Error(`haproxy exited ${proxy.exitCode}: ${proxy.output}`);
    return (await request(`${base}/haproxy-health`)).status === 200;
  });

  // Which backend (index) holds each world, from the backends themselves.
  const holder = new Map();
  await step('30 worlds created through the proxy land on all three backends', async () => {
    const puts = await Promise.all(ids.map((id) => request(`${base}/api/worlds/${id}`, {
      method: 'PUT', headers: { 'Content-Type': 'application/json' }, body: JSON.stringify({ scene: 'seed' }),
    })));
    puts.forEach((r, i) => assert.equal(r.status, 201, `PUT /api/worlds/${ids[i]}: ${r.text}`));
    const lists = await Promise.all(backends.map((b) => worldsOn(b.port)));
    for (const id of ids) {
      const on = lists.flatMap((list, i) => (list.has(id) ? [i] : []));
      assert.equal(on.length, 1, `${id} is listed on backends [${on}], expected exactly one`);
      holder.set(id, on[0]);
    }
    const counts = lists.map((_, i) => ids.filter((id) => holder.get(id) === i).length);
    console.log(`worlds per backend: ${counts.join(', ')}`);
    counts.forEach((n, i) => assert.ok(n > 0, `backend ${i} holds no world (spread ${counts})`));
  });

  await step('each world\'s REST and /ws reach the backend that holds it', async () => {
    const states = await Promise.all(ids.map((id) => request(`${base}/api/worlds/${id}/state`)));
    states.forEach((r, i) => {
      assert.equal(r.status, 200, `GET /api/worlds/${ids[i]}/state: ${r.text}`);
      assert.equal(typeof r.json.time, 'number', `state of ${ids[i]} has no time`);
    });
    const sockets = await Promise.all(ids.map((id) => openViewer(proxyPort, id)));
    try {
      const lists = await Promise.all(backends.map((b) => worldsOn(b.port)));
      for (const id of ids) {
        const entry = lists[holder.get(id)].get(id);
        assert.ok(entry && entry.viewers >= 1, `${id}: viewers on its backend ${JSON.stringify(entry)}`);
        lists.forEach((list, i) => assert.ok(i === holder.get(id) || !list.has(id), `${id} also on ${i}`));
      }
      const viewers = lists.reduce((sum, list) => sum + [...list.values()].reduce((s, w) => s + w.viewers, 0), 0);
      assert.equal(viewers, kWorlds, 'every socket counted once, on the world it asked for');
    } finally {
      for (const ws of sockets) ws.close();
    }
  });

  await step('a stopped backend: only its worlds answer 503, the others keep running', async () => {
    const victim = 1;
    const dead = ids.filter((id) => holder.get(id) === victim);
    const alive = ids.filter((id) => holder.get(id) !== victim);
    const timeOf = async (id) => (await request(`${base}/api/worlds/${id}/state`)).json.time;
    const before = new Map(await Promise.all(alive.map(async (id) => [id, await timeOf(id)])));
    backends[victim].child.kill('SIGTERM');
    const code = await until('the stopped backend to exit', () => {
      const c = backends[victim].child;
      return c.exitCode !== null || c.signalCode !== null ? String(c.exitCode ?? c.signalCode) : null;
    }, 5000, 50);
    assert.equal(code, '0', 'tumble-server exits 0 on SIGTERM');

    const answers = await Promise.all(ids.map((id) => request(`${base}/api/worlds/${id}/state`)));
    answers.forEach((r, i) => {
      const want = dead.includes(ids[i]) ? 503 : 200;
      assert.equal(r.status, want, `GET /api/worlds/${ids[i]}/state (backend ${holder.get(ids[i])})`);
    });
    const wsAnswer = await request(`${base}/ws?world=${dead[0]}`);
    assert.equal(wsAnswer.status, 503, `/ws?world=${dead[0]} of the stopped backend`);
    for (const id of alive) {
      const now = await timeOf(id);
      assert.ok(now > before.get(id), `${id}: sim time ${before.get(id)} -> ${now} did not advance`);
    }
  });
}));

// SIGTERM to whatever still runs, and up to 2 s for it to exit (the exit handler kills the rest).
after(async () => {
  const running = children.filter((c) => c.exitCode === null && c.signalCode === null);
  await Promise.race([sleep(2000), Promise.all(running.map((c) => new Promise((resolve) => {
    c.once('exit', resolve);
    c.kill('SIGTERM');
  })))]);
});
