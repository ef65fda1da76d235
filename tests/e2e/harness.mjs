// What the browser tests share: where the server, playwright-core and Chromium are, how to
// start and stop a tumble-server child on an ephemeral port, and polling with a deadline.
import assert from 'node:assert/strict';
import { spawn } from 'node:child_process';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

/** The repository root. */
export const kRepo = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '..', '..');
/** The server binary (TUMBLE_SERVER, or the release build's). */
export const kServer = process.env.TUMBLE_SERVER || path.join(kRepo, 'build/release/server/tumble-server');
/** playwright-core from web/node_modules (tools/setup.sh runs `npm ci` there). */
export const kPlaywright = path.join(kRepo, 'web/node_modules/playwright-core/index.mjs');
/** Debian's Chromium: never a downloaded build. */
export const kChromium = '/usr/bin/chromium';
/** Headless Chromium with SwiftShader's WebGL (docs: ENVIRONMENT). */
export const kChromiumArgs = ['--headless', '--no-sandbox', '--disable-gpu', '--disable-background-networking',
  '--disable-component-update', '--disable-sync', '--no-first-run', '--enable-unsafe-swiftshader'];
/** Small (SwiftShader pays per pixel), not phone-sized. */
export const kViewport = { width: 720, height: 540 };

/** Resolves after `ms` milliseconds. */
export const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));

/** Polls `probe` until it returns a truthy value; fails with `what` after `timeoutMs`. */
export async function until(what, probe, timeoutMs = 15000, everyMs = 150) {
  const end = Date.now() + timeoutMs;
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

/**
 * Starts tumble-server on `port` (0: ephemeral) with `scene`, serving web/, without a --token
 * from the environment; resolves with {child, port} once it prints its URL.
 */
export function startServer(port = 0, scene = 'seed') {
  const env = { ...process.env };
  delete env.TUMBLE_TOKEN;
  delete env.TUMBLE_PORT;
  const child = spawn(kServer, ['--port', String(port), '--scene', scene, '--web-root', path.join(kRepo, 'web')],
    { env, stdio: ['ignore', 'pipe', 'pipe'] });
  let output = '';
  return new Promise((resolve, reject) => {
    const timer = setTimeout(() => reject(new Error(`server printed no URL in 10 s:\n${output}`)), 10000);
    const onData = (chunk) => {
      output += chunk;
      const match = /Tumble viewer: http:\/\/[^:\s]+:(\d+)\//.exec(output);
      if (match) {
        clearTimeout(timer);
        resolve({ child, port: Number(match[1]) });
      }
    };
    child.stdout.on('data', onData);
    child.stderr.on('data', onData);
    child.on('exit', (code) => {
      clearTimeout(timer);
      reject(new Error(`server exited with ${code}:\n${output}`));
    });
  });
}

/** SIGTERM, then SIGKILL after 3 s; resolves once the child has exited. */
export async function stopServer(child) {
  if (child.exitCode !== null || child.signalCode !== null) return;
  const exited = new Promise((resolve) => child.once('exit', resolve));
  child.kill('SIGTERM');
  const timer = setTimeout(() => child.kill('SIGKILL'), 3000);
  await exited;
  clearTimeout(timer);
}
