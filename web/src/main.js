// Entry point: wires the stream to the viewer, HUD, energy plot and controls; runs the render loop.
import { Viewer } from './viewer.js';
import { StreamConnection, pollState, streamUrl } from './connection.js';
import { Hud } from './hud.js';
import { EnergyPlot } from './plot.js';
import { Controls } from './controls.js';
import { sceneIntegrator, sceneName } from './protocol.js';

const viewer = createViewer();
const hud = new Hud(document.getElementById('hud'), document.getElementById('toasts'));
const plot = new EnergyPlot(document.getElementById('plot'), document.getElementById('energy'));
const controls = new Controls(viewer, hud);

function createViewer() {
  try {
    return new Viewer(document.getElementById('stage'));
  } catch (error) {
    document.getElementById('banner').textContent = `This viewer needs WebGL: ${error.message}`;
    throw error;
  }
}

let currentScene = null; // name of the scene the meshes were built for
let latestFrame = null;  // newest frame not drawn yet (older ones are simply superseded)
let framesDrawn = 0;

const connection = new StreamConnection(streamUrl(), {
  onScene(message) {
    const name = sceneName(message.scene);
    viewer.setScene(message, { refit: name !== currentScene });
    currentScene = name;
    latestFrame = null;
    plot.clear();
    hud.setScene(name, sceneIntegrator(message.scene));
    controls.setSceneName(name);
    controls.setIntegrator(sceneIntegrator(message.scene));
  },
  onFrame(frame) {
    hud.onFrame(frame, performance.now());
    plot.push(frame.time, frame.energy);
    controls.setPaused(frame.paused);
    latestFrame = frame;
  },
  onState(state, detail) {
    hud.setConnection(state, detail);
    if (state === 'open' && connection.connects > 1) controls.loadSceneList();
  },
  onError(error) {
    console.warn('tumble stream:', error);
  },
});

// The server's real-time factor and integrator, twice a second. /api/state lists every body, so
// large scenes skip it and the HUD measures the real-time factor from the frames instead.
const kMaxPolledBodies = 2000;
pollState({
  everyMs: 500,
  when: () => connection.state === 'open' && !document.hidden && viewer.bodyCount <= kMaxPolledBodies,
  onState(state) {
    hud.setServerState(state);
    controls.setIntegrator(state.integrator);
  },
});

function animate(now) {
  requestAnimationFrame(animate);
  if (latestFrame && viewer.applyFrame(latestFrame)) framesDrawn += 1;
  latestFrame = null;
  viewer.render();
  hud.onRender(now);
  plot.draw(now);
}

// A read-only window onto the page's state, for tests and the console.
window.tumble = Object.freeze({
  get simTime() { return hud.simTime; },
  get frames() { return hud.framesReceived; },
  get framesDrawn() { return framesDrawn; },
  get dropped() { return hud.dropped; },
  get connected() { return connection.state === 'open'; },
  get connectionState() { return connection.state; },
  get connects() { return connection.connects; },
  get paused() { return hud.paused; },
  get scene() { return currentScene; },
  get bodies() { return viewer.bodyCount; },
  bodyScreenPosition: (i) => viewer.bodyScreenPosition(i),
});

connection.start();
requestAnimationFrame(animate);
