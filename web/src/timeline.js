// The timeline bar under the scene (docs/protocol.md, "Timeline"): a slider over the range the
// server keeps (drag to seek), markers at impacts and commands, play/pause, a speed menu
// (0.25–4×), "Resume here" from a past moment and a Live button. Hidden when the server keeps
// no timeline.
import { api } from './connection.js';

/** Time between two reads of GET …/history while the bar is shown, ms. */
const kRefreshMs = 1000;
/** …and between two tries when the server has no timeline (older server, --history-s 0), ms. */
const kRetryMs = 15000;
/** Playback speeds offered. */
export const kSpeeds = [0.25, 0.5, 1, 2, 4];
/** Most markers drawn of each kind (the newest). */
const kMaxMarkers = 400;

export class Timeline {
  /**
   * @param {HTMLElement} bar the #timeline element of index.html
   * @param {import('./hud.js').Hud} hud for errors
   */
  constructor(bar, hud) {
    this.bar = bar;
    this.hud = hud;
    this.history = null;  // newest GET …/history answer
    this.enabled = false;
    this.dragging = false;
    this.seeking = null;  // promise of the seek in flight
    this.wanted = null;   // time to seek to once it returns, s
    this.seeks = 0;       // seeks answered
    this.changes = 0;     // drags and key presses the slider finished
    this.timer = 0;
    this.slider = bar.querySelector('input[type="range"]');
    this.playButton = bar.querySelector('[data-action="play"]');
    this.resumeButton = bar.querySelector('[data-action="resume"]');
    this.liveButton = bar.querySelector('[data-action="live"]');
    this.speedMenu = bar.querySelector('select');
    this.label = bar.querySelector('[data-field="timeline-time"]');
    this.markers = bar.querySelector('.markers');
    for (const speed of kSpeeds) this.speedMenu.add(new Option(`${speed}×`, String(speed), speed === 1, speed === 1));

    this.slider.addEventListener('pointerdown', () => { this.dragging = true; });
    this.slider.addEventListener('input', () => this.seek(Number(this.slider.value)));
    this.slider.addEventListener('change', () => {
      // After a drag the keys go back to the shortcuts; arrow keys keep the focus for more steps.
      if (this.dragging) this.slider.blur();
      this.dragging = false;
      this.changes += 1;
      this.seek(Number(this.slider.value));
    });
    this.playButton.addEventListener('click', () => this.togglePlay());
    this.resumeButton.addEventListener('click', () => this.#command(api.resume()));
    this.liveButton.addEventListener('click', () => this.goLive());
    this.speedMenu.addEventListener('change', () => {
      this.speedMenu.blur();
      this.#command(api.speed(Number(this.speedMenu.value)));
    });
    for (const button of [this.playButton, this.resumeButton, this.liveButton]) {
      button.addEventListener('click', () => button.blur());
    }
    this.refresh();
  }

  /** Reads GET …/history and redraws; hides the bar when there is no timeline. */
  async refresh() {
    clearTimeout(this.timer);
    let next = kRefreshMs;
    try {
      if (!document.hidden) this.#show(await api.history());
    } catch (e) {
      this.#show(null);
      next = e.status === 404 || e.status === 405 ? kRetryMs : kRefreshMs * 3;
    }
    this.timer = setTimeout(() => this.refresh(), this.enabled ? next : Math.max(next, kRetryMs));
  }

  /** True while the world shows a past step (a timeline that is not live). */
  get inPast() {
    return Boolean(this.history && !this.history.live);
  }

  /** The speed chosen in the bar's menu. */
  get speed() {
    return Number(this.speedMenu.value);
  }

  /** Takes the timeline fields of a status message (live, playing, speed, paused, time). */
  onStatus(status) {
    if (!this.history || status.live === undefined) return;
    Object.assign(this.history, {
      live: status.live, playing: status.playing, speed: status.speed ?? this.history.speed, paused: status.paused,
    });
    this.history.at = { time: status.time, step: status.step };
    if (status.live && status.time > this.history.to.time) this.history.to = { time: status.time, step: status.step };
    this.#render();
  }

  /** Follows the sim time drawn (s): the slider's thumb moves with a playback or the live run. */
  onDrawn(time) {
    if (!this.history || this.dragging || this.seeking) return;
    if (this.history.live && time > this.history.to.time) this.history.to = { ...this.history.to, time };
    this.history.at = { ...this.history.at, time };
    this.#render();
  }

  /** Shows sim time `time` (s): POST …/seek, at most one in flight (the newest wish wins). */
  seek(time) {
    this.wanted = time;
    if (this.seeking) return this.seeking;
    const go = async () => {
      while (this.wanted !== null) {
        const t = this.wanted;
        this.wanted = null;
        try {
          const r = await api.seek(t);
          this.seeks += 1;
          if (this.history) {
            this.history.at = { time: r.time, step: r.step };
            Object.assign(this.history, { live: r.step === this.history.to.step, playing: false, paused: true });
          }
        } catch (e) {
          this.hud.toast(e.field ? `seek: ${e.message} (${e.field})` : `seek: ${e.message}`);
        }
      }
      this.seeking = null;
      this.#render();
      this.refresh();
    };
    this.seeking = go();
    return this.seeking;
  }

  /** Play (from the past: the recorded future at the chosen speed) or pause. */
  togglePlay() {
    const h = this.history;
    if (h && !h.paused && (h.playing || h.live)) this.#command(api.pause());
    else this.#command(api.play(Number(this.speedMenu.value)));
  }

  /** Back to the newest step, running: seek to it, then resume. */
  async goLive() {
    try {
      const h = await api.history();
      await api.seekStep(h.to.step);
      await api.resume();
    } catch (e) {
      this.hud.toast(`live: ${e.message}`);
    }
    this.refresh();
  }

  async #command(promise) {
    try {
      await promise;
    } catch (e) {
      this.hud.toast(e.field ? `${e.message} (${e.field})` : e.message);
    }
    this.refresh();
  }

  #show(history) {
    this.enabled = Boolean(history?.enabled);
    this.bar.hidden = !this.enabled;
    document.body.dataset.timeline = this.enabled ? 'on' : 'off';
    if (!this.enabled) { this.history = null; return; }
    this.history = history;
    this.#drawMarkers();
    this.#render();
  }

  #render() {
    const h = this.history;
    if (!h) return;
    const { from, to, at } = h;
    const dt = to.step > from.step ? (to.time - from.time) / (to.step - from.step) : 0.01;
    this.slider.min = String(from.time);
    this.slider.max = String(Math.max(to.time, from.time + dt));
    this.slider.step = String(dt);
    if (!this.dragging) this.slider.value = String(at.time);
    const behind = to.time - at.time;
    this.label.textContent = h.live ? `${at.time.toFixed(2)} s · live` : `${at.time.toFixed(2)} s · ${behind.toFixed(2)} s back`;
    const running = !h.paused && (h.playing || h.live);
    this.playButton.textContent = running ? '⏸' : '▶';
    this.playButton.setAttribute('aria-label', running ? 'pause' : 'play');
    this.resumeButton.hidden = h.live;
    this.liveButton.classList.toggle('on', Boolean(h.live));
    const speed = String(h.speed);
    if (!this.speedMenu.matches(':focus') && [...this.speedMenu.options].some((o) => o.value === speed)) this.speedMenu.value = speed;
    this.bar.dataset.state = h.live ? 'live' : h.playing ? 'playing' : 'past';
  }

  #drawMarkers() {
    const h = this.history;
    const span = Math.max(h.to.time - h.from.time, 1e-9);
    const place = (time) => `${(100 * (time - h.from.time)) / span}%`;
    const items = [];
    for (const m of (h.impacts ?? []).slice(-kMaxMarkers)) items.push(['impact', m.time, `impact: ${m.impacts} at ${m.time.toFixed(2)} s`]);
    for (const c of (h.commands ?? []).slice(-kMaxMarkers)) items.push(['command', c.time, `${c.kind} at ${c.time.toFixed(2)} s`]);
    this.markers.replaceChildren(...items.filter(([, t]) => t >= h.from.time && t <= h.to.time).map(([kind, time, title]) => {
      const el = document.createElement('span');
      el.className = `marker ${kind}`;
      el.style.left = place(time);
      el.title = title;
      return el;
    }));
  }
}
