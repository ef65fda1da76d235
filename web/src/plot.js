// Live plot of the total energy (frame header field) against sim time, with uPlot.
import uPlot from 'uplot';
import { energyRange, joulesLabels, secondsLabels } from './ticks.js';

/** Seconds of sim time kept on the plot. */
const kWindowSeconds = 20;
/** Most points kept (older ones are dropped first). */
const kMaxPoints = 4000;
/** Minimum wall time between redraws, ms. */
const kRedrawMs = 100;

export class EnergyPlot {
  /** @param {HTMLElement} container  @param {HTMLElement} readout element showing E and its drift */
  constructor(container, readout) {
    this.container = container;
    this.readout = readout;
    this.times = [];
    this.energies = [];
    this.reference = null; // energy at the start of the current run, J
    this.lastDraw = 0;
    this.dirty = false;
    this.ticks = { x: null, y: null }; // the axes' newest ticks: {values, step, labels}
    const keep = (axis, format) => (u, values, axisIndex, space, step) => {
      const labels = format(values, step);
      this.ticks[axis] = { values: [...values], step, labels };
      return labels;
    };
    const axisStyle = { stroke: '#9aa4b2', grid: { stroke: 'rgba(255,255,255,0.07)', width: 1 },
      ticks: { stroke: 'rgba(255,255,255,0.15)', width: 1 }, font: '11px system-ui, sans-serif' };
    this.plot = new uPlot({
      width: Math.max(container.clientWidth, 100),
      height: Math.max(container.clientHeight, 60),
      legend: { show: false },
      cursor: { show: false },
      scales: { x: { time: false }, y: { range: (u, min, max) => energyRange(min, max) } },
      axes: [
        { ...axisStyle, size: 26, space: 44, values: keep('x', secondsLabels) },
        // As wide as its longest label (about 6.2 px a character at 11 px).
        { ...axisStyle, space: 18, size: (u, values) => 14 + 6.2 * Math.max(5, ...(values ?? []).map((v) => v.length)),
          values: keep('y', joulesLabels) },
      ],
      series: [{}, { label: 'E', stroke: '#f0a04b', width: 1.5, points: { show: false } }],
    }, [[], []], container);
    new ResizeObserver(() => this.resize()).observe(container);
  }

  resize() {
    this.plot.setSize({ width: Math.max(this.container.clientWidth, 100), height: Math.max(this.container.clientHeight, 60) });
  }

  /** Forgets all points (new scene, reset, or time running backwards). */
  clear() {
    this.times.length = 0;
    this.energies.length = 0;
    this.reference = null;
    this.dirty = true;
  }

  /** Adds one sample: sim time in s, total energy in J. Non-finite energies are skipped. */
  push(time, energy) {
    const last = this.times.length ? this.times[this.times.length - 1] : -Infinity;
    if (time < last) this.clear();
    else if (time === last) return; // paused: the same state again
    if (!Number.isFinite(energy)) return;
    if (this.reference === null) this.reference = energy;
    this.times.push(time);
    this.energies.push(energy);
    let drop = 0;
    while (drop < this.times.length && (this.times[drop] < time - kWindowSeconds || this.times.length - drop > kMaxPoints)) drop++;
    if (drop) {
      this.times.splice(0, drop);
      this.energies.splice(0, drop);
    }
    this.dirty = true;
  }

  /** Redraws if new samples came and the last redraw is old enough. Call once per animation frame. */
  draw(now) {
    if (!this.dirty || now - this.lastDraw < kRedrawMs) return;
    this.dirty = false;
    this.lastDraw = now;
    this.plot.setData([this.times, this.energies]);
    const n = this.energies.length;
    if (n === 0) {
      this.readout.textContent = 'E —';
      return;
    }
    const e = this.energies[n - 1];
    const drift = e - this.reference;
    let relative = '';
    if (Math.abs(this.reference) > 1e-9) {
      const r = drift / Math.abs(this.reference);
      relative = Math.abs(r) >= 1e-4 ? ` (${(100 * r).toFixed(2)}%)` : r === 0 ? '' : ` (${r.toExponential(0)} rel.)`;
    }
    this.readout.textContent = `E ${formatJoules(e)}  ΔE ${drift >= 0 ? '+' : ''}${formatJoules(drift)}${relative}`;
  }
}

function formatJoules(value) {
  const a = Math.abs(value);
  if (a >= 1e9 || (a > 0 && a < 1e-2)) return `${value.toExponential(1)} J`;
  if (a >= 1e6) return `${(value / 1e6).toFixed(a >= 1e8 ? 0 : 1)} MJ`;
  if (a >= 1e4) return `${(value / 1e3).toFixed(a >= 1e5 ? 0 : 1)} kJ`;
  return `${value.toFixed(a >= 100 ? 0 : a >= 10 ? 1 : 2)} J`;
}
