// Browser test of the viewer's controls (issue 15) against the real server, in Debian's headless
// Chromium: shortcuts after a panel click, the aimed kick, the plot's tick labels, the camera
// kept above the floor, the inspector and follow camera, the PNG screenshot and WebM
// recording, a scene file dropped on the page, and the phone layout.
//
//   cd web && TUMBLE_SERVER=../build/release/server/tumble-server node --test ../tests/e2e/controls.test.mjs
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

/** Pixels of the aiming arrow's colour (#7fd4ff, unlit) in a screenshot. */
function countArrowPixels(png) {
  const { width, height, rgba } = decodePng(png);
  let count = 0;
  for (let i = 0; i < width * height * 4; i += 4) {
    if (Math.abs(rgba[i] - 0x7f) < 14 && Math.abs(rgba[i + 1] - 0xd4) < 14 && Math.abs(rgba[i + 2] - 0xff) < 14) count++;
  }
  return count;
}

/** Pixels of the seed box's orange (#d9822b under any lighting) in a decoded image. */
function countOrange({ width, height, rgba }) {
  let count = 0;
  for (let i = 0; i < width * height * 4; i += 4) {
    const r = rgba[i], g = rgba[i + 1], b = rgba[i + 2];
    const k = r / 0xd9;
    if (r >= 60 && Math.abs(g - 0x82 * k) < 22 && Math.abs(b - 0x2b * k) < 22 && r - b > 50) count++;
  }
  return count;
}

const norm = (v) => Math.hypot(...v);
const unit = (v) => v.map((x) => x / norm(v));
const dot = (a, b) => a.reduce((s, x, k) => s + x * b[k], 0);

test('controls: shortcuts, aimed kick, ticks, floor, inspector and follow, capture, scene drop, phone',
  { timeout: 240000 }, async (t) => {
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

    context = await chromium.launchPersistentContext(userData, {
      executablePath: kChromium, headless: true, args: kChromiumArgs, viewport: kViewport, acceptDownloads: true,
    });
    const page = context.pages()[0] ?? await context.newPage();
    page.setDefaultTimeout(15000);
    const pageErrors = [];
    page.on('pageerror', (e) => pageErrors.push(e.message));
    await page.goto(base);
    await until('frames drawn', () => page.evaluate(() => window.tumble?.connected && window.tumble.framesDrawn >= 2), 30000);
    const newFrame = async () => {
      const n = await page.evaluate(() => window.tumble.framesDrawn);
      await until('a newly drawn frame', () => page.evaluate((k) => window.tumble.framesDrawn > k, n));
    };
    /** Restarts the seed scene paused: the box in the air where the camera was framed. */
    const restartPaused = async () => {
      assert.ok((await post('pause')).ok);
      assert.ok((await post('reset')).ok);
      await until('the page to show the restart, paused', () => page.evaluate(() => window.tumble.paused && window.tumble.shownTime < 0.05));
      await page.keyboard.press('f');
      await newFrame();
      await newFrame();
    };
    const openFolder = async (name) => {
      const title = page.locator('#panel .lil-title', { hasText: name }).first();
      if ((await title.getAttribute('aria-expanded')) !== 'true') await title.click();
    };

    await t.test('after clicking Reset, space pauses (it does not press Reset again); r and space still work', async () => {
      const step0 = (await get('state')).step;
      await page.getByRole('button', { name: 'Reset', exact: true }).click();
      await until('the reset', async () => (await get('state')).step < step0);
      await until('a second of sim time', async () => (await get('state')).time > 1.0);
      const before = (await get('state')).time;
      await page.keyboard.press(' ');
      const paused = await until('space to pause the world', async () => {
        const s = await get('state');
        return s.paused ? s : null;
      }, 5000);
      await sleep(500);
      const after = await get('state');
      assert.ok(after.time >= before, `no second reset: sim time ${after.time} s after space, ${before} s before`);
      assert.equal(after.time, paused.time, 'paused, not reset and running');
      const focused = await page.evaluate(() => document.activeElement?.textContent ?? '');
      assert.notEqual(focused.trim(), 'Reset', 'the Reset button does not keep the focus');
      // A menu used with the mouse does not swallow the shortcuts either.
      await page.getByRole('combobox', { name: 'integrator' }).selectOption('rk4');
      await until('rk4', async () => (await get('state')).integrator === 'rk4');
      await page.keyboard.press(' ');
      await until('space to resume after using a menu', async () => !(await get('state')).paused, 5000);
      const step1 = (await get('state')).step;
      await page.keyboard.press('r');
      await until('r to reset after using a menu', async () => (await get('state')).step < step1, 5000);
    });

    await t.test('an aimed kick (drag from the box) pushes the box the way it was dragged, with an arrow while aiming', async () => {
      await restartPaused();
      const scene = await get('scene');
      const mass = scene.bodies[0].mass ?? 1;
      const before = (await get('state')).bodies[0];
      const from = await page.evaluate(() => window.tumble.bodyScreenPosition(0));
      assert.ok(from?.visible, 'the box is in view');
      const drag = [110, -60]; // px: right and up on the screen
      const noArrow = countArrowPixels(await page.screenshot());
      await page.mouse.move(from.x, from.y);
      await page.mouse.down();
      await page.mouse.move(from.x + drag[0] / 2, from.y + drag[1] / 2, { steps: 4 });
      await page.mouse.move(from.x + drag[0], from.y + drag[1], { steps: 4 });
      await newFrame();
      const arrow = countArrowPixels(await page.screenshot());
      t.diagnostic(`arrow pixels: ${noArrow} before aiming, ${arrow} while aiming`);
      assert.ok(arrow > 150 && arrow > 5 * noArrow + 50, `an arrow is seen while aiming (${arrow} px vs ${noArrow})`);
      await page.mouse.up();
      const after = await until('the kick to change the velocity', async () => {
        const b = (await get('state')).bodies[0];
        return norm(b.velocity.map((v, k) => v - before.velocity[k])) > 0.2 ? b : null;
      }, 10000);
      const dv = after.velocity.map((v, k) => v - before.velocity[k]);
      const kick = await page.evaluate(() => window.tumble.lastKick);
      // The server's answer to the impulse posted: Δv = J / m.
      assert.ok(Math.abs(norm(dv) - norm(kick.impulse) / mass) < 0.02 * norm(dv), `|Δv| ${norm(dv)} vs |J|/m`);
      // In world terms the push lies in the plane facing the camera (not along the view ray)...
      const view = await page.evaluate(() => window.tumble.viewDirection);
      const along = Math.abs(dot(unit(dv), view));
      assert.ok(along < 0.1, `the push is across the view, |cos| to the view ray = ${along.toFixed(3)} (tolerance 0.1)`);
      // ...and, drawn on the screen from the box's centre, it points the way the mouse went.
      const c = await page.evaluate(() => window.tumble.bodyScreenPosition(0));
      const centre = before.position;
      const tip = centre.map((x, k) => x + 0.5 * unit(dv)[k]);
      const [p0, p1] = await page.evaluate(([a, b]) => [window.tumble.worldToScreen(a), window.tumble.worldToScreen(b)], [centre, tip]);
      const screen = [p1.x - p0.x, p1.y - p0.y];
      const angle = Math.acos(Math.min(1, dot(unit(screen), unit(drag)))) * 180 / Math.PI;
      t.diagnostic(`Δv ${dv.map((x) => x.toFixed(2))} m/s; on screen ${angle.toFixed(1)}° from the drag; centre at ${c.x.toFixed(0)},${c.y.toFixed(0)}`);
      assert.ok(angle < 8, `the push is ${angle.toFixed(1)}° from the drag direction on screen (tolerance 8°)`);
    });

    await t.test('the energy plot\'s tick labels are distinct and are their ticks correctly rounded', async () => {
      assert.ok((await post('resume')).ok);
      let seen = null;
      await until('ticks on both axes', async () => {
        seen = await page.evaluate(() => window.tumble.plotTicks());
        return seen.x?.labels.length >= 2 && seen.y?.labels.length >= 2;
      }, 15000).catch((e) => { throw new Error(`${e.message}; ticks ${JSON.stringify(seen)}`); });
      await sleep(2500); // a few redraws of a longer window
      const ticks = await page.evaluate(() => window.tumble.plotTicks());
      t.diagnostic(`x: ${ticks.x.labels.join(' | ')}; y: ${ticks.y.labels.join(' | ')}`);
      const scale = { s: 1, J: 1, kJ: 1e3, MJ: 1e6, GJ: 1e9 };
      for (const axis of ['x', 'y']) {
        const { values, labels, step } = ticks[axis];
        assert.equal(new Set(labels).size, labels.length, `${axis} labels distinct: ${labels}`);
        labels.forEach((label, k) => {
          const [number, u] = label.split(' ');
          assert.ok(u in scale, `unit of ${label}`);
          const decimals = (number.split('.')[1] ?? '').length;
          const tolerance = 0.5 * 10 ** -decimals * scale[u] * (1 + 1e-9);
          assert.ok(Math.abs(Number(number) * scale[u] - values[k]) <= tolerance, `${label} for the tick at ${values[k]}`);
          // Enough digits for the step: neighbours differ by the step as read.
          if (k > 0) {
            const prev = Number(labels[k - 1].split(' ')[0]) * scale[u];
            assert.ok(Math.abs(Number(number) * scale[u] - prev - step) < 1e-6 * Math.max(1, Math.abs(step)),
              `${labels[k - 1]} → ${label} is the step ${step}`);
          }
        });
      }
    });

    await t.test('the camera cannot orbit under the floor', async () => {
      // Drag upwards on empty space near the top edge (no box there): orbit to look from below.
      const box = await page.evaluate(() => window.tumble.bodyScreenPosition(0));
      const x = box.x < kViewport.width / 2 ? kViewport.width - 250 : 250;
      await page.mouse.move(x, 240);
      await page.mouse.down();
      for (let k = 1; k <= 8; k++) await page.mouse.move(x, 240 - 25 * k, { steps: 2 });
      await page.mouse.up();
      await sleep(1500); // damping settles
      const { position, target } = await page.evaluate(() => window.tumble.camera);
      t.diagnostic(`camera at y = ${position[1].toFixed(2)} m, target y = ${target[1].toFixed(2)} m`);
      assert.ok(position[1] > 0.01, `camera above the floor (y = ${position[1]})`);
      assert.ok(position[1] >= target[1], 'camera not below its target\'s horizontal plane');
      await page.keyboard.press('f'); // frame the bodies again
    });

    await t.test('the inspector shows the body, and the camera follows it while it flies', async () => {
      await openFolder('View');
      await page.getByRole('checkbox', { name: 'click inspects' }).check();
      await restartPaused();
      const p = await page.evaluate(() => window.tumble.bodyScreenPosition(0));
      const v0 = (await get('state')).bodies[0].velocity;
      await page.mouse.click(p.x, p.y);
      await until('the inspector to open on the box', () => page.evaluate(() => window.tumble.inspected === 0));
      await until('the inspector to show its state', () => page.evaluate(() => window.tumble.inspectedState !== null));
      const text = await page.locator('#inspector').innerText();
      assert.match(text, /box/);
      assert.match(text, /1\.00 kg/);
      assert.match(text, /kinetic energy/);
      assert.deepEqual((await get('state')).bodies[0].velocity, v0, 'a click with the inspector on does not kick');
      await page.locator('#inspector button[data-action="follow"]').click();
      assert.equal(await page.evaluate(() => window.tumble.following), 0);
      await page.getByRole('checkbox', { name: 'click inspects' }).uncheck();
      // Up at 9 m/s: about 4 m of flight for about 2 s.
      const y0 = (await get('state')).bodies[0].position[1];
      assert.ok((await post('impulse', { body: 0, impulse: [0.8, 9, 0] })).ok);
      assert.ok((await post('resume')).ok);
      const offsets = [];
      let highest = y0;
      // At least 3 s and 5 drawn frames (a loaded machine draws few), at most 12 s: the box
      // bounces on the elastic floor all along.
      const end = Date.now() + 3000, last = Date.now() + 12000;
      while ((Date.now() < end || offsets.length < 5) && Date.now() < last) {
        await newFrame();
        const s = await page.evaluate(() => ({ p: window.tumble.bodyScreenPosition(0), w: innerWidth, h: innerHeight }));
        offsets.push(Math.hypot(s.p.x - s.w / 2, s.p.y - s.h / 2));
        highest = Math.max(highest, (await get('state')).bodies[0].position[1]);
      }
      const worst = Math.max(...offsets);
      t.diagnostic(`followed over ${offsets.length} frames: at most ${worst.toFixed(1)} px from the centre; rose ${(highest - y0).toFixed(2)} m`);
      assert.ok(highest - y0 > 1.5, `the body flew (rose ${highest - y0} m)`);
      assert.ok(offsets.length >= 5, `several frames looked at (${offsets.length})`);
      assert.ok(worst < 12, `the followed body stays within 12 px of the centre (worst ${worst.toFixed(1)} px)`);
      // Without following, the same flight leaves the centre: the check above can fail.
      await page.keyboard.press('Escape');
      assert.equal(await page.evaluate(() => window.tumble.following), -1);
      assert.ok((await post('impulse', { body: 0, impulse: [0, 9, 0] })).ok);
      let away = 0;
      await until('the unfollowed body to leave the centre', async () => {
        const s = await page.evaluate(() => ({ p: window.tumble.bodyScreenPosition(0), w: innerWidth, h: innerHeight }));
        away = Math.hypot(s.p.x - s.w / 2, s.p.y - s.h / 2);
        return away > 40;
      }, 5000, 50);
      await page.keyboard.press('f');
    });

    await t.test('the Screenshot button downloads a PNG of the view', async () => {
      await openFolder('View');
      await restartPaused();
      const [download] = await Promise.all([
        page.waitForEvent('download'),
        page.getByRole('button', { name: 'Screenshot (PNG)' }).click(),
      ]);
      assert.match(download.suggestedFilename(), /^tumble-seed-\d+\.\d\ds\.png$/);
      const bytes = fs.readFileSync(await download.path());
      assert.equal(bytes.subarray(0, 8).toString('hex'), '89504e470d0a1a0a', 'PNG signature');
      const image = decodePng(bytes);
      const canvas = await page.evaluate(() => [document.querySelector('#stage canvas').width, document.querySelector('#stage canvas').height]);
      assert.deepEqual([image.width, image.height], canvas, 'the canvas, at its size');
      const orange = countOrange(image);
      assert.ok(orange > 200, `the box is in the picture (${orange} orange px)`);
    });

    await t.test('the Record button records the canvas to a WebM file', async (t2) => {
      const supported = await page.evaluate(() => typeof MediaRecorder === 'function' && MediaRecorder.isTypeSupported('video/webm'));
      if (!supported) { t2.skip('this Chromium has no WebM MediaRecorder'); return; }
      await page.getByRole('button', { name: 'Record (WebM)' }).click();
      await sleep(1500);
      const [download] = await Promise.all([
        page.waitForEvent('download'),
        page.getByRole('button', { name: 'Stop recording' }).click(),
      ]);
      assert.match(download.suggestedFilename(), /\.webm$/);
      const bytes = fs.readFileSync(await download.path());
      assert.equal(bytes.subarray(0, 4).toString('hex'), '1a45dfa3', 'EBML (WebM) header');
      assert.ok(bytes.length > 1000, `${bytes.length} bytes of video`);
    });

    /** Drops a file with `text` named `name` on the page, as a person dragging it from a file manager. */
    const dropFile = (name, text) => page.evaluate(([n, body]) => {
      const data = new DataTransfer();
      data.items.add(new File([body], n, { type: 'application/json' }));
      const target = document.querySelector('#stage canvas');
      for (const type of ['dragenter', 'dragover', 'drop']) {
        target.dispatchEvent(new DragEvent(type, { dataTransfer: data, bubbles: true, cancelable: true }));
      }
    }, [name, text]);

    await t.test('a dropped malformed scene shows the field and its error; the world keeps running', async () => {
      if (await page.evaluate(() => window.tumble.paused)) assert.ok((await post('resume')).ok);
      const s0 = await get('state');
      await dropFile('bad.json', JSON.stringify({ name: 'bad', bodies: [{ name: 'a', mass: 1 }, { name: 'b', mass: -2 }] }));
      await until('the error card', () => page.locator('#scene-error').isVisible(), 5000);
      const card = await page.locator('#scene-error').innerText();
      t.diagnostic(`error card: ${card.replace(/\s+/g, ' ')}`);
      assert.match(card, /bad\.json/);
      assert.match(card, /bodies\[1\]\.mass/, 'the card names the field');
      assert.match(card, /-2/, 'and shows its value from the file');
      const { field, error } = await page.evaluate(() => window.tumble.sceneError);
      assert.equal(field, 'scene.bodies[1].mass', 'the server\'s field');
      assert.ok(card.includes(error), 'and the server\'s message');
      await until('the world to keep running its scene', async () => {
        const s = await get('state');
        return s.time > s0.time + 0.5 && !s.paused;
      }, 5000);
      assert.equal((await get('scene')).name, 'seed');
      // Not JSON at all: said so, nothing sent.
      await dropFile('notes.json', '{"name": "x", bodies: ');
      await until('the JSON error', async () => /not JSON/.test(await page.locator('#scene-error').innerText()), 5000);
      assert.equal((await get('scene')).name, 'seed');
    });

    await t.test('a dropped valid scene loads, and its description is shown', async () => {
      const scene = {
        name: 'dropped', description: 'Two boxes dropped from a browser test.',
        bodies: [{ name: 'p', position: [0, 2, 0], color: '#3a86ff' }, { name: 'q', position: [1.5, 3, 0] }],
      };
      await dropFile('dropped.json', JSON.stringify(scene));
      await until('the server to run the dropped scene', async () => (await get('scene')).name === 'dropped', 5000);
      await until('the page to show it', () => page.evaluate(() => window.tumble.scene === 'dropped' && window.tumble.bodies === 2));
      await until('the error card to go', () => page.locator('#scene-error').isHidden(), 5000);
      await until('the description', async () => (await page.locator('#description').innerText()) === scene.description, 5000);
    });

    await t.test('Frame bodies frames the bulk, not one runaway body', async () => {
      const bodies = [[-1.5, 0.5, 0], [0, 0.5, 0], [1.5, 0.5, 0], [0, 1.5, 0], [0, 0.5, 1.5]]
        .map((position, i) => ({ name: `b${i}`, position }));
      bodies.push({ name: 'runaway', position: [400, 0.5, -300] });
      await dropFile('runaway.json', JSON.stringify({ name: 'runaway', bodies }));
      await until('the page to show the runaway scene', () => page.evaluate(() => window.tumble.scene === 'runaway' && window.tumble.bodies === 6));
      await newFrame();
      await page.keyboard.press('f');
      await newFrame();
      await newFrame();
      const { position, target } = await page.evaluate(() => window.tumble.camera);
      const distance = Math.hypot(...position.map((x, k) => x - target[k]));
      t.diagnostic(`target (${target.map((x) => x.toFixed(1))}), camera ${distance.toFixed(1)} m away`);
      assert.ok(Math.hypot(target[0], target[2]) < 2, `the camera looks at the bulk (target ${target})`);
      assert.ok(distance < 30, `from near enough to see it (${distance.toFixed(1)} m)`);
      const xs = await page.evaluate(() => [0, 2].map((i) => window.tumble.bodyScreenPosition(i).x));
      assert.ok(Math.abs(xs[1] - xs[0]) > 100, `the bulk is not a speck: 3 m across is ${Math.abs(xs[1] - xs[0]).toFixed(0)} px`);
    });

    await t.test('on a phone the hint stays (short) and the panel\'s controls are 44 px touch targets', async () => {
      await page.setViewportSize({ width: 390, height: 760 });
      await until('the panel to fold', () => page.evaluate(() => document.getElementById('panel').classList.contains('lil-closed')));
      const hint = await page.evaluate(() => {
        const r = document.getElementById('hint').getBoundingClientRect();
        return { left: r.left, right: r.right, top: r.top, bottom: r.bottom, text: document.getElementById('hint').innerText };
      });
      assert.ok(hint.right > hint.left && hint.left >= 0 && hint.right <= 390 && hint.bottom <= 760, `hint visible: ${JSON.stringify(hint)}`);
      assert.ok(hint.text.length > 10 && hint.text.length < 60, `a short hint: "${hint.text}"`);
      await page.locator('#panel > .lil-title').click();
      await openFolder('View');
      const small = await page.evaluate(() => [...document.querySelectorAll('#panel .lil-title, #panel .lil-controller')]
        .filter((el) => el.offsetParent !== null)
        .map((el) => ({ text: el.innerText.split('\n')[0], h: el.getBoundingClientRect().height }))
        .filter(({ h }) => h < 44 - 0.01));  // layout rounds 44 px to 43.99998 at some scales
      assert.deepEqual(small, [], 'every visible row of the panel is at least 44 px tall');
      await page.locator('#panel > .lil-title').click();
      await page.setViewportSize(kViewport);
    });

    assert.deepEqual(pageErrors, [], 'no uncaught errors in the page');
  });
