// Tick labels of the energy plot's axes: as many decimals as the tick step needs, so that
// neighbouring labels differ and each is its tick rounded right ("2.5 s, 5.0 s, 7.5 s";
// "453.1 kJ, 453.2 kJ"). Pure: no DOM, no uPlot.

/** Most decimals a label gets. */
const kMaxDecimals = 9;

/** Decimals needed to write every multiple of `step` exactly: 0 for 5, 1 for 2.5, 2 for 0.25. */
export function stepDecimals(step) {
  if (!(step > 0) || !Number.isFinite(step)) return 0;
  for (let d = 0; d < kMaxDecimals; d++) {
    const scaled = step * 10 ** d;
    if (Math.abs(scaled - Math.round(scaled)) <= 1e-7 * Math.max(1, scaled)) return d;
  }
  return kMaxDecimals;
}

/** `value` with `decimals` decimals, never "-0". */
function fixed(value, decimals) {
  const text = value.toFixed(decimals);
  return /^-0(\.0*)?$/.test(text) ? text.slice(1) : text;
}

/** Labels of time ticks `step` seconds apart. */
export function secondsLabels(ticks, step) {
  const d = stepDecimals(step);
  return ticks.map((t) => `${fixed(t, d)} s`);
}

/** The unit energies `values` (J) are best written in: {unit, scale}. */
export function energyUnit(values) {
  const largest = Math.max(0, ...values.filter(Number.isFinite).map(Math.abs));
  if (largest >= 1e9) return { unit: 'GJ', scale: 1e9 };
  if (largest >= 1e6) return { unit: 'MJ', scale: 1e6 };
  if (largest >= 1e4) return { unit: 'kJ', scale: 1e3 };
  return { unit: 'J', scale: 1 };
}

/** Labels of energy ticks (J) `step` J apart, all in one unit. */
export function joulesLabels(ticks, step) {
  const { unit, scale } = energyUnit(ticks);
  const d = stepDecimals(step / scale);
  return ticks.map((t) => `${fixed(t / scale, d)} ${unit}`);
}

/**
 * The y range of an energy plot holding [min, max] J: at least a span of 2e-4 of the energy
 * (and 0.05 J), so a settled world's flat line gets a few readable ticks instead of labels
 * that differ in the ninth digit.
 */
export function energyRange(min, max) {
  if (!Number.isFinite(min) || !Number.isFinite(max)) return [0, 1];
  const mid = (min + max) / 2;
  const span = Math.max(max - min, 2e-4 * Math.abs(mid), 0.05);
  return [mid - 0.55 * span, mid + 0.55 * span];
}
