// Dedicated worker that receives the /ws stream, decodes and applies every frame, acknowledges
// it, and keeps the newest state for the page (shared_state.js). Its event loop is its own, so
// a page whose main thread is busy still gets every frame applied at once and draws only the
// newest state when it can; the server's pace follows what this worker received.
//
// Messages from the page: {type: 'start', url}, {type: 'pull'} (only when not cross-origin
// isolated: asks for a copy of the state), {type: 'subscribe', what, on} (an opt-in stream such
// as contacts, kept across reconnects). To the page: {type: 'scene', message},
// {type: 'message', message} (contacts and other text messages),
// {type: 'status', message}, {type: 'connection', state, detail, connects},
// {type: 'buffers', buffers} (a new state, shared or copied), {type: 'error', message}.
import { StreamConnection } from './connection.js';
import { BodyStates } from './protocol.js';
import { StateWriter, allocateBuffers, copyBuffers } from './shared_state.js';

const shared = self.crossOriginIsolated === true && typeof SharedArrayBuffer === 'function';
const bodies = new BodyStates();
let writer = null;       // state of the current scene, made at its first keyframe
let needBuffers = true;  // a scene message came: its first keyframe gets new buffers
let sentSeq = -1;        // sequence of the copy last sent (copy mode)
let frames = 0;
let serverTime = 0;
let connection = null;

const wallNow = () => performance.timeOrigin + performance.now();

function counters(time) {
  if (!writer) return;
  if (time !== undefined) serverTime = time;
  writer.writeCounters({ bytes: connection.bytesReceived, frames, serverTime, at: wallNow() });
}

function applyFrame(frame) {
  if (!bodies.apply(frame)) return false;
  frames += 1;
  if (needBuffers) {
    needBuffers = false;
    writer = new StateWriter(allocateBuffers(bodies.count, shared), bodies.count);
    postMessage({ type: 'buffers', buffers: shared ? writer.buffers : copyBuffers(writer.buffers) });
  }
  writer.writeFrame(frame, bodies);
  counters(frame.time);
  return true;
}

function start(url) {
  connection = new StreamConnection(url, {
    onScene(message) {
      bodies.clear();
      needBuffers = true;
      postMessage({ type: 'scene', message });
    },
    onStatus(message) {
      if (Number.isFinite(message.time) && message.time > serverTime) counters(message.time);
      postMessage({ type: 'status', message });
    },
    onFrame: applyFrame,
    onMessage(message) {
      postMessage({ type: 'message', message });
    },
    onState(state, detail) {
      postMessage({ type: 'connection', state, detail, connects: connection.connects });
    },
    onError(error) {
      postMessage({ type: 'error', message: String(error?.message ?? error) });
    },
  });
  connection.start();
}

self.onmessage = ({ data }) => {
  if (data?.type === 'start') start(data.url);
  else if (data?.type === 'subscribe' && connection) connection.subscribe(data.what, data.on);
  else if (data?.type === 'pull' && writer && !shared) {
    counters();
    if (writer.seq === sentSeq) return;
    sentSeq = writer.seq;
    postMessage({ type: 'buffers', buffers: copyBuffers(writer.buffers), update: true });
  }
};
