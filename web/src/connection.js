// The page's two links to the server: the /ws stream (with automatic reconnect) and the REST API.
import { decodeFrame, parseTextMessage } from './protocol.js';

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
  constructor(url, { onScene, onStatus, onFrame, onState, onError }) {
    this.url = url;
    this.onScene = onScene;
    this.onStatus = onStatus;
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
