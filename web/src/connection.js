// The page's two links to the server: the /ws stream (with automatic reconnect) and the REST API.
import { decodeFrame, parseTextMessage } from './protocol.js';

/** First reconnect delay, ms; doubled after every failed attempt up to kMaxDelayMs. */
const kFirstDelayMs = 250;
const kMaxDelayMs = 5000;

/**
 * A WebSocket to /ws that reconnects with exponential backoff (and a little jitter).
 * Callbacks: onScene(sceneMessage), onFrame(frame), onState(state, detail).
 * state is 'connecting' | 'open' | 'reconnecting'; detail.retryInMs is set when reconnecting.
 */
export class StreamConnection {
  constructor(url, { onScene, onFrame, onState, onError }) {
    this.url = url;
    this.onScene = onScene;
    this.onFrame = onFrame;
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
      this.#setState('open');
    };
    socket.onmessage = (event) => {
      try {
        if (typeof event.data === 'string') {
          const scene = parseTextMessage(event.data);
          if (scene) this.onScene(scene);
        } else {
          this.onFrame(decodeFrame(event.data));
        }
      } catch (e) {
        this.onError(e);
      }
    };
    socket.onclose = () => {
      if (this.socket !== socket) return;
      this.socket = null;
      this.#scheduleRetry();
    };
    socket.onerror = () => {}; // onclose follows and handles the retry.
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
 * The WebSocket URL of the page's server (same host, /ws beside the page). A `?token=` of the
 * page goes along as `access_token` (a browser's WebSocket cannot send an Authorization
 * header; the server wants it under --token-reads).
 */
export function streamUrl() {
  const url = new URL('ws', window.location.href);
  url.protocol = url.protocol === 'https:' ? 'wss:' : 'ws:';
  const token = new URLSearchParams(window.location.search).get('token');
  if (token) url.searchParams.set('access_token', token);
  return url.href;
}

/** Error thrown by the REST helpers: carries the server's message and offending field. */
export class ApiError extends Error {
  constructor(status, message, field) {
    super(message);
    this.status = status;
    this.field = field;
  }
}

async function request(method, path, body) {
  const init = { method, headers: {} };
  if (body !== undefined) {
    init.headers['Content-Type'] = 'application/json';
    init.body = JSON.stringify(body);
  }
  const token = new URLSearchParams(window.location.search).get('token');
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

/** The REST API of docs/protocol.md, one function per route. Each returns the parsed JSON. */
export const api = {
  scenes: () => request('GET', 'scenes'),
  state: () => request('GET', 'state'),
  pause: () => request('POST', 'pause'),
  resume: () => request('POST', 'resume'),
  step: (steps) => request('POST', 'step', { steps }),
  reset: (scene) => request('POST', 'reset', scene ? { scene } : undefined),
  integrator: (integrator) => request('POST', 'integrator', { integrator }),
  /** impulse in N·s and point in metres, world frame. */
  impulse: (body, impulse, point) => request('POST', 'impulse', { body, impulse, point }),
};

/**
 * Polls GET /api/state every `everyMs` while `when()` is true, one request at a time; failures
 * are ignored (the stream's state already tells the user when the server is gone).
 */
export function pollState({ everyMs, when, onState }) {
  let busy = false;
  return setInterval(async () => {
    if (busy || !when()) return;
    busy = true;
    try {
      onState(await api.state());
    } catch {
      // next tick tries again
    } finally {
      busy = false;
    }
  }, everyMs);
}
