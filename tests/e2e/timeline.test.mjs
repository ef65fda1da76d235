// Browser test of the viewer's timeline bar and contacts overlay (issue 15) against the real
// server in Debian's headless Chromium: drag the timeline back 3 s and the boxes are where they
// were (on screen and in /api/state), resume from there; the contacts overlay draws points where
// a box touches the floor; the Add box form adds one. The last two skip on a server without
// the contacts stream or POST …/bodies.
//
//   cd web && TUMBLE_SERVER=../build/release/server/tumble-server node --test ../tests/e2e/timeline.test.mjs
import { test } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { pathToFileURL } from 'node:url';
import {
  kChromium, kChromiumArgs, kPlaywright, kServer, kViewport, sleep, startServer, stopServer, until,
} from './harness.mjs';
import { decodePng } from './png.mjs';

/** Hue of an sRGB colour in degrees [0, 360), or -1 for a grey. */
function hueOf(r, g, b) {
  const max = Math.max(r, g, b), min = Math.min(r, g, b);
  if (max === min) return -1;
  const h = max === r ? (g - b) / (max - min) : max === g ? 2 + (b - r) / (max - min) : 4 + (r - g) / (max - min);
  return (h * 60 + 360) % 360;
}

/**
 * Centroid and count of the pixels of colour `rgb` (under any lighting) in a screenshot.
 * Why hue: a lit face is the base colour scaled and with some of the light's white added
 * (a face of the seed box turned to the sun reads (232, 146, 78) for base (217, 130, 43)), so
 * channels proportional to the base miss it at some orientations; its hue stays within a few
 * degrees. Greys, near-greys and dark pixels are left out.
 */
function findColour(png, [cr, cg, cb], box = null) {
  const { width, height, rgba } = decodePng(png);
  const base = hueOf(cr, cg, cb);
  let count = 0, sx = 0, sy = 0;
  for (let y = 0; y < height; y++) {
    for (let x = 0; x < width; x++) {
      if (box && (x < box.x0 || x > box.x1 || y < box.y0 || y > box.y1)) continue;
      const i = (y * width + x) * 4, r = rgba[i], g = rgba[i + 1], b = rgba[i + 2];
      const max = Math.max(r, g, b), min = Math.min(r, g, b);
      if (max < 60 || max - min < 0.4 * max) continue;
      const off = Math.abs(((hueOf(r, g, b) - base + 540) % 360) - 180);
      if (off < 8) { count++; sx += x; sy += y; }
    }
  }
  return { count, x: sx / count, y: sy / count };
}

const kSeedOrange = [0xd9, 0x82, 0x2b];
const kContactPink = [0xff, 0x3b, 0x6b];

test('timeline: drag back 3 s shows the past exactly, resume from there; contacts where a box touches the floor',
  { timeout: 200000 }, async (t) => {
    if (!fs.existsSync(kServer) || !fs.existsSync(kPlaywright) || !fs.existsSync(kChromium)) {
      t.skip(`server (${kServer}), playwright-core or chromium missing`);
      return;
    }
    const { chromium } = await import(pathToFileURL(kPlaywright).href);
    const userData = fs.mkdtempSync(path.join(os.tmpdir(), 'tumble-e2e-chromium-'));
    const server = await startServer(0, 'seed');
    const base = `http://127.0.0.1:${server.port}/`;
    let context;
    t.after(async () => {
      await context?.close().catch(() => {});
      await stopServer(server.child);
      fs.rmSync(userData, { recursive: true, force: true });
    });
    const get = async (route) => {
      const response = await fetch(`${base}api/${route}`);
      assert.equal(response.status, 200, `GET /api/${route}`);
      return response.json();
    };
    const post = (route, body) => fetch(`${base}api/${route}`, { method: 'POST', body: body && JSON.stringify(body) });
    if ((await fetch(`${base}api/history`)).status === 404) {
      t.skip('this server has no timeline (GET /api/history is 404)');
      return;
    }

    context = await chromium.launchPersistentContext(userData, {
      executablePath: kChromium, headless: true, args: kChromiumArgs, viewport: kViewport,
    });
    const page = context.pages()[0] ?? await context.newPage();
    page.setDefaultTimeout(15000);
    const pageErrors = [];
    page.on('pageerror', (e) => pageErrors.push(e.message));
    await page.goto(base);
    await until('frames drawn', () => page.evaluate(() => window.tumble?.connected && window.tumble.framesDrawn >= 2), 30000);
    await until('the timeline bar', () => page.locator('#timeline').isVisible(), 20000);
    // The scene alone: the cards and the panel are painted black, since the timeline's fill,
    // the energy readout and the panel's numbers share the seed box's orange hue.
    const sceneShot = () => page.screenshot({ mask: [page.locator('.card, .lil-gui, #hint')], maskColor: '#000000' });
    const newFrame = async () => {
      const n = await page.evaluate(() => window.tumble.framesDrawn);
      await until('a newly drawn frame', () => page.evaluate((k) => window.tumble.framesDrawn > k, n));
    };

    await t.test('drag the timeline back 3 s: the boxes are where they were (pixels and /api/state); resume from there', async () => {
      await until('a second of sim time', async () => (await get('state')).time > 1.5, 15000);
      // The moment to come back to: paused, its state and its picture.
      assert.ok((await post('pause')).ok);
      await until('paused on the page', () => page.evaluate(() => window.tumble.paused));
      // The scene's description card lies over the scene for its first 12 s: put it away (a
      // click does) so that both pictures show the same part of the scene.
      await page.evaluate(() => { const card = document.getElementById('description'); if (card) card.hidden = true; });
      await newFrame();
      const then = await get('state');
      await newFrame();
      const pictureThen = findColour(await sceneShot(), kSeedOrange);
      assert.ok(pictureThen.count > 300, `the box is seen (${pictureThen.count} px)`);
      assert.ok((await post('resume')).ok);
      await until('3.5 s more', async () => (await get('state')).time > then.time + 3.5, 20000);
      const now = await get('state');
      assert.ok(Math.hypot(...now.bodies[0].position.map((x, k) => x - then.bodies[0].position[k])) > 0.05
        || Math.hypot(...now.bodies[0].velocity.map((x, k) => x - then.bodies[0].velocity[k])) > 0.05, 'the box moved on since');

      // Drag the slider's thumb to where `then` lies on the track. Pressing the track half a
      // second back seeks there, which pauses the world: the range then stands still.
      await until('the bar to know the new range', () => page.evaluate((t0) => window.tumble.timeline?.to.time > t0 + 3, then.time));
      const slider = page.locator('#timeline input[type="range"]');
      const thumb = 8; // px: half the thumb; a range input maps [min, max] to [left + thumb, right − thumb]
      const track = async () => {
        const box = await slider.boundingBox();
        const { from, to } = await page.evaluate(() => window.tumble.timeline);
        return { box, from, to, xOf: (time) => box.x + thumb + ((time - from.time) / (to.time - from.time)) * (box.width - 2 * thumb) };
      };
      const idle = (what, n) => until(what, () => page.evaluate((k) => window.tumble.timelineChanges >= k && !window.tumble.seeking, n), 30000);
      let { box, from, to, xOf } = await track();
      const changes = await page.evaluate(() => window.tumble.timelineChanges);
      await page.mouse.move(xOf(to.time - 0.5), box.y + box.height / 2); // the track, just left of the thumb
      await page.mouse.down();
      await until('the press to pause the world on a past step', async () => (await get('state')).paused, 10000);
      await idle('the press\'s seek', changes);
      ({ box, from, to, xOf } = await track());
      assert.ok(from.time <= then.time, `the timeline reaches back to ${then.time} s (from ${from.time} s)`);
      await page.mouse.move(xOf((then.time + to.time) / 2), box.y + box.height / 2, { steps: 4 });
      await page.mouse.move(xOf(then.time), box.y + box.height / 2, { steps: 4 });
      await page.mouse.up();
      await idle('the drag to end and its seeks to be answered', changes + 1);
      // Then step by step with the arrow keys (one step each) onto `then`'s exact step.
      const startedAt = (await get('state')).step;
      t.diagnostic(`the drag left the world at step ${startedAt}; the step wanted is ${then.step}`);
      for (let tries = 0; tries < 30; tries++) {
        const shown = await get('state');
        if (shown.step === then.step) break;
        await slider.focus();
        const n = await page.evaluate(() => window.tumble.timelineChanges);
        await page.keyboard.press(shown.step > then.step ? 'ArrowLeft' : 'ArrowRight');
        await idle('the arrow key\'s seek', n + 1)
          .catch(async (e) => {
            const detail = await slider.evaluate((el) => `${el.min}..${el.max} step ${el.step} value ${el.value} focused ${document.activeElement === el}`);
            throw new Error(`${e.message}; at step ${shown.step}, want ${then.step}; slider ${detail}`);
          });
      }
      const back = await get('state');
      assert.equal(back.step, then.step, 'the world shows the step it was at then');
      assert.ok(back.paused, 'paused at the past step');
      assert.deepEqual(back.bodies.map((b) => [b.position, b.orientation, b.velocity, b.angular_velocity]),
        then.bodies.map((b) => [b.position, b.orientation, b.velocity, b.angular_velocity]),
        'every body exactly as it was (the replay is exact)');
      await page.locator('#timeline input[type="range"]').blur();
      await until('the page to draw the past step', () => page.evaluate((t0) => Math.abs(window.tumble.shownTime - t0) < 1e-6, back.time), 10000);
      await newFrame();
      const pictureBack = findColour(await sceneShot(), kSeedOrange);
      t.diagnostic(`box then at (${pictureThen.x.toFixed(1)}, ${pictureThen.y.toFixed(1)}) ${pictureThen.count} px; ` +
        `after the seek at (${pictureBack.x.toFixed(1)}, ${pictureBack.y.toFixed(1)}) ${pictureBack.count} px`);
      assert.ok(Math.hypot(pictureBack.x - pictureThen.x, pictureBack.y - pictureThen.y) < 3, 'drawn where it was (within 3 px)');
      assert.ok(Math.abs(pictureBack.count - pictureThen.count) < 0.1 * pictureThen.count, 'and as large (within 10%)');
      const bar = await page.locator('#timeline').innerText();
      assert.match(bar, /back/, 'the bar says the view is in the past');

      // Resume from here: the future is dropped and the world runs on from this step.
      await page.locator('#timeline [data-action="resume"]').click();
      await until('the world to run again', async () => !(await get('state')).paused, 5000);
      const history = await get('history');
      assert.ok(history.live, 'live again');
      assert.ok(history.to.time < then.time + 2, `the old future is gone (newest step at ${history.to.time} s, resumed at ${then.time} s)`);
      await until('sim time to advance from the resumed step', async () => {
        const s = await get('state');
        return s.time > then.time + 0.5 && s.time < then.time + 3;
      }, 10000);
    });

    await t.test('the contacts overlay draws points where a box touches the floor', async (t2) => {
      assert.ok((await post('reset', { scene: 'resting' })).ok);
      assert.ok((await post('resume')).ok, 'running, whatever the subtest before left');
      await until('the resting scene on the page', () => page.evaluate(() => window.tumble.scene === 'resting'));
      // Does this server stream contacts at all? A socket of the test's own (not the viewer's)
      // asks for them for 4 s: without any, the server has no contacts stream yet.
      const served = await page.evaluate(() => new Promise((resolve) => {
        const socket = new WebSocket(new URL('ws', location.href).href.replace(/^http/, 'ws'));
        let count = 0;
        socket.onopen = () => socket.send(JSON.stringify({ type: 'contacts', on: true }));
        socket.onmessage = (e) => { if (typeof e.data === 'string' && JSON.parse(e.data).type === 'contacts') count++; };
        setTimeout(() => { socket.close(); resolve(count); }, 4000);
      }));
      if (served === 0) {
        t2.skip('this server sends no contacts messages to a viewer that asks ({"type":"contacts","on":true})');
        return;
      }
      await page.locator('#panel .lil-title', { hasText: 'View' }).first().click();
      await page.getByRole('checkbox', { name: 'contacts' }).check();
      const contacts = await until('contact points from the stream', () => page.evaluate(() => {
        const c = window.tumble.contacts;
        return c?.points?.length >= 4 ? c : null;
      }), 10000);
      const scene = await get('scene');
      const state = await get('state');
      // Each point lies on the floor (y = 0) under one of the boxes' footprints.
      for (const [x, y, z, nx, ny, nz, impulse] of contacts.points) {
        assert.ok(Math.abs(y) < 0.02, `contact at y = ${y} m, on the floor`);
        const under = state.bodies.some((b, i) => {
          const [sx, , sz] = scene.bodies[i].size;
          return Math.abs(x - b.position[0]) <= sx / 2 + 0.02 && Math.abs(z - b.position[2]) <= sz / 2 + 0.02;
        });
        assert.ok(under, `contact at (${x}, ${z}) under a box`);
        // Normals come rounded to 1e-4 (docs/protocol.md, "contacts").
        assert.ok(Math.abs(Math.hypot(nx, ny, nz) - 1) < 1e-3 && Math.abs(ny) > 0.99, 'a vertical unit normal');
        assert.ok(impulse >= 0, 'a non-negative impulse');
      }
      // And they are drawn: the overlay's colour near each point's projection.
      await newFrame();
      const png = await page.screenshot();
      let drawn = 0;
      for (const p of contacts.points.slice(0, 12)) {
        const s = await page.evaluate((q) => window.tumble.worldToScreen(q), p.slice(0, 3));
        const seen = findColour(png, kContactPink, { x0: s.x - 10, x1: s.x + 10, y0: s.y - 10, y1: s.y + 10 });
        if (seen.count >= 4) drawn++;
      }
      assert.ok(drawn >= Math.min(4, contacts.points.length), `contact dots seen at ${drawn} points`);
      // None away from the contacts: the top of the frame has no such colour.
      const away = findColour(png, kContactPink, { x0: 0, x1: kViewport.width - 1, y0: 0, y1: 60 });
      assert.ok(away.count < 20, `no contact colour far from the contacts (${away.count} px)`);
      await page.getByRole('checkbox', { name: 'contacts' }).uncheck();
    });

    await t.test('the Add box form adds a box to the running world', async (t2) => {
      const before = (await get('scene')).bodies.length;
      await page.locator('#panel .lil-title', { hasText: 'Add box' }).first().click();
      await page.getByRole('button', { name: 'Add box', exact: true }).click();
      const outcome = await until('the answer to the form', () => page.evaluate(
        () => (window.tumble.boxesAdded > 0 ? 'added' : window.tumble.addBoxError)), 10000);
      if (outcome?.status === 404 || outcome?.status === 405) {
        t2.skip(`this server has no POST …/bodies (${outcome.status})`);
        return;
      }
      assert.equal(outcome, 'added', `the server took the box (${JSON.stringify(outcome)})`);
      await until('the scene to hold one more body', async () => (await get('scene')).bodies.length === before + 1, 5000);
      await until('the page to draw it', () => page.evaluate((n) => window.tumble.bodies === n, before + 1), 10000);
    });

    assert.deepEqual(pageErrors, [], 'no uncaught errors in the page');
  });
