// Entry point: wires the stream to the viewer, HUD, energy plot and controls; runs the render loop.
import { Viewer } from './viewer.js';
import { StreamConnection, streamUrl } from './connection.js';
import { Hud } from './hud.js';
import { EnergyPlot } from './plot.js';
import { Controls } from './controls.js';
import { BodyStates, sceneIntegrator, sceneName } from './protocol.js';

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
const bodies = new BodyStates(); // every body's newest pose, updated by each frame on arrival
let drawnFrame = null;   // number of the frame drawn last
let drawnTime = 0;       // its sim time, s
let framesDrawn = 0;

const connection = new StreamConnection(streamUrl(), {
  onScene(message) {
    const name = sceneName(message.scene);
    viewer.setScene(message, { refit: name !== currentScene });
    currentScene = name;
    bodies.clear();
    drawnFrame = null;
    plot.clear();
    hud.setScene(name, sceneIntegrator(message.scene));
    controls.setSceneName(name);
    controls.setIntegrator(sceneIntegrator(message.scene));
  },
  onStatus(status) {
    hud.setServerState(status);
    if (status.integrator) controls.setIntegrator(status.integrator);
  },
  // Frames are applied as they arrive (cheap: only the bodies they carry); drawing takes
  // whatever is newest when the browser next paints, so nothing waits in a queue.
  onFrame(frame) {
    if (!bodies.apply(frame)) return false;
    hud.onFrame(frame, performance.now());
    plot.push(frame.time, frame.energy);
    controls.setPaused(frame.paused);
    return true;
  },
  onState(state, detail) {
    hud.setConnection(state, detail);
    if (state === 'open' && connection.connects > 1) controls.loadSceneList();
  },
  onError(error) {
    console.warn('tumble stream:', error);
  },
});

// A page whose animation frames come slower than the stream's 20 ms (a busy main thread)
// handles about one message per animation frame: every frame in flight is then one animation
// frame of lag, so it asks for one frame at a time; a page that keeps up allows four (room for
// the network's round trip).
let lastAnimate = 0;
let animateGapMs = 16;
connection.ackWindow = () => (animateGapMs > 40 ? 1 : 4);

function animate(now) {
  animateGapMs = 0.8 * animateGapMs + 0.2 * Math.min(1000, now - (lastAnimate || now));
  lastAnimate = now;
  requestAnimationFrame(animate);
  if (bodies.frame !== null && bodies.frame !== drawnFrame && viewer.applyFrame(bodies)) {
    drawnFrame = bodies.frame;
    drawnTime = bodies.time;
    framesDrawn += 1;
  }
  viewer.render();
  hud.onRender(now, drawnTime, connection.bytesReceived);
  plot.draw(now);
}

// A read-only window onto the page's state, for tests and the console.
window.tumble = Object.freeze({
  get simTime() { return hud.simTime; },
  get shownTime() { return drawnTime; },
  get lag() { return hud.lag; },
  get bytesPerSecond() { return hud.bytesPerSecond; },
  get bytesReceived() { return connection.bytesReceived; },
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
