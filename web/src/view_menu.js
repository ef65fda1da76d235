// The panel's View folder: overlays (velocity arrows, trails), the body inspector and camera
// following, a PNG screenshot, a WebM recording, and loading a scene file.
import { CanvasRecorder, captureName, download, screenshot } from './capture.js';

export class ViewMenu {
  /**
   * @param {import('lil-gui').GUI} folder the panel's View folder
   * @param {{viewer, overlays, inspector, sceneDrop, hud, sceneName: () => string, simTime: () => number,
   *   subscribe: (what: string, on: boolean) => void}} parts
   */
  constructor(folder, { viewer, overlays, inspector, sceneDrop, hud, sceneName, simTime, subscribe }) {
    this.viewer = viewer;
    this.inspector = inspector;
    this.hud = hud;
    this.sceneName = sceneName;
    this.simTime = simTime;
    this.recorder = new CanvasRecorder(viewer.renderer.domElement);
    this.downloads = 0; // files offered for download (screenshots and recordings)
    this.params = {
      velocity: false,
      trails: false,
      contacts: false,
      inspect: false,
      screenshot: () => this.screenshot(),
      record: () => this.toggleRecording(),
      load: () => sceneDrop.choose(),
    };
    folder.add(this.params, 'velocity').name('velocity arrows').onChange((on) => overlays.setVelocity(on));
    folder.add(this.params, 'trails').name('trails').onChange((on) => overlays.setTrails(on));
    folder.add(this.params, 'contacts').name('contacts').onChange((on) => {
      overlays.setContacts(on);
      subscribe('contacts', on); // the server sends contact points only to viewers that ask
    });
    folder.add(this.params, 'inspect').name('click inspects');
    folder.add(this.params, 'screenshot').name('Screenshot (PNG)');
    this.recordButton = folder.add(this.params, 'record').name('Record (WebM)');
    if (!CanvasRecorder.supported()) this.recordButton.disable();
    folder.add(this.params, 'load').name('Load scene file…');
    folder.close();
  }

  /** True when a click on a body should inspect it rather than kick it. */
  get inspectOnClick() {
    return this.params.inspect;
  }

  /** Downloads a PNG of the view. */
  async screenshot() {
    try {
      const blob = await screenshot(this.viewer);
      download(blob, captureName(this.sceneName(), this.simTime(), 'png'));
      this.downloads++;
    } catch (e) {
      this.hud.toast(`screenshot: ${e.message}`);
    }
  }

  /** Starts a recording, or stops it and downloads the WebM. */
  async toggleRecording() {
    if (!this.recorder.recording) {
      try {
        this.recorder.start();
        this.recordButton.name('Stop recording');
        this.hud.toast('recording the view: press Stop recording to save it', 'info');
      } catch (e) {
        this.hud.toast(`recording: ${e.message}`);
      }
      return;
    }
    this.recordButton.name('Record (WebM)');
    const blob = await this.recorder.stop();
    download(blob, captureName(this.sceneName(), this.simTime(), 'webm'));
    this.downloads++;
  }
}
