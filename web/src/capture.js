// Pictures of the view: a PNG screenshot of the canvas, and a WebM recording of it
// (MediaRecorder on canvas.captureStream). Both download a file named for the scene and time.

/** Frames per second of a recording. */
const kRecordFps = 30;

/** Saves `blob` as a download named `name` (an <a download> clicked, its URL freed after). */
export function download(blob, name) {
  const url = URL.createObjectURL(blob);
  const a = document.createElement('a');
  a.href = url;
  a.download = name;
  a.style.display = 'none';
  document.body.appendChild(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(url), 10000);
}

/** A file name for a capture: `tumble-<scene>-<sim time>s.<ext>`. */
export function captureName(scene, simTime, ext) {
  const safe = String(scene || 'scene').replace(/[^a-z0-9_-]+/gi, '_');
  return `tumble-${safe}-${simTime.toFixed(2)}s.${ext}`;
}

/**
 * A PNG of the canvas as drawn now. Why render first: WebGL clears its drawing buffer after
 * each composite (no preserveDrawingBuffer, which costs every frame), so the picture is drawn
 * again and read in the same task.
 */
export function screenshot(viewer) {
  return new Promise((resolve, reject) => {
    viewer.render();
    viewer.renderer.domElement.toBlob((blob) => (blob ? resolve(blob) : reject(new Error('no PNG from the canvas'))), 'image/png');
  });
}

/** Records the canvas to WebM: start(), then stop() resolves with the video's Blob. */
export class CanvasRecorder {
  /** @param {HTMLCanvasElement} canvas */
  constructor(canvas) {
    this.canvas = canvas;
    this.recorder = null;
    this.chunks = [];
  }

  /** True while recording. */
  get recording() {
    return this.recorder?.state === 'recording';
  }

  /** Whether this browser can record a canvas to WebM. */
  static supported() {
    return typeof MediaRecorder === 'function' && typeof HTMLCanvasElement.prototype.captureStream === 'function'
      && ['video/webm;codecs=vp9', 'video/webm;codecs=vp8', 'video/webm'].some((t) => MediaRecorder.isTypeSupported(t));
  }

  /** Starts recording (VP9 when the browser has it, else VP8). */
  start() {
    const type = ['video/webm;codecs=vp9', 'video/webm;codecs=vp8', 'video/webm'].find((t) => MediaRecorder.isTypeSupported(t));
    this.chunks = [];
    this.recorder = new MediaRecorder(this.canvas.captureStream(kRecordFps), { mimeType: type });
    this.recorder.ondataavailable = (e) => { if (e.data.size) this.chunks.push(e.data); };
    this.recorder.start(250);
  }

  /** Stops recording; resolves with the WebM Blob. */
  stop() {
    const recorder = this.recorder;
    if (!recorder) return Promise.reject(new Error('not recording'));
    return new Promise((resolve) => {
      recorder.onstop = () => {
        recorder.stream.getTracks().forEach((t) => t.stop());
        this.recorder = null;
        resolve(new Blob(this.chunks, { type: 'video/webm' }));
      };
      recorder.stop();
    });
  }
}
