// The body inspector: a card with the chosen body's name, mass, velocity, angular velocity,
// kinetic energy and sleep state, read from GET …/state (docs/protocol.md) while it is open,
// and a button that makes the camera follow the body.
import { api } from './connection.js';

/** Time between two reads of the state while the card is open, ms. */
const kPollMs = 400;

/**
 * Kinetic energy of a box, J: ½ m |v|² + ½ ωᵀ I ω, with I = R diag(m(b²+c²)/12, …) Rᵀ the
 * solid cuboid's inertia in the world frame (R from the orientation quaternion [w, x, y, z]).
 */
export function kineticEnergy(mass, size, orientation, velocity, omega) {
  const [a, b, c] = size;
  const inertia = [mass * (b * b + c * c) / 12, mass * (a * a + c * c) / 12, mass * (a * a + b * b) / 12];
  const [w, x, y, z] = orientation;
  const n = Math.hypot(w, x, y, z) || 1;
  const [qw, qx, qy, qz] = [w / n, x / n, y / n, z / n];
  // ω in the body frame: Rᵀ ω (rows of Rᵀ are the columns of R).
  const R = [
    [1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)],
    [2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw)],
    [2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy)],
  ];
  let rotational = 0;
  for (let k = 0; k < 3; k++) {
    const wk = R[0][k] * omega[0] + R[1][k] * omega[1] + R[2][k] * omega[2];
    rotational += inertia[k] * wk * wk;
  }
  const v2 = velocity[0] ** 2 + velocity[1] ** 2 + velocity[2] ** 2;
  return 0.5 * mass * v2 + 0.5 * rotational;
}

const vec = (v) => `(${v.map((x) => x.toFixed(2)).join(', ')})`;

export class Inspector {
  /**
   * @param {HTMLElement} card the #inspector card of index.html
   * @param {import('./viewer.js').Viewer} viewer
   */
  constructor(card, viewer) {
    this.card = card;
    this.viewer = viewer;
    this.body = -1;
    this.latest = null; // the body's entry of the newest state read, with `energy` added
    this.timer = 0;
    this.onFollow = () => {}; // (body index or -1)
    card.querySelector('[data-action="follow"]').addEventListener('click', (e) => {
      e.currentTarget.blur();
      this.onFollow(this.viewer.following === this.body ? -1 : this.body);
      this.#render();
    });
    card.querySelector('[data-action="close"]').addEventListener('click', () => this.show(-1));
  }

  /** Opens the card on body `i` (-1: closes it) and reads its state now and every kPollMs. */
  show(i) {
    clearInterval(this.timer);
    this.body = i;
    this.latest = null;
    this.card.hidden = i < 0;
    if (i < 0) return;
    this.#render();
    this.refresh();
    this.timer = setInterval(() => this.refresh(), kPollMs);
  }

  /** Reads GET …/state and shows the body's entry. */
  async refresh() {
    const i = this.body;
    if (i < 0 || document.hidden) return;
    try {
      const state = await api.state();
      const b = state.bodies?.[i];
      if (this.body !== i || !b) return;
      const mass = this.viewer.bodyMasses[i] ?? 1;
      const size = this.viewer.bodySizes[i] ?? [1, 1, 1];
      this.latest = { ...b, mass, energy: kineticEnergy(mass, size, b.orientation, b.velocity, b.angular_velocity) };
      this.#render();
    } catch (e) {
      this.card.querySelector('[data-field="inspector-error"]').textContent = e.message;
    }
  }

  #render() {
    const set = (field, text) => { this.card.querySelector(`[data-field="${field}"]`).textContent = text; };
    const b = this.latest;
    set('inspector-name', this.viewer.bodyNames?.[this.body] ?? `body ${this.body}`);
    set('inspector-mass', `${(this.viewer.bodyMasses[this.body] ?? 1).toPrecision(3)} kg`);
    set('inspector-v', b ? `${vec(b.velocity)} m/s  |v| ${Math.hypot(...b.velocity).toFixed(2)}` : '…');
    set('inspector-w', b ? `${vec(b.angular_velocity)} rad/s` : '…');
    set('inspector-energy', b ? formatEnergy(b.energy) : '…');
    set('inspector-asleep', b ? (b.frozen ? 'frozen' : b.asleep ? 'asleep' : 'awake') : '…');
    set('inspector-error', '');
    const follow = this.card.querySelector('[data-action="follow"]');
    follow.textContent = this.viewer.following === this.body ? 'Stop following' : 'Follow';
  }
}

function formatEnergy(joules) {
  if (Math.abs(joules) >= 1e4) return `${(joules / 1e3).toFixed(2)} kJ`;
  return `${joules.toFixed(3)} J`;
}
