// The panel's World folder: the server's worlds (join one), a new private world from a bundled
// scene, and the view and steer links of the world shown.
import { api } from './connection.js';
import {
  currentWorld, randomWorldId, shareable, steerLink, storeWorldToken, viewLink, worldToken, worldUrl,
} from './world.js';

/** Time between refreshes of the world list while the folder is open, ms. */
const kRefreshMs = 5000;
/** At most this many worlds are listed (the menu of a busy server stays usable). */
const kMaxListed = 50;
/** Random ids tried before "new private world" gives up (an id may be taken). */
const kCreateTries = 3;
/** Label of the default world in the menu. */
const kDefault = 'default';

export class WorldMenu {
  /**
   * @param {import('lil-gui').GUI} gui the panel to add the folder to
   * @param {import('./hud.js').Hud} hud where errors and confirmations go
   */
  constructor(gui, hud) {
    this.hud = hud;
    this.world = currentWorld();
    this.timer = 0;
    this.loading = false;
    this.params = {
      join: this.world ?? kDefault,
      template: 'seed',
      create: () => this.createWorld(),
      view: () => this.#copy('view link', shareable(viewLink(this.world))),
      steer: () => this.#copy('steer link', shareable(steerLink(this.world))),
    };
    const folder = gui.addFolder('World');
    this.folder = folder;
    this.joinController = folder.add(this.params, 'join', [this.params.join]).name('world')
      .onChange((id) => this.join(id));
    this.templateController = folder.add(this.params, 'template', ['seed']).name('template');
    this.createButton = folder.add(this.params, 'create').name('New private world');
    folder.add(this.params, 'view').name('Copy view link');
    this.steerButton = folder.add(this.params, 'steer').name('Copy steer link');
    this.updateSteer();
    // Why only while open: a closed menu needs no list, and a page left open all day should
    // not poll the server every few seconds for nothing.
    folder.onOpenClose((changed) => {
      if (changed !== folder) return;
      if (folder._closed) this.#stopRefresh();
      else this.#startRefresh();
    });
    folder.close();
  }

  /** Offers the bundled scenes (GET /api/scenes, read by the panel) as templates of a new world. */
  setScenes(names) {
    if (!names.length) return;
    if (!names.includes(this.params.template)) this.params.template = names[0];
    this.templateController.options(names);
    this.templateController.updateDisplay();
  }

  /** Enables "Copy steer link" when the page holds the shown world's token. */
  updateSteer() {
    if (worldToken(this.world)) this.steerButton.enable();
    else this.steerButton.disable();
  }

  /** Fills the world menu from GET /api/worlds (the default and the shown world always listed). */
  async refresh() {
    if (this.loading || document.hidden) return;
    this.loading = true;
    try {
      const { worlds } = await api.worlds();
      const options = { [kDefault]: kDefault };
      for (const w of (worlds ?? []).slice(0, kMaxListed)) {
        if (w.id === kDefault) continue;
        const viewers = `${w.viewers} viewer${w.viewers === 1 ? '' : 's'}`;
        options[`${w.id} · ${w.scene} · ${viewers}${w.paused ? ' · paused' : ''}`] = w.id;
      }
      if (this.world && !Object.values(options).includes(this.world)) options[this.world] = this.world;
      this.joinController.options(options);
      this.joinController.updateDisplay();
    } catch (e) {
      this.hud.toast(`world list: ${e.message}`);
    } finally {
      this.loading = false;
    }
  }

  /** Opens world `id` ('default' or null: the default world) by loading its address. */
  join(id) {
    const target = id === kDefault ? null : id;
    if (target === this.world) return;
    window.location.assign(worldUrl(target));
  }

  /**
   * Creates a private world from the chosen scene under a random id (PUT /api/worlds/{id}),
   * keeps its write token and opens it. An id that exists already (200 without a token, or 409)
   * belongs to someone else: another id is tried.
   */
  async createWorld() {
    this.createButton.disable();
    try {
      for (let i = 0; i < kCreateTries; i++) {
        const id = randomWorldId();
        let created;
        try {
          created = await api.createWorld(id, this.params.template);
        } catch (e) {
          if (e.status === 409) continue;
          this.hud.toast(createError(e));
          return false;
        }
        if (!created?.token) continue;
        storeWorldToken(id, created.token);
        // The steer link, fragment and all: the new page takes the token from it even where
        // localStorage is refused.
        window.location.assign(steerLink(id));
        return true;
      }
      this.hud.toast(`new world: ${kCreateTries} random ids were taken; try again`);
      return false;
    } finally {
      this.createButton.enable();
    }
  }

  #startRefresh() {
    this.refresh();
    clearInterval(this.timer);
    this.timer = setInterval(() => this.refresh(), kRefreshMs);
  }

  #stopRefresh() {
    clearInterval(this.timer);
    this.timer = 0;
  }

  async #copy(what, link) {
    if (!link) {
      this.hud.toast(`no ${what}: this page holds no token for this world`);
      return;
    }
    if (await copyText(link)) this.hud.toast(`${what} copied`, 'info');
    else this.hud.toast(`${what} (copy it by hand): ${link}`, 'info');
  }
}

/** The message for a failed PUT /api/worlds/{id}. */
function createError(e) {
  if (e.status === 429) return `new world: the server holds as many worlds as it may (${e.message})`;
  if (e.status === 401) return 'new world: this server needs its token to create worlds (open the page with ?token=…)';
  return `new world: ${e.field ? `${e.message} (${e.field})` : e.message}`;
}

/** Puts `text` on the clipboard; false when the browser refuses (no secure context, no focus). */
async function copyText(text) {
  try {
    await navigator.clipboard.writeText(text);
    return true;
  } catch {
    // Older or stricter browsers: a selected off-screen textarea and the copy command.
  }
  const area = document.createElement('textarea');
  area.value = text;
  area.setAttribute('readonly', '');
  area.style.cssText = 'position:fixed;left:-9999px;top:0;opacity:0';
  document.body.appendChild(area);
  area.select();
  let ok = false;
  try {
    ok = document.execCommand('copy');
  } catch {
    ok = false;
  }
  area.remove();
  return ok;
}
