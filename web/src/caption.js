// The scene's description (docs/scenes.md), shown for a while when a scene loads.

/** How long the caption stays, ms (a tap or click dismisses it sooner). */
const kShowMs = 12000;

export class SceneCaption {
  /** @param {HTMLElement} element the #description card */
  constructor(element) {
    this.element = element;
    this.text = '';
    this.timer = 0;
    element.addEventListener('click', () => { element.hidden = true; });
  }

  /** Shows `description` (nothing when empty) and hides it after kShowMs. */
  show(description) {
    clearTimeout(this.timer);
    this.text = typeof description === 'string' ? description.trim() : '';
    this.element.textContent = this.text;
    this.element.hidden = !this.text;
    if (this.text) this.timer = setTimeout(() => { this.element.hidden = true; }, kShowMs);
  }
}
