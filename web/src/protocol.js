// Decoding of the WebSocket messages described in docs/protocol.md (version 2), and the
// viewer's copy of every body's pose that frames update. Pure: no DOM, no three.js.

/** Size of the fixed frame header, bytes. */
export const kHeaderBytes = 40;
/** Frame format version this viewer understands. */
export const kFrameVersion = 2;
/** Unit of a body's centre on the wire, m (2⁻¹⁶). */
export const kCentreUnit = 1 / 65536;
/** Header flag bits. */
export const Flags = Object.freeze({ paused: 1, someFrozen: 2, keyframe: 4, bitmap: 8 });

/** Per-body activity codes of a frame. */
export const Activity = Object.freeze({ awake: 0, asleep: 1, frozen: 2 });

/** The 6 box faces used when a scene message carries none (same order as the server's). */
export const kDefaultFaces = [[0, 4, 6, 2], [1, 3, 7, 5], [0, 1, 5, 4], [2, 6, 7, 3], [0, 2, 3, 1], [4, 5, 7, 6]];

/**
 * Decodes a binary frame (deltas not applied: see BodyStates).
 * @param {ArrayBuffer} buffer
 * @returns {{paused: boolean, someFrozen: boolean, keyframe: boolean, frame: number, base: number,
 *   count: number, time: number, energy: number, bodies: {index: number, activity: number,
 *   absolute: boolean, exponent: number, centre: number[], axes: number[]}[]}}
 * @throws {Error} on a wrong magic, version or length, or an index out of range.
 */
export function decodeFrame(buffer) {
  if (buffer.byteLength < kHeaderBytes) throw new Error(`frame too short: ${buffer.byteLength} bytes`);
  const view = new DataView(buffer);
  const magic = String.fromCharCode(view.getUint8(0), view.getUint8(1), view.getUint8(2), view.getUint8(3));
  if (magic !== 'TMBL') throw new Error(`bad frame magic ${JSON.stringify(magic)}`);
  const version = view.getUint16(4, true);
  if (version !== kFrameVersion) throw new Error(`unsupported frame version ${version}`);
  const flags = view.getUint16(6, true);
  const frame = {
    paused: (flags & Flags.paused) !== 0,
    someFrozen: (flags & Flags.someFrozen) !== 0,
    keyframe: (flags & Flags.keyframe) !== 0,
    frame: view.getUint32(8, true),
    base: view.getUint32(12, true),
    count: view.getUint32(16, true),
    time: view.getFloat64(24, true),
    energy: view.getFloat64(32, true),
    bodies: [],
  };
  const m = view.getUint32(20, true);
  if (m > frame.count || (frame.keyframe && m !== frame.count)) throw new Error(`frame carries ${m} of ${frame.count} bodies`);
  const reader = { view, at: kHeaderBytes };
  const indices = readSelection(reader, flags, frame.count, m);
  for (const index of indices) frame.bodies.push(readRecord(reader, index));
  if (reader.at !== buffer.byteLength) {
    throw new Error(`frame of ${m} records is ${buffer.byteLength} bytes, expected ${reader.at}`);
  }
  return frame;
}

function need(reader, bytes) {
  if (reader.at + bytes > reader.view.byteLength) throw new Error(`frame ends early at byte ${reader.at}, expected more`);
}

function readSelection(reader, flags, n, m) {
  if (flags & Flags.keyframe) return Array.from({ length: n }, (_, i) => i);
  const indices = [];
  if (flags & Flags.bitmap) {
    const bytes = Math.ceil(n / 8);
    need(reader, bytes);
    for (let byte = 0; byte < bytes; byte++) {
      const bits = reader.view.getUint8(reader.at + byte);
      for (let bit = 0; bit < 8; bit++) if (bits & (1 << bit)) indices.push(byte * 8 + bit);
    }
    reader.at += bytes;
  } else {
    need(reader, 4 * m);
    for (let k = 0; k < m; k++) indices.push(reader.view.getUint32(reader.at + 4 * k, true));
    reader.at += 4 * m;
  }
  if (indices.length !== m) throw new Error(`frame selects ${indices.length} bodies, expected ${m}`);
  indices.forEach((index, k) => {
    if (index >= n || (k > 0 && index <= indices[k - 1])) throw new Error(`bad body index ${index}`);
  });
  return indices;
}

function readRecord(reader, index) {
  need(reader, 1);
  const { view } = reader;
  const format = view.getUint8(reader.at++);
  const absolute = (format & 4) !== 0, wide = (format & 8) !== 0;
  const centreBytes = absolute ? 4 : 2, axisBytes = wide ? 4 : 2;
  need(reader, 3 * centreBytes + 9 * axisBytes);
  const read = (bytes) => {
    const value = bytes === 4 ? view.getInt32(reader.at, true) : view.getInt16(reader.at, true);
    reader.at += bytes;
    return value;
  };
  const centre = [read(centreBytes), read(centreBytes), read(centreBytes)];
  const axes = Array.from({ length: 9 }, () => read(axisBytes));
  return { index, activity: format & 3, absolute, exponent: (format >> 4) + 8, centre, axes };
}

/**
 * What the viewer holds of the stream: every body's quantised centre and vertices, built by
 * applying keyframes and deltas in order. `vertices` (m, body-major, vertex 0…7, x y z) and
 * `activity` always describe the newest frame applied; `dirty` marks the bodies changed since
 * the drawing code last cleared it.
 */
export class BodyStates {
  constructor() {
    this.count = 0;
    this.frame = null;       // number of the last frame applied
    this.time = 0;
    this.energy = 0;
    this.paused = false;
    this.centre = new Int32Array(0);
    this.vertices = new Float64Array(0);
    this.activity = new Uint8Array(0);
    this.dirty = new Uint8Array(0);
  }

  /** Forgets everything (a new scene): the next frame must be a keyframe. */
  clear() {
    this.frame = null;
  }

  /**
   * Applies a decoded frame. A delta must be relative to the last frame applied.
   * @returns {boolean} false (nothing changed) when the frame does not fit what is held.
   */
  apply(frame) {
    if (frame.keyframe) {
      if (frame.count !== this.count) this.#resize(frame.count);
      this.dirty.fill(1);
    } else if (this.frame === null || frame.base !== this.frame || frame.count !== this.count) {
      return false;
    }
    for (const body of frame.bodies) this.#applyBody(body);
    this.frame = frame.frame;
    this.time = frame.time;
    this.energy = frame.energy;
    this.paused = frame.paused;
    return true;
  }

  #resize(n) {
    this.count = n;
    this.centre = new Int32Array(3 * n);
    this.vertices = new Float64Array(24 * n);
    this.activity = new Uint8Array(n);
    this.dirty = new Uint8Array(n);
  }

  // Vertex i = centre ± a ± b ± d: additions of exact multiples of the units, no rotation.
  #applyBody({ index, activity, absolute, exponent, centre, axes }) {
    const c = this.centre, o = 3 * index;
    for (let k = 0; k < 3; k++) c[o + k] = absolute ? centre[k] : c[o + k] + centre[k];
    const unit = 2 ** -exponent, v = this.vertices;
    for (let i = 0; i < 8; i++) {
      const sa = i & 1 ? 1 : -1, sb = i & 2 ? 1 : -1, sd = i & 4 ? 1 : -1;
      for (let k = 0; k < 3; k++) {
        v[24 * index + 3 * i + k] = c[o + k] * kCentreUnit + (sa * axes[k] + sb * axes[3 + k] + sd * axes[6 + k]) * unit;
      }
    }
    this.activity[index] = activity;
    this.dirty[index] = 1;
  }
}

/**
 * Parses a text message: `{"type": "scene"}` gives the scene below, `{"type": "status"}` and
 * `{"type": "contacts"}` are returned as sent (with type); anything else returns null.
 * @param {string} text
 * @returns {null | {type: 'scene', scene: object, faces: number[][], bodies: {name: string, size: number[], color: string}[]}
 *   | {type: 'status', time: number, step: number, paused: boolean, real_time_factor: number,
 *      integrator: string, bodies: number, awake: number, asleep: number, frozen: number, dropped: number}}
 */
export function parseTextMessage(text) {
  const msg = JSON.parse(text);
  if (msg?.type === 'status' || msg?.type === 'contacts') return msg;
  if (!msg || msg.type !== 'scene') return null;
  const scene = msg.scene ?? {};
  const bodies = Array.isArray(msg.bodies) ? msg.bodies
    : (scene.bodies ?? []).map((b) => ({ name: b.name, size: b.size, color: b.color }));
  const faces = Array.isArray(msg.faces) && msg.faces.length === 6 ? msg.faces : kDefaultFaces;
  return { type: 'scene', scene, faces, bodies };
}

/**
 * The floor of a scene object: `{height}` or null when the scene has none.
 * A missing key means the engine's default floor at y = 0.
 */
export function sceneFloor(scene) {
  const holder = scene && 'floor' in scene ? scene : scene?.world;
  if (!holder || !('floor' in holder)) return { height: 0 };
  if (holder.floor === null) return null;
  return { height: Number(holder.floor.height ?? 0) };
}

/** The integrator named by a scene object, or '' when it names none. */
export function sceneIntegrator(scene) {
  return scene?.integrator ?? scene?.world?.integrator ?? '';
}

/** The scene's name, or '' when it has none. */
export function sceneName(scene) {
  return scene?.name ?? scene?.world?.name ?? '';
}
