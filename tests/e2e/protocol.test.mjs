// Unit test of the viewer's frame and scene decoding (web/src/protocol.js) against
// docs/protocol.md, on hand-made messages. No browser, no server.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { BodyStates, decodeFrame, parseTextMessage, sceneFloor, kDefaultFaces } from '../../web/src/protocol.js';

/**
 * Builds a version-2 frame as docs/protocol.md lays it out: 40-byte header, the selection
 * (none for a keyframe, a bitmap or u32 indices), then per body a format byte, the centre
 * (3 × int32, or 3 × int16 relative to the base) and 9 axis components (int16 or int32).
 */
function makeFrame({ flags = 4, frame = 7, base = frame, count, time = 1.25, energy = 29.5, bodies, bitmap = false }) {
  const bytes = [];
  const u8 = (v) => bytes.push(v & 255);
  const le = (v, n) => { for (let i = 0; i < n; i++) u8(Number((BigInt.asUintN(8 * n, BigInt(v)) >> BigInt(8 * i)) & 255n)); };
  const f64 = (v) => { const d = new DataView(new ArrayBuffer(8)); d.setFloat64(0, v, true); for (let i = 0; i < 8; i++) u8(d.getUint8(i)); };
  [...'TMBL'].forEach((c) => u8(c.charCodeAt(0)));
  le(2, 2); le(flags | (bitmap ? 8 : 0), 2); le(frame, 4); le(base, 4); le(count, 4); le(bodies.length, 4);
  f64(time); f64(energy);
  if (!(flags & 4)) {
    if (bitmap) {
      const bits = new Array(Math.ceil(count / 8)).fill(0);
      for (const b of bodies) bits[b.index >> 3] |= 1 << (b.index & 7);
      bits.forEach(u8);
    } else {
      for (const b of bodies) le(b.index, 4);
    }
  }
  for (const b of bodies) {
    const wide = b.wide ?? false;
    u8((b.activity ?? 0) | (b.absolute ? 4 : 0) | (wide ? 8 : 0) | ((b.exponent - 8) << 4));
    for (const c of b.centre) le(c, b.absolute ? 4 : 2);
    for (const a of b.axes) le(a, wide ? 4 : 2);
  }
  return new Uint8Array(bytes).buffer;
}

// A unit cube at the origin, axis-aligned: half-edges of 0.5 m at 2⁻¹⁶ m units.
const cube = (index, { centre = [0, 0, 0], absolute = true, activity = 0 } = {}) => ({
  index, activity, absolute, exponent: 16, centre,
  axes: [32767, 0, 0, 0, 32767, 0, 0, 0, 32767],
});
const half = 32767 / 65536;

test('decodeFrame reads a keyframe; BodyStates rebuilds the vertices by additions', () => {
  const frame = decodeFrame(makeFrame({ flags: 4 | 1 | 2, frame: 4294967295, count: 2, bodies: [
    cube(0), cube(1, { centre: [2 * 65536, 0, 0], activity: 2 })] }));
  assert.equal(frame.paused, true);
  assert.equal(frame.someFrozen, true);
  assert.equal(frame.keyframe, true);
  assert.equal(frame.frame, 4294967295);
  assert.equal(frame.count, 2);
  assert.equal(frame.time, 1.25);
  assert.equal(frame.energy, 29.5);
  const states = new BodyStates();
  assert.ok(states.apply(frame));
  assert.deepEqual([...states.vertices.subarray(24, 27)], [2 - half, -half, -half]); // body 1, vertex 0
  assert.deepEqual([...states.vertices.subarray(45, 48)], [2 + half, half, half]);  // body 1, vertex 7
  assert.deepEqual([...states.activity], [0, 2]);
});

test('a delta moves only the bodies it carries, relative to its base', () => {
  const states = new BodyStates();
  assert.ok(states.apply(decodeFrame(makeFrame({ frame: 10, count: 3, bodies: [cube(0), cube(1), cube(2)] }))));
  states.dirty.fill(0);
  const delta = decodeFrame(makeFrame({ flags: 0, frame: 12, base: 10, count: 3,
    bodies: [cube(1, { centre: [65536 / 4, -2, 0], absolute: false })] }));
  assert.equal(delta.keyframe, false);
  assert.ok(states.apply(delta));
  assert.deepEqual([...states.dirty], [0, 1, 0]);
  assert.equal(states.vertices[24], 0.25 - half, 'body 1 moved by the delta 0.25 m along x');
  assert.equal(states.vertices[25], -half - 2 / 65536);
  assert.equal(states.vertices[0], -half, 'body 0 untouched');
  // The same bodies by bitmap.
  const byBitmap = decodeFrame(makeFrame({ flags: 0, frame: 13, base: 12, count: 3, bitmap: true,
    bodies: [cube(0, { centre: [1, 0, 0], absolute: false }), cube(2, { centre: [5, 5, 5] })] }));
  assert.deepEqual(byBitmap.bodies.map((b) => b.index), [0, 2]);
  assert.ok(states.apply(byBitmap));
  assert.equal(states.frame, 13);
  // A delta against a frame the page does not hold is refused and changes nothing.
  const stray = decodeFrame(makeFrame({ flags: 0, frame: 20, base: 19, count: 3, bodies: [cube(0, { centre: [9, 9, 9] })] }));
  assert.equal(states.apply(stray), false);
  assert.equal(states.frame, 13);
});

test('wide axes (int32) for large boxes', () => {
  const big = { index: 0, activity: 1, absolute: true, wide: true, exponent: 20, centre: [0, 0, 0],
    axes: [5 * 2 ** 20, 0, 0, 0, 2 ** 20, 0, 0, 0, 2 ** 19] };
  const states = new BodyStates();
  assert.ok(states.apply(decodeFrame(makeFrame({ count: 1, bodies: [big] }))));
  assert.deepEqual([...states.vertices.subarray(21, 24)], [5, 1, 0.5]);
  assert.equal(states.activity[0], 1);
});

test('decodeFrame refuses a wrong magic, version or length and bad indices', () => {
  const good = makeFrame({ count: 1, bodies: [cube(0)] });
  const bad = (mutate) => { const copy = good.slice(0); mutate(new DataView(copy)); return copy; };
  assert.throws(() => decodeFrame(bad((v) => v.setUint8(0, 0x58))), /magic/);
  assert.throws(() => decodeFrame(bad((v) => v.setUint16(4, 1, true))), /version/);
  assert.throws(() => decodeFrame(good.slice(0, good.byteLength - 1)), /early|expected/);
  assert.throws(() => decodeFrame(new ArrayBuffer(8)), /too short/);
  assert.throws(() => decodeFrame(makeFrame({ flags: 0, frame: 2, base: 1, count: 2, bodies: [cube(5)] })), /index/);
  assert.throws(() => decodeFrame(makeFrame({ flags: 0, frame: 2, base: 1, count: 4, bodies: [cube(2), cube(1)] })), /index/);
});

test('parseTextMessage reads a scene message; sceneFloor knows a null floor', () => {
  const text = JSON.stringify({ type: 'scene', scene: { name: 'seed', floor: { height: 0.5 } },
    faces: kDefaultFaces, bodies: [{ name: 'box', size: [1, 1, 1], color: '#d9822b' }] });
  const message = parseTextMessage(text);
  assert.equal(message.bodies[0].color, '#d9822b');
  assert.deepEqual(message.faces, kDefaultFaces);
  assert.deepEqual(sceneFloor(message.scene), { height: 0.5 });
  assert.equal(sceneFloor({ floor: null }), null);
  assert.deepEqual(sceneFloor({}), { height: 0 });
  assert.equal(parseTextMessage('{"type":"other"}'), null);
  assert.equal(parseTextMessage('{"type":"status","real_time_factor":1}').real_time_factor, 1);
});

test('the default faces are counter-clockwise seen from outside', () => {
  const v = (i) => [i & 1 ? 1 : -1, i & 2 ? 1 : -1, i & 4 ? 1 : -1];
  for (const [a, b, c, d] of kDefaultFaces) {
    const [pa, pb, pc, pd] = [a, b, c, d].map(v);
    const u = pc.map((x, k) => x - pa[k]), w = pd.map((x, k) => x - pb[k]);
    const n = [u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]];
    const centre = [pa, pb, pc, pd].reduce((s, p) => s.map((x, k) => x + p[k] / 4), [0, 0, 0]);
    assert.ok(n[0] * centre[0] + n[1] * centre[1] + n[2] * centre[2] > 0, `face ${[a, b, c, d]} points outwards`);
  }
});
