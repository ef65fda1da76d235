// The panel's "Add box" folder: size, mass, position and velocity of a new box, posted to
// POST …/bodies; a refused box shows the server's message with its field.
import { api } from './connection.js';

export class AddBoxMenu {
  /**
   * @param {import('lil-gui').GUI} gui the panel
   * @param {import('./hud.js').Hud} hud for the answer
   */
  constructor(gui, hud) {
    this.hud = hud;
    this.added = 0; // boxes the server took from this page
    this.lastError = null; // {status, error, field} of the newest refusal
    this.params = {
      sx: 1, sy: 1, sz: 1, mass: 1, x: 0, y: 4, z: 0, vx: 0, vy: 0, vz: 0,
      color: '#4cc38a',
      add: () => this.add(),
    };
    const folder = gui.addFolder('Add box');
    const p = this.params;
    for (const [key, name] of [['sx', 'size x (m)'], ['sy', 'size y (m)'], ['sz', 'size z (m)']]) folder.add(p, key, 0.05, 10, 0.05).name(name);
    folder.add(p, 'mass', 0.01, 1000, 0.01).name('mass (kg)');
    for (const [key, name] of [['x', 'x (m)'], ['y', 'y (m)'], ['z', 'z (m)']]) folder.add(p, key).name(name);
    for (const [key, name] of [['vx', 'vx (m/s)'], ['vy', 'vy (m/s)'], ['vz', 'vz (m/s)']]) folder.add(p, key).name(name);
    folder.addColor(p, 'color');
    this.button = folder.add(p, 'add').name('Add box');
    folder.close();
    this.folder = folder;
  }

  /** The box the form describes, as a scene body (docs/scenes.md). */
  get body() {
    const p = this.params;
    return {
      size: [p.sx, p.sy, p.sz], mass: p.mass, position: [p.x, p.y, p.z], velocity: [p.vx, p.vy, p.vz], color: p.color,
    };
  }

  /** Posts the box; the answer is a toast (the field named when refused). */
  async add() {
    this.button.disable();
    try {
      await api.addBody(this.body);
      this.added += 1;
      this.hud.toast('box added', 'info');
      return true;
    } catch (e) {
      this.lastError = { status: e.status, error: e.message, field: e.field };
      this.hud.toast(`add box: ${e.message}${e.field ? ` (${e.field})` : ''}`);
      return false;
    } finally {
      this.button.enable();
    }
  }
}
