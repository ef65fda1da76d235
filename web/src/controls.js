// User input: the lil-gui panel (pause / step / reset / scene / integrator / impulse / world),
// keyboard shortcuts, and click-or-tap on a box to kick it.
import GUI from 'lil-gui';
import { api } from './connection.js';
import { currentWorld } from './world.js';
import { WorldMenu } from './world_menu.js';

export const kIntegrators = ['euler', 'midpoint', 'rk4', 'symplectic_euler', 'splitting', 'exact'];

/** A pointer that moves less than this (px) between down and up is a click, not an orbit. */
const kClickSlopPx = 6;
/** …and is released within this many ms. */
const kClickMaxMs = 600;

/** What the HUD says when a world refuses this page's commands (401). */
export const kViewOnlyWorld = 'view only: this world belongs to another viewer; open its steer link to control it';
/** …and when the default world of a server run with --token does. */
export const kViewOnlyServer = 'view only: this server needs its token to steer; open the page with ?token=…';

export class Controls {
  /**
   * @param {import('./viewer.js').Viewer} viewer
   * @param {import('./hud.js').Hud} hud
   */
  constructor(viewer, hud) {
    this.viewer = viewer;
    this.hud = hud;
    this.paused = false;
    this.sceneNames = [];
    this.params = {
      toggle: () => this.#run(this.paused ? api.resume() : api.pause(), (r) => this.setPaused(r.paused)),
      step: () => this.#run(api.step(this.params.steps)),
      steps: 1,
      reset: () => this.#run(api.reset()),
      scene: '',
      integrator: 'exact',
      impulse: 3,
      frame: () => this.viewer.refit(),
    };
    this.#buildPanel();
    this.#bindPointer(viewer.renderer.domElement);
    this.#bindKeys();
  }

  #buildPanel() {
    const gui = new GUI({ title: 'Tumble' });
    gui.domElement.id = 'panel';
    this.gui = gui;
    this.toggleButton = gui.add(this.params, 'toggle').name('Pause');
    const stepFolder = gui.addFolder('Step (while paused)');
    this.stepButton = stepFolder.add(this.params, 'step').name('Step');
    stepFolder.add(this.params, 'steps', 1, 1000, 1).name('steps');
    this.stepButton.disable();
    gui.add(this.params, 'reset').name('Reset');
    this.sceneController = gui.add(this.params, 'scene', []).name('scene')
      .onChange((name) => this.#run(api.reset(name)));
    this.integratorController = gui.add(this.params, 'integrator', kIntegrators).name('integrator')
      .onChange((name) => this.#run(api.integrator(name), (r) => this.hud.setIntegrator(r.integrator ?? name)));
    gui.add(this.params, 'impulse', 0.1, 50, 0.1).name('impulse (N·s)');
    gui.add(this.params, 'frame').name('Frame bodies');
    this.worldMenu = new WorldMenu(gui, this.hud);
    if (window.matchMedia('(max-width: 640px)').matches) gui.close();
    this.loadSceneList();
  }

  /** Fills the scene menu from GET /api/scenes (kept as is when that fails). */
  async loadSceneList() {
    try {
      const { scenes } = await api.scenes();
      this.sceneNames = [...new Set([...(scenes ?? []), this.params.scene].filter(Boolean))];
      this.sceneController.options(this.sceneNames); // lil-gui ≥ 0.20 updates the menu in place
      this.worldMenu.setScenes(scenes ?? []);
    } catch (e) {
      this.hud.toast(`scene list: ${e.message}`);
    }
  }

  /** Shows the running scene in the menu without resetting it. */
  setSceneName(name) {
    if (!name || name === this.params.scene) return;
    this.params.scene = name;
    if (!this.sceneNames.includes(name)) {
      this.sceneNames = [...this.sceneNames, name];
      this.sceneController.options(this.sceneNames);
    }
    this.sceneController.updateDisplay();
  }

  /** Shows the running integrator in the menu without sending it. */
  setIntegrator(name) {
    if (!name || !kIntegrators.includes(name)) return;
    this.params.integrator = name;
    this.integratorController.updateDisplay();
  }

  /** Follows the server's paused flag (from every frame). */
  setPaused(paused) {
    if (paused === this.paused) return;
    this.paused = paused;
    this.toggleButton.name(paused ? 'Resume' : 'Pause');
    if (paused) this.stepButton.enable();
    else this.stepButton.disable();
  }

  /**
   * Awaits a REST call; shows its error (with the offending field) as a toast. A 401 means the
   * page may watch but not steer: the HUD says so until a command goes through.
   */
  async #run(promise, onOk) {
    try {
      const result = await promise;
      if (this.hud.notice) this.hud.setNotice('');
      if (onOk) onOk(result);
      return result;
    } catch (e) {
      if (e.status === 401) {
        const text = currentWorld() ? kViewOnlyWorld : kViewOnlyServer;
        this.hud.setNotice(text);
        this.hud.toast(text);
      } else {
        this.hud.toast(e.field ? `${e.message} (${e.field})` : e.message);
      }
      return null;
    }
  }

  #bindPointer(canvas) {
    const downs = new Map(); // pointerId → {x, y, t}
    let multiTouch = false;
    canvas.addEventListener('pointerdown', (e) => {
      downs.set(e.pointerId, { x: e.clientX, y: e.clientY, t: performance.now() });
      if (downs.size > 1) multiTouch = true;
    });
    const release = (e, cancelled) => {
      const down = downs.get(e.pointerId);
      downs.delete(e.pointerId);
      const wasMulti = multiTouch;
      if (downs.size === 0) multiTouch = false;
      if (!down || cancelled || wasMulti || e.button > 0) return;
      const moved = Math.hypot(e.clientX - down.x, e.clientY - down.y);
      if (moved <= kClickSlopPx && performance.now() - down.t <= kClickMaxMs) this.kick(e.clientX, e.clientY);
    };
    canvas.addEventListener('pointerup', (e) => release(e, false));
    canvas.addEventListener('pointercancel', (e) => release(e, true));
  }

  /** Kicks the box under a client point: impulse along the view ray, applied at the hit point. */
  kick(x, y) {
    const hit = this.viewer.pick(x, y);
    if (!hit) return false;
    const impulse = hit.direction.clone().multiplyScalar(this.params.impulse);
    this.viewer.showKick(hit.point, hit.direction);
    this.#run(api.impulse(hit.body, impulse.toArray(), hit.point.toArray()));
    return true;
  }

  #bindKeys() {
    window.addEventListener('keydown', (e) => {
      if (e.target instanceof HTMLInputElement || e.target instanceof HTMLSelectElement) return;
      if (e.key === ' ') { e.preventDefault(); this.params.toggle(); }
      else if (e.key === 's' && this.paused) this.params.step();
      else if (e.key === 'r') this.params.reset();
      else if (e.key === 'f') this.params.frame();
    });
  }
}
