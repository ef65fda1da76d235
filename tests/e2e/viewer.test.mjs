// Browser test of the viewer against the real server: headless Chromium (Debian's, driven by
// playwright-core) opens the page and the test looks at what a person would see.
//
//   node --test tests/e2e/viewer.test.mjs
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

const kBoxColor = [0xd9, 0x82, 0x2b]; // the seed scene's box, #d9822b

/** Counts the pixels whose colour is the box's orange under some lighting; returns their centroid. */
function findBoxPixels(png) {
  const { width, height, rgba } = decodePng(png);
  const [br, bg, bb] = kBoxColor;
  let count = 0, sx = 0, sy = 0;
  for (let y = 0; y < height; y++) {
    for (let x = 0; x < width; x++) {
      const i = (y * width + x) * 4;
      const r = rgba[i], g = rgba[i + 1], b = rgba[i + 2];
      if (r < 60) continue;
      // Same chromaticity as #d9822b within a tolerance: lighting scales all channels alike.
      const k = r / br;
      if (Math.abs(g - bg * k) < 22 && Math.abs(b - bb * k) < 22 && r - b > 50) {
        count++;
        sx += x;
        sy += y;
      }
    }
  }
  return { count, share: count / (width * height), x: count ? sx / count : NaN, y: count ? sy / count : NaN };
}

/** World corners (m) of a box at `position` with unit quaternion [w, x, y, z] and edge lengths `size`. */
function boxCorners(position, [w, x, y, z], size) {
  const rotate = ([a, b, c]) => {
    // v + 2 q×(q×v + w v), with q the quaternion's vector part.
    const t = [2 * (y * c - z * b), 2 * (z * a - x * c), 2 * (x * b - y * a)];
    return [a + w * t[0] + (y * t[2] - z * t[1]), b + w * t[1] + (z * t[0] - x * t[2]),
            c + w * t[2] + (x * t[1] - y * t[0])];
  };
  const corners = [];
  for (const sx of [-0.5, 0.5]) for (const sy of [-0.5, 0.5]) for (const sz of [-0.5, 0.5]) {
    const r = rotate([sx * size[0], sy * size[1], sz * size[2]]);
    corners.push([position[0] + r[0], position[1] + r[1], position[2] + r[2]]);
  }
  return corners;
}

async function getJson(base, route) {
  const response = await fetch(`${base}api/${route}`);
  assert.equal(response.status, 200, `GET /api/${route}`);
  return response.json();
}

const hudTime = async (page) => parseFloat(await page.evaluate(() => document.getElementById('hud-time').textContent));
const hudText = (page) => page.evaluate(() => document.getElementById('hud').innerText);

test('viewer against the real server: pixels, HUD, pause, step, click-kick, reconnect, scene menu, phone tap',
  { timeout: 88000 }, async (t) => {
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
    let server = await startServer(0);
    const base = `http://127.0.0.1:${server.port}/`;
    let context;
    t.after(async () => {
      await context?.close().catch(() => {});
      await stopServer(server.child);
      fs.rmSync(userData, { recursive: true, force: true });
      if (!process.env.TUMBLE_E2E_SHOTS) fs.rmSync(shots, { recursive: true, force: true });
    });

    context = await chromium.launchPersistentContext(userData, {
      executablePath: kChromium, headless: true, args: kChromiumArgs, viewport: kViewport, hasTouch: true,
    });
    const page = context.pages()[0] ?? await context.newPage();
    page.setDefaultTimeout(15000);
    const pageErrors = [];
    page.on('pageerror', (e) => pageErrors.push(e.message));
    const snap = async (name) => {
      // Wait for a newly drawn frame, so the picture shows the current state.
      const drawn = await page.evaluate(() => window.tumble.framesDrawn);
      await until('a newly drawn frame', () => page.evaluate((n) => window.tumble.framesDrawn > n, drawn));
      const png = await page.screenshot({ path: path.join(shots, `${name}.png`) });
      return findBoxPixels(png);
    };

    await page.goto(base);
    await until('the stream to connect and frames to be drawn',
      () => page.evaluate(() => window.tumble?.connected && window.tumble.framesDrawn >= 2), 30000);
    assert.equal(await page.evaluate(() => window.tumble.bodies), 1, 'the seed scene has one body');
    const webgl = await page.evaluate(() => !!document.querySelector('#stage canvas')?.getContext('webgl2'));
    assert.ok(webgl, 'the page draws with WebGL 2');

    await t.test('the box is drawn in its colour', async () => {
      const seen = await snap('1-running');
      assert.ok(seen.count > 400, `expected orange box pixels, found ${seen.count}`);
      assert.ok(seen.share < 0.5, `orange covers ${(100 * seen.share).toFixed(0)}% of the page: not a box`);
    });

    await t.test('the HUD sim time advances', async () => {
      const t0 = await hudTime(page);
      await until('the HUD sim time to advance by 0.3 s', async () => (await hudTime(page)) > t0 + 0.3);
      const text = await hudText(page);
      assert.match(text, /live/, 'HUD shows the connection as live');
      assert.match(text, /fps/);
      assert.match(text, /dropped frames/);
    });

    let paused;
    await t.test('the Pause button stops the simulation', async () => {
      // The scene's caption lies over the bottom left of the scene for its first 12 s: a user
      // clicks it away to look at the box (CI failed so: the box paused under it, 5 px seen).
      // Checked and clicked in one go in the page: the caption's own timer may hide it between
      // a check from here and a click, which would then wait for it to show again.
      await page.evaluate(() => {
        const card = document.getElementById('description');
        if (card && !card.hidden) card.click();
      });
      await until('the caption to go', async () => !(await page.locator('#description').isVisible()));
      await page.getByRole('button', { name: 'Pause', exact: true }).click();
      await until('the server to report paused', async () => (await getJson(base, 'state')).paused === true);
      await until('the HUD to show paused', async () => (await hudText(page)).includes('paused'));
      await until('the button to read Resume', () => page.getByRole('button', { name: 'Resume', exact: true }).isVisible());
      const h0 = await hudTime(page);
      const s0 = (await getJson(base, 'state')).time;
      await sleep(1000);
      assert.equal(await hudTime(page), h0, 'HUD sim time is frozen while paused');
      assert.equal((await getJson(base, 'state')).time, s0, 'server sim time is frozen while paused');
      paused = await snap('2-paused');
      assert.ok(paused.count > 400, `box visible while paused (${paused.count} px)`);
      // The orange pixels are where the page's camera puts the body: the centre of any part of
      // the box's picture lies inside the screen rectangle that holds its 8 projected corners
      // (a few px more for anti-aliasing). Shadowed faces do not count as orange, so the lit
      // ones' centre may sit anywhere in it: a clean-clone CI run saw a small box (1,511 px)
      // whose lit faces centred 43 px off its centre's projection, inside its picture.
      const body = (await getJson(base, 'state')).bodies[0];
      const size = (await getJson(base, 'scene')).bodies?.[0]?.size ?? [1, 1, 1];
      const corners = await page.evaluate((points) => points.map((p) => window.tumble.worldToScreen(p)),
        boxCorners(body.position, body.orientation, size));
      const xs = corners.map((c) => c.x), ys = corners.map((c) => c.y), margin = 4;
      const [left, right, top, bottom] = [Math.min(...xs), Math.max(...xs), Math.min(...ys), Math.max(...ys)];
      const inside = paused.x > left - margin && paused.x < right + margin &&
                     paused.y > top - margin && paused.y < bottom + margin;
      assert.ok(inside, `orange pixels (${paused.count}) centred at (${paused.x.toFixed(0)}, ` +
                `${paused.y.toFixed(0)}) px, outside the box's projected corners x ` +
                `${left.toFixed(0)}..${right.toFixed(0)}, y ${top.toFixed(0)}..${bottom.toFixed(0)}`);
    });

    await t.test('Step advances a paused simulation by one step; the integrator menu switches it', async () => {
      const s0 = await getJson(base, 'state');
      await page.getByRole('button', { name: 'Step', exact: true }).click();
      const s1 = await until('one step', async () => {
        const s = await getJson(base, 'state');
        return s.step > s0.step ? s : null;
      });
      assert.equal(s1.step, s0.step + 1);
      assert.ok(s1.paused);
      await until('the HUD to show the stepped time', async () => Math.abs((await hudTime(page)) - s1.time) < 2e-3);
      await page.getByRole('combobox', { name: 'integrator' }).selectOption('rk4');
      await until('the server to switch to rk4', async () => (await getJson(base, 'state')).integrator === 'rk4');
    });

    await t.test('clicking the box kicks it', async () => {
      const scene = await getJson(base, 'scene');
      const mass = scene.bodies[0].mass ?? 1;
      const before = (await getJson(base, 'state')).bodies[0];
      // The scene's caption, which once covered the box here, was clicked away before the pause.
      const covering = () => page.evaluate(([x, y]) => {
        const el = document.elementFromPoint(x, y);
        return el?.tagName === 'CANVAS' ? null : `${el?.tagName}#${el?.id}`;
      }, [paused.x, paused.y]);
      assert.equal(await covering(), null, 'nothing covers the box where it is clicked');
      const kickBefore = await page.evaluate(() => JSON.stringify(window.tumble.lastKick));
      await page.mouse.click(paused.x, paused.y);
      await until('the page to send a kick for the click', () => page.evaluate(
        (old) => JSON.stringify(window.tumble.lastKick) !== old, kickBefore), 5000);
      const after = await until('the impulse to change the body velocity', async () => {
        const body = (await getJson(base, 'state')).bodies[0];
        const dv = Math.hypot(...body.velocity.map((v, k) => v - before.velocity[k]));
        return dv > 0.5 ? body : null;
      }, 10000);
      const dv = after.velocity.map((v, k) => v - before.velocity[k]);
      const speed = Math.hypot(...dv);
      // The panel's default impulse is 3 N·s along the view ray: Δv = 3 / m.
      assert.ok(Math.abs(speed - 3 / mass) < 0.3 * (3 / mass), `|Δv| = ${speed.toFixed(3)} m/s, expected ${3 / mass}`);
      assert.ok(dv[1] < 0, 'the view ray points down at the box, so the kick does too');
      assert.ok(Math.hypot(dv[0], dv[2]) > 0.3, 'the kick has a horizontal part');

      await page.getByRole('button', { name: 'Resume', exact: true }).click();
      await until('the box to drift sideways after the kick', async () => {
        const body = (await getJson(base, 'state')).bodies[0];
        return Math.hypot(body.position[0] - before.position[0], body.position[2] - before.position[2]) > 0.2;
      }, 10000);
    });

    await t.test('the page reconnects after a server restart', async () => {
      const port = server.port;
      await stopServer(server.child);
      await until('the page to notice the lost connection', () => page.evaluate(() => !window.tumble.connected), 10000);
      await until('the HUD to say reconnecting', async () => (await hudText(page)).includes('reconnecting'));
      server = await startServer(port);
      await until('the page to reconnect', () => page.evaluate(() => window.tumble.connected && window.tumble.connects >= 2), 20000);
      const frames = await page.evaluate(() => window.tumble.frames);
      const t0 = await until('frames of the new server', async () => {
        const shown = await page.evaluate(() => window.tumble.simTime);
        const state = await getJson(base, 'state');
        const more = await page.evaluate((n) => window.tumble.frames > n + 5, frames);
        return more && Math.abs(shown - state.time) < 1 ? shown + 1e-9 : null;
      });
      await until('the HUD sim time to advance again', async () => (await hudTime(page)) > t0 + 0.2);
      // The box is drawn again: on a loaded machine one picture can catch it where the panels
      // hide part of it, so a few newly drawn frames are looked at before giving up.
      let seen = { count: 0 };
      await until('the box drawn again after the restart', async () => {
        seen = await snap('3-reconnected');
        return seen.count > 400;
      }, 10000, 250).catch(() => {});
      assert.ok(seen.count > 400, `box drawn again after the restart (${seen.count} px)`);
      // Resync: the new server runs the scene's own integrator again, and the menu follows it.
      const integrator = (await getJson(base, 'state')).integrator;
      await until(`the integrator menu to show ${integrator}`,
        async () => (await page.getByRole('combobox', { name: 'integrator' }).inputValue()) === integrator);
    });

    await t.test('the scene menu resets to another scene and the page rebuilds it', async () => {
      const { scenes } = await getJson(base, 'scenes');
      const other = scenes.find((name) => name !== 'seed');
      assert.ok(other, `a second bundled scene (have ${scenes})`);
      const count = (await getJson(base, 'scene')).bodies?.length;
      await page.getByRole('combobox', { name: 'scene' }).selectOption(other);
      await until(`the server to run ${other}`, async () => (await getJson(base, 'scene')).name === other);
      const expected = (await getJson(base, 'scene')).bodies.length;
      await until(`the page to show ${other} with ${expected} bodies`,
        () => page.evaluate(([name, n]) => window.tumble.scene === name && window.tumble.bodies === n, [other, expected]));
      assert.ok(count >= 1);
    });

    await t.test('on a phone-sized screen the overlays fit and a tap kicks a box', async () => {
      await page.setViewportSize({ width: 390, height: 760 });
      assert.ok((await fetch(`${base}api/pause`, { method: 'POST' })).ok);
      await until('the page to show paused', () => page.evaluate(() => window.tumble.paused));
      const boxes = await page.evaluate(() => ['hud', 'plot-card', 'panel'].map((id) => {
        const r = document.getElementById(id).getBoundingClientRect();
        return { id, left: r.left, right: r.right };
      }));
      for (const { id, left, right } of boxes) {
        assert.ok(left >= 0 && right <= 390.5, `#${id} fits the 390 px width (${left}..${right})`);
      }
      const index = 0;
      // The target is taken from a frame drawn at the phone size (canvas resized), and must be
      // the canvas itself at that point: on a phone the panel folds, so it cannot cover it.
      await until('the canvas at the phone size', () => page.evaluate(() => {
        const c = document.querySelector('#stage canvas');
        return c.clientWidth === innerWidth && c.clientHeight === innerHeight;
      }));
      const drawn = await page.evaluate(() => window.tumble.framesDrawn);
      await until('a frame drawn at the phone size', () => page.evaluate((n) => window.tumble.framesDrawn > n, drawn));
      const target = await page.evaluate((i) => window.tumble.bodyScreenPosition(i), index);
      assert.ok(target?.visible && target.x > 0 && target.x < 390 && target.y > 0 && target.y < 760,
        `body ${index} is on the phone's screen (${JSON.stringify(target)})`);
      const atTarget = await page.evaluate(([x, y]) => {
        const el = document.elementFromPoint(x, y);
        return el?.closest('#panel') ? 'the panel' : el?.tagName === 'CANVAS' ? 'canvas' : `${el?.tagName}#${el?.id}`;
      }, [target.x, target.y]);
      assert.equal(atTarget, 'canvas', 'nothing covers the body where it is tapped');
      const before = (await getJson(base, 'state')).bodies[index];
      const kickBefore = await page.evaluate(() => JSON.stringify(window.tumble.lastKick));
      await page.touchscreen.tap(target.x, target.y);
      const kick = await until('the page to send a kick for the tap', () => page.evaluate(
        (old) => JSON.stringify(window.tumble.lastKick) !== old && window.tumble.lastKick, kickBefore), 5000);
      assert.equal(kick.body, index, 'the tap kicks the body tapped');
      await until('the tap to change the body velocity', async () => {
        const body = (await getJson(base, 'state')).bodies[index];
        return Math.hypot(...body.velocity.map((v, k) => v - before.velocity[k])) > 0.5;
      }, 10000);
      await snap('5-phone');
    });

    assert.deepEqual(pageErrors, [], 'no uncaught errors in the page');
    const seconds = (Date.now() - started) / 1000;
    t.diagnostic(`browser test took ${seconds.toFixed(1)} s` +
      (process.env.TUMBLE_E2E_SHOTS ? `; screenshots in ${shots}` : ''));
  });

/** The median of a list of numbers. */
function median(values) {
  const sorted = [...values].sort((x, y) => x - y);
  const mid = sorted.length >> 1;
  return sorted.length % 2 ? sorted[mid] : (sorted[mid - 1] + sorted[mid]) / 2;
}

/** A metric of GET /metrics. */
async function metric(base, name) {
  const text = await (await fetch(`${base}metrics`)).text();
  const match = new RegExp(`^${name} (\\S+)$`, 'm').exec(text);
  return match ? Number(match[1]) : NaN;
}

/** Bytes on the wire of every HTTP response the page loads (WebSocket excluded), via CDP. */
async function countPageBytes(page, load) {
  const cdp = await page.context().newCDPSession(page);
  await cdp.send('Network.enable');
  const http = new Set();
  let bytes = 0, requests = 0, notModified = 0;
  cdp.on('Network.responseReceived', (e) => {
    if (e.type === 'WebSocket' || !e.response.url.startsWith('http')) return;
    http.add(e.requestId);
    if (e.response.status === 304) notModified++;
  });
  cdp.on('Network.loadingFinished', (e) => {
    if (!http.has(e.requestId)) return;
    bytes += e.encodedDataLength;
    requests++;
  });
  await load();
  await sleep(1000);
  await cdp.detach();
  return { bytes, requests, notModified };
}

test('pile: page weight, a slow page keeps up, bytes/s near zero asleep, a kicked box moves',
  { timeout: 150000 }, async (t) => {
    if (!fs.existsSync(kServer) || !fs.existsSync(kPlaywright) || !fs.existsSync(kChromium)) {
      t.skip('server, playwright-core or chromium missing (see the first test)');
      return;
    }
    const { chromium } = await import(pathToFileURL(kPlaywright).href);
    const userData = fs.mkdtempSync(path.join(os.tmpdir(), 'tumble-e2e-chromium-'));
    const server = await startServer(0, 'pile');
    const base = `http://127.0.0.1:${server.port}/`;
    let context;
    t.after(async () => {
      await context?.close().catch(() => {});
      await stopServer(server.child);
      fs.rmSync(userData, { recursive: true, force: true });
    });
    context = await chromium.launchPersistentContext(userData, {
      executablePath: kChromium, headless: true, args: kChromiumArgs, viewport: kViewport,
    });
    const page = context.pages()[0] ?? await context.newPage();
    page.setDefaultTimeout(20000);
    const pageErrors = [];
    page.on('pageerror', (e) => pageErrors.push(e.message));

    await t.test('a first visit is at most 1 MB on the wire, a repeat visit at most 10 KB (304s)', async () => {
      const first = await countPageBytes(page, () => page.goto(base));
      await until('frames drawn', () => page.evaluate(() => window.tumble?.framesDrawn >= 2), 30000);
      const repeat = await countPageBytes(page, () => page.goto(base));
      await until('frames drawn again', () => page.evaluate(() => window.tumble?.framesDrawn >= 2), 30000);
      t.diagnostic(`first visit ${first.bytes} B in ${first.requests} requests; repeat ${repeat.bytes} B, ` +
        `${repeat.notModified} of ${repeat.requests} answered 304`);
      assert.ok(first.bytes <= 1e6, `first visit ${first.bytes} B`);
      assert.ok(repeat.bytes <= 10e3, `repeat visit ${repeat.bytes} B`);
      assert.ok(repeat.notModified >= 5, 'the modules are revalidated, not downloaded again');
    });

    // The stream is received in a worker (web/src/stream_worker.js) that a busy main thread
    // does not block; the page draws only the newest state at each animation frame.
    await t.test('with 200 ms of work per animation frame the page stays within 0.5 s of the server', async () => {
      assert.ok((await fetch(`${base}api/reset`, { method: 'POST', body: '{"scene": "pile"}' })).ok);
      assert.ok(await page.evaluate(() => self.crossOriginIsolated), 'the page is cross-origin isolated');
      await page.evaluate(() => {
        window.slowPage = true;
        const busy = () => {
          const start = performance.now();
          while (performance.now() - start < 200) { /* a slow device */ }
          if (window.slowPage) requestAnimationFrame(busy);
        };
        requestAnimationFrame(busy);
      });
      try {
        await sleep(2000);
        // Steady state over 5 s: the server's sim time against the sim time on screen, and the
        // HUD's own figure, sampled 20 times; the median must hold the bound. The page answers
        // an evaluate only between its 200 ms busy spells, so the server's clock is read before
        // and after: the HUD's figure is for an instant between the two.
        const lags = [], hudLags = [], lagsAfter = [];
        for (let i = 0; i < 20; i++) {
          const before = await metric(base, 'tumble_sim_time_seconds');
          const [shown, hudLag] = await page.evaluate(() => [window.tumble.shownTime, window.tumble.lag]);
          const after = await metric(base, 'tumble_sim_time_seconds');
          lags.push(before - shown);
          lagsAfter.push(after - shown);
          hudLags.push(hudLag);
          await sleep(250);
        }
        const lag = median(lags), lagAfter = median(lagsAfter), hudLag = median(hudLags);
        t.diagnostic(`lag: median ${(lag * 1000).toFixed(0)} ms (${(lagAfter * 1000).toFixed(0)} ms read after), ` +
          `worst ${(Math.max(...lags) * 1000).toFixed(0)} ms; the HUD's median ${(hudLag * 1000).toFixed(0)} ms`);
        assert.ok(lag <= 0.5, `the slow page is ${lag.toFixed(2)} s behind (median of 20)`);
        // The HUD tells the lag it has: within 0.25 s of the lag measured against the server.
        assert.ok(hudLag >= lag - 0.25 && hudLag <= lagAfter + 0.25,
          `the HUD says ${hudLag.toFixed(2)} s, measured ${lag.toFixed(2)}–${lagAfter.toFixed(2)} s`);
        assert.match(await hudText(page), /lag/);
        const asked = Date.now();
        assert.ok((await fetch(`${base}api/reset`, { method: 'POST', body: '{"scene": "many"}' })).ok);
        await until('the slow page to draw the new scene', () => page.evaluate(
          () => window.tumble.scene === 'many' && window.tumble.shownTime < 1), 5000, 50);
        const switchMs = Date.now() - asked;
        t.diagnostic(`scene switch drawn after ${switchMs} ms`);
        // The server's own reset counts in this too (about 1 s for the pile on 2 busy cores).
        assert.ok(switchMs < 3000, `the scene switch took ${switchMs} ms to show`);
      } finally {
        await page.evaluate(() => { window.slowPage = false; }).catch(() => {});
        await fetch(`${base}api/reset`, { method: 'POST', body: '{"scene": "pile"}' });
      }
    });

    await t.test('once the pile sleeps the HUD shows bytes/s near zero; a kicked box is seen moving', async () => {
      await until('the page to show the pile', () => page.evaluate(() => window.tumble.scene === 'pile'));
      await until('every body of the pile to sleep', async () => (await metric(base, 'tumble_bodies_awake')) === 0, 90000, 500);
      await sleep(3500); // the HUD's rate window
      const asleep = await page.evaluate(() => window.tumble.bytesPerSecond);
      t.diagnostic(`asleep: the HUD shows ${asleep.toFixed(0)} bytes/s`);
      assert.ok(asleep < 2000, `bytes/s while everything sleeps: ${asleep}`);
      assert.match(await hudText(page), /received\s+\d+ B\/s/);
      const state = await getJson(base, 'state');
      let top = 0;
      state.bodies.forEach((b, i) => { if (b.position[1] > state.bodies[top].position[1]) top = i; });
      const before = await page.evaluate((i) => window.tumble.bodyScreenPosition(i), top);
      const mass = (await getJson(base, 'scene')).bodies[top].mass ?? 1;
      // 10 m/s up lifts the top box about 5 m (v²/2g) for about 2 s. The camera frames the
      // whole pile, so a metre is only a dozen pixels or so: the page must draw the box near the
      // top of its flight to pass. (Before the stream moved to a worker the page drew states
      // seconds old and few of them, and saw a 6 m/s kick move the box at most 8.8 px.)
      const kick = await fetch(`${base}api/impulse`, { method: 'POST',
        body: JSON.stringify({ body: top, impulse: [0, 10 * mass, 0] }) });
      assert.ok(kick.ok);
      let moved = 0;
      await until('the kicked box to move on screen', async () => {
        const now = await page.evaluate((i) => window.tumble.bodyScreenPosition(i), top);
        moved = Math.hypot(now.x - before.x, now.y - before.y);
        return moved > 30;
      }, 5000, 50).catch((e) => { throw new Error(`${e.message}; moved ${moved} px, body ${top}, before ${JSON.stringify(before)}`); });
      t.diagnostic(`the kicked box moved ${moved.toFixed(0)} px on screen`);
      await until('bytes to flow again', () => page.evaluate(() => window.tumble.bytesPerSecond > 200), 5000);
    });
    assert.deepEqual(pageErrors, [], 'no uncaught errors in the page');
  });
