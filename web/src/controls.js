// User input: the lil-gui panel (pause / step / reset / scene / integrator / impulse / view /
// world), keyboard shortcuts, and the pointer on a box: click or tap kicks it, a drag aims the
// kick (aim.js), a long press (or a click with the inspector on) inspects it.
import GUI from 'lil-gui';
import { api } from './connection.js';
import { KickAim } from './aim.js';
import { AddBoxMenu } from './add_box.js';
import { currentWorld } from './world.js';
import { WorldMenu } from './world_menu.js';

export const kIntegrators = ['euler', 'midpoint', 'rk4', 'symplectic_euler', 'splitting', 'exact'];

/** A press on a box that moves less than this (px) before it is released is a click (a kick), not an aim. */
const kClickSlopPx = 6;
/** A press held still this long on a box inspects it instead of kicking, ms. */
const kLongPressMs = 650;

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
      toggle: () => this.#run(this.paused ? this.resume() : api.pause(), (r) => this.setPaused(r.paused)),
      step: () => this.#run(api.step(this.params.steps)),
      steps: 1,
      reset: () => this.#run(api.reset()),
      scene: '',
      integrator: 'exact',
      impulse: 3,
      speed: 1,
      frame: () => this.viewer.refit(),
    };
    this.aim = new KickAim(viewer);
    this.lastKick = null; // {body, impulse, point} of the newest kick sent
    this.onInspect = () => {}; // set by main.js: (body index) → show it in the inspector
    this.inspected = () => -1; // …the body the inspector shows (−1: none)
    this.inspectOnClick = () => false; // …and whether a click inspects rather than kicks
    this.extraShortcuts = {}; // more key → action pairs (main.js)
    // What Resume (and space) sends: main.js makes it a playback while the timeline shows the
    // past, so that it never discards the recorded future by accident.
    this.resume = () => api.resume();
    this.#buildPanel();
    this.#bindPointer(viewer.renderer.domElement);
    this.#bindKeys();
    this.#keepKeysAfterClicks(this.gui.domElement);
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
    // Slow motion: the pace of the live run (POST …/speed; the timeline bar offers 0.25–4×).
    this.speedController = gui.add(this.params, 'speed', 0.1, 1, 0.05).name('speed (×)')
      .onFinishChange((v) => this.#run(api.speed(v)));
    gui.add(this.params, 'frame').name('Frame bodies');
    this.viewFolder = gui.addFolder('View');
    this.addBox = new AddBoxMenu(gui, this.hud);
    this.worldMenu = new WorldMenu(gui, this.hud);
    // On a phone the open panel would cover the scene: it starts folded, and folds when the
    // window becomes phone-sized.
    const phone = window.matchMedia('(max-width: 640px)');
    if (phone.matches) gui.close();
    phone.addEventListener('change', (e) => { if (e.matches) gui.close(); });
    this.loadSceneList();
  }

  /**
   * Why: a clicked lil-gui button or menu keeps the keyboard focus, and space then activates
   * that button again (Reset, then space: a second reset). Buttons and menus give the focus
   * back after use; text fields keep it while typed in, until Enter or a change.
   */
  #keepKeysAfterClicks(panel) {
    panel.addEventListener('click', (e) => {
      const button = e.target.closest?.('button');
      if (button) button.blur();
    });
    panel.addEventListener('change', (e) => {
      if (e.target instanceof HTMLSelectElement || e.target.type === 'checkbox') e.target.blur();
    });
    panel.addEventListener('keydown', (e) => {
      if (e.key === 'Enter' && e.target instanceof HTMLInputElement) e.target.blur();
    });
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

  /** Shows the server's speed (status message) on the slow-motion slider, when it is within it. */
  setSpeed(speed) {
    if (!Number.isFinite(speed) || speed === this.params.speed || speed > 1) return;
    this.params.speed = speed;
    this.speedController.updateDisplay();
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

  /**
   * A press on a box is ours (OrbitControls does not see it): released where it began it kicks
   * along the view ray (or, with the inspector on, inspects); dragged, it aims (aim.js); held
   * still for kLongPressMs, it inspects. A press elsewhere orbits, pans and zooms as before; a
   * second finger hands the gesture back to the orbit controls.
   *
   * Click or long press is decided by the events' own timestamps: on a busy page (a slow frame,
   * a phone) the long-press timer can run before a release that came in time, and that release
   * is still a click: the inspector goes back to what it showed and the box is kicked.
   */
  #bindPointer(canvas) {
    let press = null; // {id, x, y, hit, aiming, timer, done}
    const end = () => {
      if (!press) return;
      clearTimeout(press.timer);
      press = null;
      this.aim.cancel();
      this.viewer.controls.enabled = true;
    };
    // Capture phase on the container: decided before OrbitControls' own pointerdown runs.
    canvas.parentElement.addEventListener('pointerdown', (e) => {
      if (e.target !== canvas) return;
      if (press) { end(); return; } // a second pointer: pinch or pan
      if (e.button !== 0) return;
      const hit = this.viewer.pick(e.clientX, e.clientY);
      if (!hit) return;
      this.viewer.controls.enabled = false;
      canvas.setPointerCapture?.(e.pointerId);
      press = {
        id: e.pointerId, x: e.clientX, y: e.clientY, t0: e.timeStamp, hit, aiming: false, done: false,
        inspected: this.inspected(),
      };
      press.timer = setTimeout(() => {
        if (!press || press.aiming) return;
        press.done = true;
        this.onInspect(hit.body);
      }, kLongPressMs);
      this.aim.begin(hit);
    }, { capture: true });
    canvas.addEventListener('pointermove', (e) => {
      if (!press || e.pointerId !== press.id || press.done) return;
      if (!press.aiming && Math.hypot(e.clientX - press.x, e.clientY - press.y) <= kClickSlopPx) return;
      press.aiming = true;
      clearTimeout(press.timer);
      this.aim.update(e.clientX, e.clientY);
    });
    canvas.addEventListener('pointerup', (e) => {
      if (!press || e.pointerId !== press.id) return;
      const { hit, aiming, done } = press;
      const quick = e.timeStamp - press.t0 < kLongPressMs;
      if (aiming) {
        this.aim.update(e.clientX, e.clientY);
        const kick = this.aim.finish(this.params.impulse);
        if (kick) this.#sendKick(kick.body, kick.impulse, kick.point);
      } else if (!done || quick) {
        if (done) this.onInspect(press.inspected); // the timer ran late: undo its inspection
        if (this.inspectOnClick()) this.onInspect(hit.body);
        else this.kick(press.x, press.y);
      }
      end();
    });
    canvas.addEventListener('pointercancel', (e) => { if (press && e.pointerId === press.id) end(); });
  }

  /** Kicks the box under a client point: impulse along the view ray, applied at the hit point. */
  kick(x, y) {
    const hit = this.viewer.pick(x, y);
    if (!hit) return false;
    this.#sendKick(hit.body, hit.direction.clone().multiplyScalar(this.params.impulse), hit.point);
    return true;
  }

  /** Shows the kick's arrow and posts it: impulse in N·s at world point `point`, m. */
  #sendKick(body, impulse, point) {
    this.viewer.showKick(point, impulse.clone().normalize());
    this.lastKick = { body, impulse: impulse.toArray(), point: point.toArray() };
    this.#run(api.impulse(body, this.lastKick.impulse, this.lastKick.point));
  }

  /**
   * Shortcuts at the window, in the capture phase: they work wherever the focus is but in a
   * text field being typed in, and space never also presses a focused button.
   */
  #bindKeys() {
    const typing = (t) => (t instanceof HTMLInputElement && t.type !== 'checkbox' && t.type !== 'range')
      || t instanceof HTMLTextAreaElement || t instanceof HTMLSelectElement || t?.isContentEditable;
    window.addEventListener('keydown', (e) => {
      if (typing(e.target) || e.ctrlKey || e.metaKey || e.altKey) return;
      const action = this.shortcuts[e.key];
      if (!action) return;
      e.preventDefault();
      e.stopPropagation();
      if (!e.repeat || e.key === 's') action();
    }, { capture: true });
    // A button activates on space's keyup: not when space is a shortcut.
    window.addEventListener('keyup', (e) => {
      if (e.key === ' ' && !typing(e.target)) e.preventDefault();
    }, { capture: true });
  }

  /** Key → action of the keyboard shortcuts (web/README.md lists them). */
  get shortcuts() {
    return {
      ' ': () => this.params.toggle(),
      s: () => { if (this.paused) this.params.step(); },
      r: () => this.params.reset(),
      f: () => this.params.frame(),
      ...this.extraShortcuts,
    };
  }
}
