// Scenes from the browser: a scene JSON file dropped on the page (or chosen with "Load scene
// file…") is posted as {"scene": {…}} to …/reset. The server validates it (docs/protocol.md);
// a refused scene leaves the world running, and the card shows the server's message beside
// the offending field as it stands in the file.
import { api } from './connection.js';

/**
 * The value at a server field path of the posted scene ("scene.bodies[0].mass" → the file's
 * bodies[0].mass), or undefined.
 */
export function valueAtField(scene, field) {
  const path = String(field ?? '').replace(/^scene\.?/, '');
  if (!path) return undefined;
  let value = scene;
  for (const part of path.match(/[^.[\]]+/g) ?? []) {
    if (value === null || typeof value !== 'object') return undefined;
    value = value[/^\d+$/.test(part) ? Number(part) : part];
  }
  return value;
}

export class SceneDrop {
  /**
   * @param {HTMLElement} card the #scene-error card (with [data-field] parts and a close button)
   * @param {HTMLElement} dropHint the overlay shown while a file is dragged over the page
   * @param {import('./hud.js').Hud} hud for the confirmation toast
   */
  constructor(card, dropHint, hud) {
    this.card = card;
    this.dropHint = dropHint;
    this.hud = hud;
    this.lastError = null; // {file, field, error} of the newest refusal, or null
    this.loaded = null;    // {name, description} of the newest scene file loaded
    card.querySelector('[data-action="close"]').addEventListener('click', () => this.#hideError());
    let depth = 0; // dragenter/dragleave pairs of nested elements
    const hasFiles = (e) => [...(e.dataTransfer?.types ?? [])].includes('Files');
    window.addEventListener('dragenter', (e) => { if (hasFiles(e)) { depth++; dropHint.hidden = false; } });
    window.addEventListener('dragleave', () => { if (--depth <= 0) { depth = 0; dropHint.hidden = true; } });
    window.addEventListener('dragover', (e) => { if (hasFiles(e)) e.preventDefault(); });
    window.addEventListener('drop', (e) => {
      depth = 0;
      dropHint.hidden = true;
      const file = e.dataTransfer?.files?.[0];
      if (!file) return;
      e.preventDefault();
      this.load(file);
    });
    this.picker = document.createElement('input');
    this.picker.type = 'file';
    this.picker.accept = '.json,application/json';
    this.picker.hidden = true;
    this.picker.addEventListener('change', () => {
      if (this.picker.files[0]) this.load(this.picker.files[0]);
      this.picker.value = '';
    });
    document.body.appendChild(this.picker);
  }

  /**
   * The description of scene `name` when it came from a file loaded here ('' otherwise): the
   * server's scene message may not carry it.
   */
  descriptionOf(name) {
    return this.loaded?.name === name ? this.loaded.description : '';
  }

  /** Opens the browser's file chooser (the panel's "Load scene file…"). */
  choose() {
    this.picker.click();
  }

  /** Reads a scene file and posts it to …/reset; shows the refusal, if any. */
  async load(file) {
    let scene;
    try {
      scene = JSON.parse(await file.text());
    } catch (e) {
      this.#showError(file.name, '', `not JSON: ${e.message}`, undefined);
      return false;
    }
    if (scene === null || typeof scene !== 'object' || Array.isArray(scene)) {
      this.#showError(file.name, '', 'a scene file holds one JSON object', undefined);
      return false;
    }
    // Known before the reset answers: the new scene's message may come first.
    this.loaded = { name: scene.name ?? 'untitled', description: scene.description ?? '' };
    try {
      await api.reset(scene);
    } catch (e) {
      this.loaded = null;
      this.#showError(file.name, e.field ?? '', e.message, valueAtField(scene, e.field));
      return false;
    }
    this.#hideError();
    this.hud.toast(`loaded ${file.name}`, 'info');
    return true;
  }

  #showError(file, field, error, value) {
    this.lastError = { file, field, error };
    const set = (name, text) => { this.card.querySelector(`[data-field="${name}"]`).textContent = text; };
    set('drop-file', file);
    set('drop-field', field ? field.replace(/^scene\./, '') : '(whole file)');
    set('drop-value', value === undefined ? '' : JSON.stringify(value).slice(0, 80));
    set('drop-error', error);
    this.card.hidden = false;
  }

  #hideError() {
    this.card.hidden = true;
  }
}
