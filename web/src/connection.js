// The page's two links to the server: the /ws stream (with automatic reconnect) and the REST API,
// both addressed to the page's world (world.js).
import { decodeFrame, parseTextMessage } from './protocol.js';
import { currentWorld, worldToken } from './world.js';

/** First reconnect delay, ms; doubled after every failed attempt up to kMaxDelayMs. */
const kFirstDelayMs = 250;
const kMaxDelayMs = 5000;

/**
 * A WebSocket to /ws that reconnects with exponential backoff (and a little jitter).
 * Callbacks: onScene(sceneMessage), onStatus(statusMessage), onFrame(frame, bytes) → false
 * when the frame could not be applied (the connection is then reopened: a keyframe follows),
 * onState(state, detail). state is 'connecting' | 'open' | 'reconnecting'; detail.retryInMs is
 * set when reconnecting. Every frame handled is acknowledged to the server, which keeps at
 * most a few unacknowledged frames in flight: a receiver too busy to handle its messages gets
 * fewer frames instead of a growing queue (docs/protocol.md, "Pace"). The page runs it in a
 * worker (stream_worker.js), whose event loop a busy page does not block.
 */
export class StreamConnection {
  constructor(url, { onScene, onStatus, onFrame, onState, onError, onMessage }) {
    this.url = url;
    this.onScene = onScene;
    this.onStatus = onStatus;
    this.onMessage = onMessage ?? (() => {}); // other text messages (contacts, …)
    this.subscriptions = new Map(); // type → the opt-in text re-sent on every new connection
    this.onFrame = onFrame;
    this.bytesReceived = 0; // message payload bytes since the page loaded
    this.ackWindow = () => 4; // frames the server may have in flight (docs/protocol.md, "ack")
    this.onState = onState;
    this.onError = onError ?? ((e) => console.warn(e));
    this.attempt = 0;
    this.socket = null;
    this.timer = 0;
    this.state = 'connecting';
    this.connects = 0;
  }

  start() {
    this.#open();
  }

  #setState(state, detail = {}) {
    this.state = state;
    this.onState(state, detail);
  }

  #open() {
    this.#setState(this.attempt === 0 ? 'connecting' : 'reconnecting', { attempt: this.attempt });
    let socket;
    try {
      socket = new WebSocket(this.url);
    } catch (e) {
      this.onError(e);
      this.#scheduleRetry();
      return;
    }
    socket.binaryType = 'arraybuffer';
    this.socket = socket;
    socket.onopen = () => {
      this.attempt = 0;
      this.connects += 1;
      for (const text of this.subscriptions.values()) socket.send(text);
      this.#setState('open');
    };
    socket.onmessage = (event) => {
      if (this.socket !== socket) return;
      try {
        if (typeof event.data === 'string') {
          this.bytesReceived += event.data.length;
          const message = parseTextMessage(event.data);
          if (message?.type === 'scene') this.onScene(message);
          else if (message?.type === 'status') this.onStatus(message);
          else if (message?.type) this.onMessage(message);
        } else {
          this.bytesReceived += event.data.byteLength;
          const frame = decodeFrame(event.data);
          if (this.onFrame(frame) === false) throw new Error(`frame ${frame.frame} does not follow frame the page holds`);
          socket.send(`{"type":"ack","frame":${frame.frame},"window":${this.ackWindow()}}`);
        }
      } catch (e) {
        this.onError(e);
        socket.close(); // A fresh connection starts with a keyframe.
      }
    };
    socket.onclose = () => {
      if (this.socket !== socket) return;
      this.socket = null;
      this.#scheduleRetry();
    };
    socket.onerror = () => {}; // onclose follows and handles the retry.
  }

  /**
   * Sends an opt-in message (`{"type": "contacts", "on": true}`) now and on every later
   * connection; `on` false sends it once and forgets it.
   */
  subscribe(type, on) {
    const text = JSON.stringify({ type, on });
    if (on) this.subscriptions.set(type, text);
    else this.subscriptions.delete(type);
    if (this.socket?.readyState === WebSocket.OPEN) this.socket.send(text);
  }

  #scheduleRetry() {
    const base = Math.min(kMaxDelayMs, kFirstDelayMs * 2 ** this.attempt);
    const delay = Math.round(base * (0.8 + 0.4 * Math.random()));
    this.attempt += 1;
    this.#setState('reconnecting', { retryInMs: delay, attempt: this.attempt });
    clearTimeout(this.timer);
    this.timer = setTimeout(() => this.#open(), delay);
  }
}

/**
 * The WebSocket URL of the page's world (same host, /ws beside the page, `?world=<id>` unless it
 * is the default world). A `?token=` of the page goes along as `access_token` (a browser's
 * WebSocket cannot send an Authorization header; the server wants it under --token-reads).
 */
export function streamUrl() {
  const url = new URL('ws', window.location.href);
  url.protocol = url.protocol === 'https:' ? 'wss:' : 'ws:';
  const world = currentWorld();
  if (world) url.searchParams.set('world', world);
  const token = serverToken();
  if (token) url.searchParams.set('access_token', token);
  return url.href;
}

/** The server's own token, from the page's `?token=` (a server run with --token). */
function serverToken() {
  return new URLSearchParams(window.location.search).get('token');
}

/** Error thrown by the REST helpers: carries the server's message and offending field. */
export class ApiError extends Error {
  constructor(status, message, field) {
    super(message);
    this.status = status;
    this.field = field;
  }
}

/**
 * Why two tokens: a world's own token (made when it was created, held in localStorage) lets its
 * holder steer that world only; the server's --token (the page's `?token=`) steers every world
 * and guards reads under --token-reads. One Authorization header goes with each request: on a
 * POST the world's token when the page holds it, on a GET the server's when given.
 */
function bearer(method, world) {
  const own = worldToken(world), server = serverToken();
  return method === 'GET' ? server ?? own : own ?? server;
}

/** Path of a route of the page's world: `worlds/<id>/<route>`, or `<route>` for the default world. */
function worldPath(route) {
  const world = currentWorld();
  return world ? `worlds/${encodeURIComponent(world)}/${route}` : route;
}

async function request(method, path, body, { world = currentWorld() } = {}) {
  const init = { method, headers: {} };
  if (body !== undefined) {
    init.headers['Content-Type'] = 'application/json';
    init.body = JSON.stringify(body);
  }
  const token = bearer(method, world);
  if (token) init.headers.Authorization = `Bearer ${token}`;
  const response = await fetch(new URL(`api/${path}`, window.location.href), init);
  let payload = null;
  try {
    payload = await response.json();
  } catch {
    payload = null;
  }
  if (!response.ok) {
    throw new ApiError(response.status, payload?.error ?? `HTTP ${response.status}`, payload?.field ?? '');
  }
  return payload;
}

/**
 * The REST API of docs/protocol.md, one function per route. Each returns the parsed JSON. The
 * world's routes address the page's world (`/api/worlds/<id>/…`, unprefixed for the default).
 */
export const api = {
  scenes: () => request('GET', 'scenes'),
  state: () => request('GET', worldPath('state')),
  scene: () => request('GET', worldPath('scene')),
  pause: () => request('POST', worldPath('pause')),
  resume: () => request('POST', worldPath('resume')),
  step: (steps) => request('POST', worldPath('step'), { steps }),
  reset: (scene) => request('POST', worldPath('reset'), scene ? { scene } : undefined),
  integrator: (integrator) => request('POST', worldPath('integrator'), { integrator }),
  /** impulse in N·s and point in metres, world frame. */
  impulse: (body, impulse, point) => request('POST', worldPath('impulse'), { body, impulse, point }),
  /** The world's timeline: range, markers, live/playing/speed (docs/protocol.md, "Timeline"). */
  history: () => request('GET', worldPath('history')),
  /** Shows the step nearest sim time `time` (s), paused. */
  seek: (time) => request('POST', worldPath('seek'), { time }),
  /** Shows step `step`, paused. */
  seekStep: (step) => request('POST', worldPath('seek'), { step }),
  /** Plays the recorded future at `speed` × real time (live: resumes at that speed). */
  play: (speed) => request('POST', worldPath('play'), { speed }),
  /** Sets the pace of the live loop and of a playback, sim s per wall s (0.1–4). */
  speed: (speed) => request('POST', worldPath('speed'), { speed }),
  /** Adds a box: {name?, size, mass, position, velocity, …} as a scene body (docs/scenes.md). */
  addBody: (body) => request('POST', worldPath('bodies'), body),
  /** The server's worlds: {worlds: [{id, scene, bodies, viewers, real_time_factor, paused, time}], max_worlds}. */
  worlds: () => request('GET', 'worlds'),
  /** One world's entry; ApiError with status 404 when there is none. */
  world: (id) => request('GET', `worlds/${encodeURIComponent(id)}`, undefined, { world: id }),
  /** Creates world `id` from a bundled scene: 201 with its write token, 200 without when it exists. */
  createWorld: (id, scene) => request('PUT', `worlds/${encodeURIComponent(id)}`, { scene }, { world: id }),
};
