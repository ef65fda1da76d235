// Browser test of the viewer on a server with several worlds (issue 14): two pages on two
// worlds in headless Chromium (Debian's, driven by playwright-core). A box kicked in world A
// moves in A's state and on A's page; world B's state and B's page stay exactly as they were.
// A page without B's token may watch B but not steer it, and says so. Then the world menu:
// join a listed world, make a new private world, and an unknown world offers the default.
//
//   node --test tests/e2e/worlds.test.mjs
//
// Env: TUMBLE_SERVER  path of tumble-server (default build/release/server/tumble-server)
//      TUMBLE_E2E_SHOTS  directory to keep the screenshots in (default: a temp dir, removed)
import { test } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { pathToFileURL } from 'node:url';
import {
  kChromium, kChromiumArgs, kPlaywright, kRepo, kServer, kViewport, sleep, startServer, stopServer, until,
} from './harness.mjs';
import { decodePng } from './png.mjs';

/** What the HUD says on a 401 (web/src/controls.js, kViewOnlyWorld). */
const kViewOnly = 'view only: this world belongs to another viewer; open its steer link to control it';
/** Hides the overlays, so that a screenshot shows the 3D view only (toasts and HUD figures change). */
const kOverlaysHidden = '.card, #panel, #hint, #toasts, #banner { visibility: hidden !important; }';

/** A REST call: {status, body}. `token` goes as a bearer token. */
async function call(base, method, route, { body, token } = {}) {
  const headers = {};
  if (token) headers.Authorization = `Bearer ${token}`;
  if (body !== undefined) headers['Content-Type'] = 'application/json';
  const response = await fetch(`${base}api/${route}`, { method, headers, body: body === undefined ? undefined : JSON.stringify(body) });
  let json = null;
  try {
    json = await response.json();
  } catch {
    json = null;
  }
  return { status: response.status, body: json };
}

async function getJson(base, route) {
  const { status, body } = await call(base, 'GET', route);
  assert.equal(status, 200, `GET /api/${route}`);
  return body;
}

/** Pixels that differ by more than `tolerance` in any channel between two PNG screenshots. */
function differingPixels(pngA, pngB, tolerance = 8) {
  const a = decodePng(pngA), b = decodePng(pngB);
  assert.equal(a.width, b.width);
  assert.equal(a.height, b.height);
  let count = 0;
  for (let i = 0; i < a.rgba.length; i += 4) {
    if (Math.abs(a.rgba[i] - b.rgba[i]) > tolerance || Math.abs(a.rgba[i + 1] - b.rgba[i + 1]) > tolerance ||
        Math.abs(a.rgba[i + 2] - b.rgba[i + 2]) > tolerance) count++;
  }
  return count;
}

/** The poses of a state's bodies (what must not change in the untouched world). */
const poses = (state) => state.bodies.map((b) => ({ position: b.position, orientation: b.orientation,
  velocity: b.velocity, angular_velocity: b.angular_velocity }));

const hudText = (page) => page.evaluate(() => document.getElementById('hud').textContent);

test('two worlds: a kick in one leaves the other still; a page without the token only watches; the world menu',
  { timeout: 180000 }, async (t) => {
    if (!fs.existsSync(kServer)) {
      t.skip(`no server binary at ${kServer} (build it, or set TUMBLE_SERVER)`);
      return;
    }
    assert.ok(fs.existsSync(kPlaywright), `playwright-core missing: run "npm ci" in ${path.join(kRepo, 'web')}`);
    assert.ok(fs.existsSync(kChromium), `no browser at ${kChromium} (apt-get install chromium)`);
    const { chromium } = await import(pathToFileURL(kPlaywright).href);

    const started = Date.now();
    const userData = fs.mkdtempSync(path.join(os.tmpdir(), 'tumble-e2e-chromium-'));
    const shots = process.env.TUMBLE_E2E_SHOTS || fs.mkdtempSync(path.join(os.tmpdir(), 'tumble-e2e-shots-'));
    fs.mkdirSync(shots, { recursive: true });
    const server = await startServer(0, 'seed');
    const base = `http://127.0.0.1:${server.port}/`;
    let context;
    t.after(async () => {
      await context?.close().catch(() => {});
      await stopServer(server.child);
      fs.rmSync(userData, { recursive: true, force: true });
      if (!process.env.TUMBLE_E2E_SHOTS) fs.rmSync(shots, { recursive: true, force: true });
    });

    // Two worlds of the seed scene (one box that bounces for ever on an elastic floor), both
    // paused: nothing in either moves until the test moves it.
    const worlds = {};
    for (const id of ['world-a', 'world-b']) {
      const created = await call(base, 'PUT', `worlds/${id}`, { body: { scene: 'seed' } });
      assert.equal(created.status, 201, `PUT /api/worlds/${id}: ${JSON.stringify(created.body)}`);
      assert.match(created.body.token, /^[0-9a-f]{32}$/);
      worlds[id] = created.body.token;
      assert.equal((await call(base, 'POST', `worlds/${id}/pause`)).status, 401, 'a POST without the token');
      assert.equal((await call(base, 'POST', `worlds/${id}/pause`, { token: created.body.token })).status, 200);
    }

    context = await chromium.launchPersistentContext(userData, {
      executablePath: kChromium, headless: true, args: kChromiumArgs, viewport: kViewport,
    });
    const pageErrors = [];
    const open = async (url) => {
      const page = await context.newPage();
      page.setDefaultTimeout(20000);
      page.on('pageerror', (e) => pageErrors.push(e.message));
      await page.goto(url);
      await until(`${url} to connect and draw`,
        () => page.evaluate(() => window.tumble?.connected && window.tumble.framesDrawn >= 2), 30000);
      return page;
    };
    // A's page opens A's steer link (token in the fragment); B's page opens B's view link.
    const pageA = await open(`${base}?world=world-a#token=${worlds['world-a']}`);
    const pageB = await open(`${base}?world=world-b`);
    for (const page of [pageA, pageB]) await until('the page to show paused', () => page.evaluate(() => window.tumble.paused));

    /** A screenshot of the 3D view alone, after a newly drawn frame. */
    const view = async (page, name) => {
      const drawn = await page.evaluate(() => window.tumble.framesDrawn);
      await until('a newly drawn frame', () => page.evaluate((n) => window.tumble.framesDrawn > n, drawn));
      const style = await page.addStyleTag({ content: kOverlaysHidden });
      await sleep(100);
      const png = await page.screenshot({ path: path.join(shots, `${name}.png`) });
      await style.evaluate((el) => el.remove());
      return png;
    };

    await t.test('the steer link\'s token is kept for its world and leaves the address bar', async () => {
      assert.ok(!pageA.url().includes('token'), `address after the steer link: ${pageA.url()}`);
      assert.ok(pageA.url().includes('world=world-a'));
      const a = await pageA.evaluate(() => ({ world: window.tumble.world, canSteer: window.tumble.canSteer,
        stored: localStorage.getItem('tumble.world-token.world-a') }));
      assert.deepEqual(a, { world: 'world-a', canSteer: true, stored: worlds['world-a'] });
      const b = await pageB.evaluate(() => ({ world: window.tumble.world, canSteer: window.tumble.canSteer }));
      assert.deepEqual(b, { world: 'world-b', canSteer: false });
      assert.match(await hudText(pageA), /world-a · steer/);
      assert.match(await hudText(pageB), /world-b/);
    });

    await t.test('a box kicked on A\'s page moves in A; B\'s state and B\'s pixels do not change', async () => {
      const stateB0 = await getJson(base, 'worlds/world-b/state');
      const a0 = await view(pageA, 'a-0'), b0 = await view(pageB, 'b-0');
      const before = (await getJson(base, 'worlds/world-a/state')).bodies[0];
      const target = await pageA.evaluate(() => window.tumble.bodyScreenPosition(0));
      assert.ok(target?.visible, 'A\'s box is in view');
      await pageA.mouse.click(target.x, target.y);
      await until('the click to kick A\'s box (a velocity change while paused)', async () => {
        const body = (await getJson(base, 'worlds/world-a/state')).bodies[0];
        return Math.hypot(...body.velocity.map((v, k) => v - before.velocity[k])) > 0.5;
      }, 10000);
      await pageA.getByRole('button', { name: 'Resume', exact: true }).click();
      await until('A to run again (Resume from the page, with its token)',
        async () => (await getJson(base, 'worlds/world-a/state')).paused === false);
      await until('A\'s box to move', async () => {
        const body = (await getJson(base, 'worlds/world-a/state')).bodies[0];
        return Math.hypot(...body.position.map((p, k) => p - before.position[k])) > 0.5;
      }, 10000);
      const a1 = await view(pageA, 'a-1'), b1 = await view(pageB, 'b-1');
      const changedA = differingPixels(a0, a1), changedB = differingPixels(b0, b1);
      t.diagnostic(`pixels changed: A's page ${changedA}, B's page ${changedB}`);
      assert.ok(changedA > 300, `A's page shows the box moved (${changedA} px changed)`);
      assert.equal(changedB, 0, 'B\'s page shows exactly what it showed');
      const stateB1 = await getJson(base, 'worlds/world-b/state');
      assert.deepEqual(poses(stateB1), poses(stateB0), 'B\'s bodies are where they were');
      assert.equal(stateB1.step, stateB0.step);
      assert.equal(stateB1.time, stateB0.time);
      assert.equal(stateB1.paused, true);
    });

    await t.test('the page without B\'s token cannot steer B and its HUD says so', async () => {
      const stateB0 = await getJson(base, 'worlds/world-b/state');
      const target = await pageB.evaluate(() => window.tumble.bodyScreenPosition(0));
      await pageB.mouse.click(target.x, target.y);
      await until('the HUD to say view only', async () => (await hudText(pageB)).includes(kViewOnly));
      assert.equal(await pageB.evaluate(() => window.tumble.notice), kViewOnly);
      await pageB.getByRole('button', { name: 'Resume', exact: true }).click();
      await sleep(500);
      const stateB1 = await getJson(base, 'worlds/world-b/state');
      assert.deepEqual(poses(stateB1), poses(stateB0), 'the refused kick changed nothing');
      assert.equal(stateB1.paused, true, 'the refused Resume changed nothing');
      assert.ok(!(await hudText(pageA)).includes('view only'), 'A\'s page is not view only');
    });

    await t.test('the world menu lists the worlds and joins one', async () => {
      await pageB.locator('#panel .lil-title', { hasText: 'World' }).click(); // its name has lil-gui's arrow too
      const menu = pageB.getByRole('combobox', { name: 'world', exact: true });
      // lil-gui's options carry labels only (`world-a · seed · 1 viewer · paused`).
      const labels = await until('the menu to list both worlds', async () => {
        const all = await menu.evaluate((el) => [...el.options].map((o) => o.textContent));
        const ids = all.map((label) => label.split(' · ')[0]);
        return ids.includes('world-a') && ids.includes('world-b') && ids.includes('default') ? all : null;
      });
      t.diagnostic(`world menu: ${labels.join(' | ')}`);
      await menu.selectOption({ label: labels.find((label) => label.startsWith('world-a ')) });
      await until('the page to open world-a', () => pageB.evaluate(() => window.tumble?.world === 'world-a' &&
        window.tumble.connected && window.tumble.framesDrawn >= 2), 30000);
      assert.ok(pageB.url().includes('world=world-a'));
      // The same browser holds A's token (stored by A's page): it may steer A here too.
      assert.equal(await pageB.evaluate(() => window.tumble.canSteer), true);
    });

    await t.test('New private world creates a world with its own token and opens it', async () => {
      const { worlds: listed0 } = await getJson(base, 'worlds');
      await pageB.locator('#panel .lil-title', { hasText: 'World' }).click(); // its name has lil-gui's arrow too
      await pageB.getByRole('button', { name: 'New private world', exact: true }).click();
      const id = await until('a new world to open', () => pageB.evaluate(() => window.tumble?.connected &&
        !['world-a', 'world-b'].includes(window.tumble.world) && window.tumble.world), 30000);
      assert.match(id, /^[a-z]+-[a-z]+-\d{4}$/, 'a readable random id');
      assert.ok(!pageB.url().includes('token'), `address: ${pageB.url()}`);
      const { worlds: listed1 } = await getJson(base, 'worlds');
      assert.equal(listed1.length, listed0.length + 1);
      assert.equal(listed1.find((w) => w.id === id)?.scene, 'seed');
      const token = await pageB.evaluate((w) => localStorage.getItem(`tumble.world-token.${w}`), id);
      assert.match(token ?? '', /^[0-9a-f]{32}$/);
      await until('the page to show running', () => pageB.evaluate(() => !window.tumble.paused));
      await pageB.getByRole('button', { name: 'Pause', exact: true }).click();
      await until('the new world to pause (the page steers it)',
        async () => (await getJson(base, `worlds/${id}/state`)).paused === true);
    });

    await t.test('an unknown world is said so, with the default world offered', async () => {
      await pageB.goto(`${base}?world=no-such-world`);
      await until('the page to say the world is missing', () => pageB.evaluate(() => window.tumble?.worldMissing));
      assert.match(await pageB.evaluate(() => document.getElementById('no-world').textContent), /no-such-world/);
      await pageB.getByRole('link', { name: 'Open the default world' }).click();
      await until('the default world to open', () => pageB.evaluate(() => window.tumble?.world === 'default' &&
        window.tumble.connected && window.tumble.framesDrawn >= 2), 30000);
      assert.equal(new URL(pageB.url()).searchParams.get('world'), null);
      assert.equal(await pageB.evaluate(() => window.tumble.scene), 'seed');
    });

    assert.deepEqual(pageErrors, [], 'no uncaught errors in the pages');
    t.diagnostic(`worlds browser test took ${((Date.now() - started) / 1000).toFixed(1)} s` +
      (process.env.TUMBLE_E2E_SHOTS ? `; screenshots in ${shots}` : ''));
  });
