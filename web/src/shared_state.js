// The newest body state, written by the stream worker and read by the page once per animation
// frame. Backed by SharedArrayBuffers when the page is cross-origin isolated (the page then
// reads it without waiting for any message), else by ArrayBuffers that the worker copies to
// the page when it asks. A sequence counter (odd while the worker writes) detects torn reads.

/** Slots of the Int32 control block. */
const kSeq = 0, kCount = 1;
/** Slots of the Float64 header. */
const Header = Object.freeze({
  frame: 0,          // number of the newest frame applied
  time: 1,           // its sim time, s
  energy: 2,         // its energy, J
  paused: 3,         // 1 when that frame says paused
  serverTime: 4,     // newest sim time the worker has heard of (frame header or status), s
  receivedAt: 5,     // wall clock when serverTime came (performance.timeOrigin + now()), ms
  bytes: 6,          // message payload bytes received since the worker started
  frames: 7,         // binary frames received since the worker started
});
const kHeaderSlots = 8;

/** Allocates the buffers of a state for `count` bodies (shared when `shared`). */
export function allocateBuffers(count, shared) {
  const Buffer = shared ? SharedArrayBuffer : ArrayBuffer;
  return {
    control: new Buffer(8),
    header: new Buffer(8 * kHeaderSlots),
    vertices: new Buffer(8 * 24 * count),
    activity: new Buffer(count),
    stamps: new Buffer(4 * count),
  };
}

/** Typed views over a state's buffers (either side). */
function views(buffers) {
  return {
    control: new Int32Array(buffers.control),
    header: new Float64Array(buffers.header),
    vertices: new Float64Array(buffers.vertices),
    activity: new Uint8Array(buffers.activity),
    stamps: new Uint32Array(buffers.stamps),
  };
}

/** The worker's side: writes applied frames (from a BodyStates) and stream counters. */
export class StateWriter {
  /** @param {object} buffers from allocateBuffers; `count` bodies. */
  constructor(buffers, count) {
    this.buffers = buffers;
    this.v = views(buffers);
    this.v.control[kCount] = count;
    this.v.header[Header.frame] = -1;
    this.stamp = 0;
  }

  /** Copies the bodies `frame` carried from `states` (a BodyStates that applied it). */
  writeFrame(frame, states) {
    const { control, header, vertices, activity, stamps } = this.v;
    this.stamp += 1;
    Atomics.add(control, kSeq, 1); // odd: being written
    for (const { index } of frame.bodies) {
      vertices.set(states.vertices.subarray(24 * index, 24 * index + 24), 24 * index);
      activity[index] = states.activity[index];
      stamps[index] = this.stamp;
    }
    header[Header.frame] = frame.frame;
    header[Header.time] = frame.time;
    header[Header.energy] = frame.energy;
    header[Header.paused] = frame.paused ? 1 : 0;
    Atomics.add(control, kSeq, 1);
  }

  /** Records stream counters and the newest server sim time heard of (s, at wall ms `at`). */
  writeCounters({ bytes, frames, serverTime, at }) {
    const { header } = this.v;
    header[Header.bytes] = bytes;
    header[Header.frames] = frames;
    if (serverTime !== undefined) {
      header[Header.serverTime] = serverTime;
      header[Header.receivedAt] = at;
    }
  }

  /** Sequence number of the newest write. */
  get seq() {
    return Atomics.load(this.v.control, kSeq);
  }
}

/** A copy of a state's buffers (for a page that is not cross-origin isolated). */
export function copyBuffers(buffers) {
  const out = {};
  for (const [key, buffer] of Object.entries(buffers)) out[key] = buffer.slice(0);
  return out;
}

/**
 * The page's side: a BodyStates-like copy (count, frame, time, energy, paused, vertices,
 * activity, dirty) that `update` brings up to the shared state, copying only changed bodies.
 */
export class StateReader {
  /** @param {object} buffers the worker's buffers (shared, or a copy it sent) */
  constructor(buffers) {
    this.attach(buffers);
    this.count = this.v.control[kCount];
    this.frame = null;
    this.time = 0;
    this.energy = 0;
    this.paused = false;
    this.vertices = new Float64Array(24 * this.count);
    this.activity = new Uint8Array(this.count);
    this.dirty = new Uint8Array(this.count);
    this.stamps = new Uint32Array(this.count);
    this.seq = -1;
  }

  /** Reads from `buffers` from now on (a newer copy of the same state). */
  attach(buffers) {
    this.v = views(buffers);
  }

  /** Stream counters and the newest server time heard of: {bytes, frames, serverTime, receivedAt}. */
  counters() {
    const h = this.v.header;
    return { bytes: h[Header.bytes], frames: h[Header.frames], serverTime: h[Header.serverTime],
      receivedAt: h[Header.receivedAt] };
  }

  /** Copies what changed since the last update; true when a new, whole state was read. */
  update() {
    const { control, header, vertices, activity, stamps } = this.v;
    const seq = Atomics.load(control, kSeq);
    if (seq === this.seq || seq & 1 || header[Header.frame] < 0) return false;
    for (let i = 0; i < this.count; i++) {
      if (stamps[i] === this.stamps[i]) continue;
      this.vertices.set(vertices.subarray(24 * i, 24 * i + 24), 24 * i);
      this.activity[i] = activity[i];
      this.stamps[i] = stamps[i];
      this.dirty[i] = 1;
    }
    const frame = header[Header.frame], time = header[Header.time];
    const energy = header[Header.energy], paused = header[Header.paused] === 1;
    if (Atomics.load(control, kSeq) !== seq) {
      this.stamps.fill(0); // torn: copy every body again next time
      return false;
    }
    Object.assign(this, { seq, frame, time, energy, paused });
    return true;
  }
}
