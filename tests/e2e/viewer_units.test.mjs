// Unit tests of the viewer's pure helpers: the energy plot's tick labels (web/src/ticks.js), the
// inspector's kinetic energy (web/src/inspector.js) and the field lookup of a refused scene
// file (web/src/scene_drop.js). No browser, no server.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { energyRange, joulesLabels, secondsLabels, stepDecimals } from '../../web/src/ticks.js';
import { kineticEnergy } from '../../web/src/inspector.js';
import { valueAtField } from '../../web/src/scene_drop.js';

test('tick decimals follow the step', () => {
  assert.equal(stepDecimals(5), 0);
  assert.equal(stepDecimals(2.5), 1);
  assert.equal(stepDecimals(0.25), 2);
  assert.equal(stepDecimals(0.1), 1);
  assert.equal(stepDecimals(0.1 + 0.2 - 0.2), 1, 'floating-point noise in the step is not a decimal');
  assert.equal(stepDecimals(2e-4), 4);
});

test('2.5 s steps read 2.5 s, 5.0 s, 7.5 s (not 3 s, 5 s, 8 s)', () => {
  assert.deepEqual(secondsLabels([2.5, 5, 7.5, 10], 2.5), ['2.5 s', '5.0 s', '7.5 s', '10.0 s']);
  assert.deepEqual(secondsLabels([0, 5, 10], 5), ['0 s', '5 s', '10 s']);
  assert.deepEqual(secondsLabels([-0.0000001, 0.1], 0.1), ['0.0 s', '0.1 s'], 'no "-0"');
});

test('a settled pile at 453.15 kJ gets distinct, correctly rounded labels', () => {
  const [lo, hi] = energyRange(453150, 453150);
  assert.ok(hi - lo >= 1e-4 * 453150, 'a flat line gets a readable span');
  assert.deepEqual(joulesLabels([453100, 453200], 100), ['453.1 kJ', '453.2 kJ']);
  assert.deepEqual(joulesLabels([2.5e6, 2.55e6], 5e4), ['2.50 MJ', '2.55 MJ'], 'not "2.5 MJ" twice');
  assert.deepEqual(joulesLabels([4.9, 4.91], 0.01), ['4.90 J', '4.91 J']);
  assert.deepEqual(joulesLabels([-20, 0, 20], 20), ['-20 J', '0 J', '20 J']);
  // Every label, read back, is its tick to within half of its last digit.
  for (const step of [0.02, 0.25, 2.5, 50, 2000, 25000]) {
    const ticks = [1, 2, 3, 4].map((k) => 123400 + k * step);
    const labels = joulesLabels(ticks, step);
    assert.equal(new Set(labels).size, labels.length, `distinct at step ${step}: ${labels}`);
    labels.forEach((label, k) => {
      const [number, unit] = label.split(' ');
      const scale = { J: 1, kJ: 1e3, MJ: 1e6 }[unit];
      const decimals = (number.split('.')[1] ?? '').length;
      assert.ok(Math.abs(Number(number) * scale - ticks[k]) <= 0.5 * 10 ** -decimals * scale + 1e-9,
        `${label} for ${ticks[k]} J`);
    });
  }
});

test('kinetic energy of a box: translation plus rotation about a principal axis', () => {
  // A 2 kg cube of 1 m spinning at 3 rad/s about y, moving at 4 m/s: I = m/6 = 1/3 kg·m².
  const e = kineticEnergy(2, [1, 1, 1], [1, 0, 0, 0], [4, 0, 0], [0, 3, 0]);
  assert.ok(Math.abs(e - (0.5 * 2 * 16 + 0.5 * (2 / 6) * 9)) < 1e-12, `E = ${e}`);
  // A 1×2×3 box turned 90° about z spins about world x = its body y axis: I_yy = m(1² + 3²)/12.
  const q = [Math.SQRT1_2, 0, 0, Math.SQRT1_2];
  const e2 = kineticEnergy(12, [1, 2, 3], q, [0, 0, 0], [1, 0, 0]);
  assert.ok(Math.abs(e2 - 0.5 * 12 * (1 + 9) / 12) < 1e-9, `E = ${e2}`);
});

test('a refused field is found in the dropped scene', () => {
  const scene = { name: 'x', bodies: [{ mass: 1 }, { mass: -1, size: [1, 0, 1] }] };
  assert.equal(valueAtField(scene, 'scene.bodies[1].mass'), -1);
  assert.deepEqual(valueAtField(scene, 'scene.bodies[1].size'), [1, 0, 1]);
  assert.equal(valueAtField(scene, 'scene.bodies[1].size[1]'), 0);
  assert.equal(valueAtField(scene, 'scene.gravity'), undefined);
  assert.equal(valueAtField(scene, ''), undefined);
});
