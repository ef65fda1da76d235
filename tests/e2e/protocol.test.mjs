// Unit test of the viewer's frame and scene decoding (web/src/protocol.js) against
// docs/protocol.md, on hand-made messages. No browser, no server.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { decodeFrame, parseTextMessage, sceneFloor, kDefaultFaces } from '../../web/src/protocol.js';

/** Builds a frame as the protocol lays it out: header, N × 8 × 3 float32, N activity bytes. */
function makeFrame({ flags = 0, frame = 7, time = 1.25, energy = 29.5, bodies }) {
  const n = bodies.length;
  const buffer = new ArrayBuffer(32 + 97 * n);
  const view = new DataView(buffer);
  [...'TMBL'].forEach((c, i) => view.setUint8(i, c.charCodeAt(0)));
  view.setUint16(4, 1, true);
  view.setUint16(6, flags, true);
  view.setUint32(8, frame, true);
  view.setUint32(12, n, true);
  view.setFloat64(16, time, true);
  view.setFloat64(24, energy, true);
  bodies.forEach((body, b) => {
    body.vertices.forEach((v, k) => view.setFloat32(32 + b * 96 + k * 4, v, true));
    view.setUint8(32 + 96 * n + b, body.activity);
  });
  return buffer;
}

const unitCube = (dx) => Array.from({ length: 8 }, (_, i) => [
  (i & 1 ? 0.5 : -0.5) + dx, i & 2 ? 0.5 : -0.5, i & 4 ? 0.5 : -0.5]).flat();

test('decodeFrame reads the header, the vertices and the activity bytes', () => {
  const frame = decodeFrame(makeFrame({ flags: 3, frame: 4294967295, bodies: [
    { vertices: unitCube(0), activity: 0 }, { vertices: unitCube(2), activity: 2 }] }));
  assert.equal(frame.paused, true);
  assert.equal(frame.someFrozen, true);
  assert.equal(frame.frame, 4294967295);
  assert.equal(frame.count, 2);
  assert.equal(frame.time, 1.25);
  assert.equal(frame.energy, 29.5);
  assert.equal(frame.vertices.length, 48);
  assert.deepEqual([...frame.vertices.subarray(24, 27)], [1.5, -0.5, -0.5]); // body 1, vertex 0
  assert.deepEqual([...frame.vertices.subarray(45, 48)], [2.5, 0.5, 0.5]);  // body 1, vertex 7
  assert.deepEqual([...frame.activity], [0, 2]);
});

test('decodeFrame refuses a wrong magic, version or length', () => {
  const good = makeFrame({ bodies: [{ vertices: unitCube(0), activity: 1 }] });
  const bad = (mutate) => { const copy = good.slice(0); mutate(new DataView(copy)); return copy; };
  assert.throws(() => decodeFrame(bad((v) => v.setUint8(0, 0x58))), /magic/);
  assert.throws(() => decodeFrame(bad((v) => v.setUint16(4, 2, true))), /version/);
  assert.throws(() => decodeFrame(bad((v) => v.setUint32(12, 2, true))), /expected/);
  assert.throws(() => decodeFrame(new ArrayBuffer(8)), /too short/);
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
