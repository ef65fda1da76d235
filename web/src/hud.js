// Heads-up display: connection state, sim time, real-time factor, frame rates, bytes/s
// received, lag behind the server, dropped frames, body activity counts, and short error
// toasts. Also keeps the statistics it shows.

/** Wall-clock window over which the drawing rate is measured, ms. */
const kRateWindowMs = 1000;
/** Longer window for the received frames and the measured real-time factor: frames arrive in
 *  bursts on a busy page. */
const kFrameWindowMs = 3000;
/** HUD text refresh interval, ms. */
const kRefreshMs = 200;

const kStateText = { connecting: 'connecting…', open: 'live', reconnecting: 'reconnecting…' };

export class Hud {
  /**
   * @param {HTMLElement} root the HUD card (gets data-connection, data-paused, data-frozen)
   * @param {HTMLElement} toastBox where error toasts go
   * Text goes to every element of the page with a matching `data-field`.
   */
  constructor(root, toastBox) {
    this.root = root;
    this.toastBox = toastBox;
    this.fields = {}; // field name → elements showing it
    for (const el of document.querySelectorAll('[data-field]')) (this.fields[el.dataset.field] ??= []).push(el);
    this.connection = 'connecting';
    this.retryInMs = 0;
    this.sceneName = '';
    this.integrator = '';
    this.simTime = 0;
    this.paused = false;
    this.framesReceived = 0;   // binary frames the stream worker received since it started
    this.bytesReceived = 0;    // message payload bytes it received
    this.dropped = 0;          // frames the server skipped for this page (its status message)
    this.droppedBefore = 0;    // ... on earlier connections
    this.latestAt = 0;         // wall clock (ms since the epoch) when simTime was received
    this.shownTime = 0;        // sim time of the state drawn last, s
    this.lag = 0;              // estimated server sim time minus shownTime, s
    this.byteSamples = [];     // [wall ms, bytes received so far, frames received so far]
    this.counts = { awake: 0, asleep: 0, frozen: 0 };
    this.frameSamples = [];    // [wall ms, sim time s] of recently drawn states
    this.renderTimes = [];     // wall ms of recent animation frames
    this.lastRefresh = 0;
    this.serverRtf = null;     // from the stream's status message
    this.serverRtfAt = 0;      // wall ms when it came
    this.world = 'default';    // id of the world shown, with ' · steer' when the page may steer it
    this.notice = '';          // a standing message (view only, …); empty when none
  }

  /** Shows which world the page follows (null: the default) and whether it holds its token. */
  setWorld(id, canSteer) {
    this.world = `${id ?? 'default'}${id && canSteer ? ' · steer' : ''}`;
    this.refresh(performance.now(), true);
  }

  /** Shows a standing message under the HUD's figures (empty string clears it). */
  setNotice(text) {
    this.notice = text;
    this.refresh(performance.now(), true);
  }

  /**
   * Says that world `id` does not exist on this server and offers the default world (null
   * hides the message). The card is #no-world in index.html.
   */
  setMissingWorld(id) {
    const card = document.getElementById('no-world');
    if (!card) return;
    card.hidden = id === null;
    set(this.fields['missing-world'], id === null ? '' : `'${id}'`);
  }

  setConnection(state, detail = {}) {
    this.connection = state;
    this.retryInMs = detail.retryInMs ?? 0;
    if (state === 'open') {
      // A new connection may be a restarted server whose frame counter starts again.
        this.droppedBefore = this.dropped;
      this.frameSamples.length = 0;
    }
    this.refresh(performance.now(), true);
  }

  setScene(name, integrator) {
    this.sceneName = name;
    if (integrator) this.integrator = integrator;
    this.frameSamples.length = 0;
  }

  setIntegrator(name) {
    this.integrator = name;
  }

  /**
   * Takes the stream worker's counters: bytes and frames received, and the newest server sim
   * time it heard of (s) with the wall-clock time it came (ms since the epoch).
   */
  onCounters({ bytes, frames, serverTime, receivedAt }) {
    this.bytesReceived = bytes;
    this.framesReceived = frames;
    this.simTime = serverTime;
    this.latestAt = receivedAt;
  }

  /** Records a newly drawn state (a StateReader) at the current animation frame. */
  onDrawn(state) {
    const now = performance.now();
    if (state.time < this.shownTime) this.frameSamples.length = 0;
    this.paused = state.paused;
    this.frameSamples.push([now, state.time]);
    trim(this.frameSamples, now, (s) => s[0], kFrameWindowMs);
  }

  /**
   * Records an animation frame at wall time `now` (ms) that shows sim time `shownTime` (s);
   * refreshes the text now and then.
   */
  onRender(now, shownTime) {
    this.renderTimes.push(now);
    trim(this.renderTimes, now, (t) => t, kRateWindowMs);
    this.byteSamples.push([now, this.bytesReceived, this.framesReceived]);
    trim(this.byteSamples, now, (s) => s[0], kFrameWindowMs);
    this.shownTime = shownTime;
    this.lag = this.lagAt(now);
    this.refresh(now, false);
  }

  /**
   * Sim seconds the state on screen is behind the server at page time `now` (ms): the newest
   * sim time the stream worker received, advanced by the wall time since (at the server's
   * real-time factor), minus the sim time of the state drawn.
   */
  lagAt(now) {
    const since = Math.max(0, performance.timeOrigin + now - this.latestAt) / 1000;
    const serverTime = this.simTime + (this.paused ? 0 : since * (this.serverRtf ?? 1));
    return Math.max(0, serverTime - this.shownTime);
  }

  /** Message bytes received per second over the last few seconds. */
  get bytesPerSecond() {
    return this.#sampleRate(1);
  }

  /** Frames per second drawn by the page. */
  get renderFps() {
    return rate(this.renderTimes.length, this.renderTimes[0], this.renderTimes[this.renderTimes.length - 1]);
  }

  /** Frames per second received by the stream worker over the last few seconds. */
  get streamFps() {
    return this.#sampleRate(2);
  }

  #sampleRate(column) {
    const s = this.byteSamples;
    if (s.length < 2 || s[s.length - 1][0] <= s[0][0]) return 0;
    return ((s[s.length - 1][column] - s[0][column]) * 1000) / (s[s.length - 1][0] - s[0][0]);
  }

  /**
   * Sim seconds per wall second: the server's own figure from its status message when fresh,
   * else measured from the frames (0 while paused).
   */
  get realTimeFactor() {
    if (this.paused) return 0;
    if (this.serverRtf !== null && performance.now() - this.serverRtfAt < 2500) return this.serverRtf;
    const s = this.frameSamples;
    if (s.length < 2) return 0;
    const wall = (s[s.length - 1][0] - s[0][0]) / 1000;
    return wall > 0 ? (s[s.length - 1][1] - s[0][1]) / wall : 0;
  }

  /** Takes the server's status message (real-time factor, integrator, counts, drops). */
  setServerState(state) {
    if (Number.isFinite(state.awake)) this.counts = { awake: state.awake, asleep: state.asleep, frozen: state.frozen };
    if (Number.isFinite(state.dropped)) this.dropped = this.droppedBefore + state.dropped;
    if (Number.isFinite(state.real_time_factor)) {
      this.serverRtf = state.real_time_factor;
      this.serverRtfAt = performance.now();
    }
    if (state.integrator) this.integrator = state.integrator;
  }

  refresh(now, force) {
    if (!force && now - this.lastRefresh < kRefreshMs) return;
    this.lastRefresh = now;
    const f = this.fields;
    const live = this.connection === 'open';
    const connText = kStateText[this.connection] ?? this.connection;
    const retry = this.connection === 'reconnecting' && this.retryInMs
      ? ` (next try in ${(this.retryInMs / 1000).toFixed(1)} s)` : '';
    this.root.dataset.connection = document.body.dataset.connection = this.connection;
    set(f.connection, connText);
    set(f['connection-detail'], connText + retry);
    set(f.world, this.world);
    set(f.notice, this.notice);
    set(f.scene, this.sceneName || '—');
    set(f.integrator, this.integrator || '—');
    set(f.time, `${this.simTime.toFixed(3)} s`);
    set(f.paused, !live ? 'offline' : this.paused ? 'paused' : 'running');
    this.root.dataset.paused = String(this.paused);
    set(f.rtf, live && !this.paused ? `${this.realTimeFactor.toFixed(2)}×` : '—');
    set(f.fps, `${this.renderFps.toFixed(0)}`);
    set(f.stream, live ? `${this.streamFps.toFixed(0)}` : '0');
    set(f.dropped, String(this.dropped));
    set(f.bytes, live ? formatRate(this.bytesPerSecond) : '0 B/s');
    set(f.lag, live ? `${(this.lag * 1000).toFixed(0)} ms` : '—');
    const c = this.counts;
    set(f.bodies, `${c.awake + c.asleep + c.frozen}`);
    set(f.activity, `${c.awake} awake · ${c.asleep} asleep${c.frozen ? ` · ${c.frozen} frozen` : ''}`);
    this.root.dataset.frozen = String(c.frozen > 0);
  }

  /** Shows a short message at the bottom of the screen for a few seconds. */
  toast(message, kind = 'error') {
    const el = document.createElement('div');
    el.className = `toast ${kind}`;
    el.textContent = message;
    this.toastBox.appendChild(el);
    setTimeout(() => el.remove(), 4000);
  }
}

function formatRate(bytesPerSecond) {
  if (bytesPerSecond >= 1e6) return `${(bytesPerSecond / 1e6).toFixed(2)} MB/s`;
  if (bytesPerSecond >= 1e3) return `${(bytesPerSecond / 1e3).toFixed(1)} kB/s`;
  return `${bytesPerSecond.toFixed(0)} B/s`;
}

function set(elements, text) {
  for (const el of elements ?? []) if (el.textContent !== text) el.textContent = text;
}

function trim(list, now, wallOf, windowMs) {
  let drop = 0;
  while (drop < list.length - 1 && now - wallOf(list[drop]) > windowMs) drop++;
  if (drop) list.splice(0, drop);
}

function rate(count, first, last) {
  return count >= 2 && last > first ? ((count - 1) * 1000) / (last - first) : 0;
}
