// Decoding of the WebSocket messages described in docs/protocol.md (version 1).
// Pure functions: no DOM, no three.js.

/** Size of the fixed frame header, bytes. */
export const kHeaderBytes = 32;
/** Bytes per body in a frame: 8 vertices × 3 float32 + 1 activity byte. */
export const kBytesPerBody = 97;
/** Frame format version this viewer understands. */
export const kFrameVersion = 1;

/** Per-body activity codes of a frame. */
export const Activity = Object.freeze({ awake: 0, asleep: 1, frozen: 2 });

/** The 6 box faces used when a scene message carries none (same order as the server's). */
export const kDefaultFaces = [[0, 4, 6, 2], [1, 3, 7, 5], [0, 1, 5, 4], [2, 6, 7, 3], [0, 2, 3, 1], [4, 5, 7, 6]];

/**
 * Decodes a binary frame.
 * @param {ArrayBuffer} buffer
 * @returns {{paused: boolean, someFrozen: boolean, frame: number, count: number, time: number,
 *   energy: number, vertices: Float32Array, activity: Uint8Array}}
 *   `vertices` is a view into `buffer`: body-major, 8 vertices, x y z (metres, world frame).
 * @throws {Error} on a wrong magic, version or length.
 */
export function decodeFrame(buffer) {
  if (buffer.byteLength < kHeaderBytes) throw new Error(`frame too short: ${buffer.byteLength} bytes`);
  const view = new DataView(buffer);
  const magic = String.fromCharCode(view.getUint8(0), view.getUint8(1), view.getUint8(2), view.getUint8(3));
  if (magic !== 'TMBL') throw new Error(`bad frame magic ${JSON.stringify(magic)}`);
  const version = view.getUint16(4, true);
  if (version !== kFrameVersion) throw new Error(`unsupported frame version ${version}`);
  const flags = view.getUint16(6, true);
  const count = view.getUint32(12, true);
  const expected = kHeaderBytes + kBytesPerBody * count;
  if (buffer.byteLength !== expected) {
    throw new Error(`frame of ${count} bodies is ${buffer.byteLength} bytes, expected ${expected}`);
  }
  return {
    paused: (flags & 1) !== 0,
    someFrozen: (flags & 2) !== 0,
    frame: view.getUint32(8, true),
    count,
    time: view.getFloat64(16, true),
    energy: view.getFloat64(24, true),
    // Little-endian float32 view: every browser that runs WebGL is little-endian.
    vertices: new Float32Array(buffer, kHeaderBytes, count * 24),
    activity: new Uint8Array(buffer, kHeaderBytes + 96 * count, count),
  };
}

/**
 * Parses a text message. Only `{"type": "scene"}` is known; anything else returns null.
 * @param {string} text
 * @returns {null | {scene: object, faces: number[][], bodies: {name: string, size: number[], color: string}[]}}
 */
export function parseTextMessage(text) {
  const msg = JSON.parse(text);
  if (!msg || msg.type !== 'scene') return null;
  const scene = msg.scene ?? {};
  const bodies = Array.isArray(msg.bodies) ? msg.bodies
    : (scene.bodies ?? []).map((b) => ({ name: b.name, size: b.size, color: b.color }));
  const faces = Array.isArray(msg.faces) && msg.faces.length === 6 ? msg.faces : kDefaultFaces;
  return { scene, faces, bodies };
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
