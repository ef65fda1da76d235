// Entry point: wires the stream to the viewer, HUD, energy plot and controls; runs the render loop.
import { Viewer } from './viewer.js';
import { api, streamUrl } from './connection.js';
import { StateReader } from './shared_state.js';
import { Hud } from './hud.js';
import { EnergyPlot } from './plot.js';
import { Controls } from './controls.js';
import { Overlays } from './overlays.js';
import { Inspector } from './inspector.js';
import { SceneDrop } from './scene_drop.js';
import { ViewMenu } from './view_menu.js';
import { SceneCaption } from './caption.js';
import { Timeline } from './timeline.js';
import { sceneIntegrator, sceneName } from './protocol.js';
import { adoptTokenFromFragment, currentWorld, isWorldId, worldToken, worldUrl } from './world.js';

/** Least time between two checks that the page's world still exists while the stream is down, ms. */
const kWorldCheckMs = 5000;

// A steer link's token is taken before anything reads tokens (and leaves the address bar).
adoptTokenFromFragment();
const world = currentWorld();

const viewer = createViewer();
const hud = new Hud(document.getElementById('hud'), document.getElementById('toasts'));
const plot = new EnergyPlot(document.getElementById('plot'), document.getElementById('energy'));
const controls = new Controls(viewer, hud);
const overlays = new Overlays(viewer);
const inspector = new Inspector(document.getElementById('inspector'), viewer);
const sceneDrop = new SceneDrop(document.getElementById('scene-error'), document.getElementById('drop-hint'), hud);
const caption = new SceneCaption(document.getElementById('description'));
const timeline = new Timeline(document.getElementById('timeline'), hud);
const viewMenu = new ViewMenu(controls.viewFolder, {
  viewer, overlays, inspector, sceneDrop, hud, sceneName: () => currentScene, simTime: () => drawnTime,
  subscribe: (what, on) => worker.postMessage({ type: 'subscribe', what, on }),
});
controls.onInspect = (i) => inspector.show(i);
controls.inspected = () => inspector.body;
controls.resume = () => (timeline.inPast ? api.play(timeline.speed) : api.resume());
controls.inspectOnClick = () => viewMenu.inspectOnClick;
inspector.onFollow = (i) => viewer.follow(i);
controls.extraShortcuts = { p: () => viewMenu.screenshot(), Escape: () => { inspector.show(-1); viewer.follow(-1); } };
hud.setWorld(world, worldToken(world) !== null);
document.getElementById('default-world').href = worldUrl(null); // other parameters (?token=) kept

function createViewer() {
  try {
    return new Viewer(document.getElementById('stage'));
  } catch (error) {
    document.getElementById('banner').textContent = `This viewer needs WebGL: ${error.message}`;
    throw error;
  }
}

let currentScene = null; // name of the scene the meshes were built for
let state = null;        // StateReader of the worker's newest state for this scene
let drawnFrame = null;   // number of the frame drawn last
let drawnTime = 0;       // its sim time, s
let framesDrawn = 0;
let connectionState = 'connecting';
let connects = 0;
let pulling = false;     // a copy of the state was asked for (page not cross-origin isolated)

// The stream lives in a worker: it applies every frame as it arrives, whatever this thread is
// doing, and the animation loop below draws only the newest state (shared_state.js).
const worker = new Worker(new URL('./stream_worker.js', import.meta.url), { type: 'module' });
const handlers = {
  scene({ message }) {
    const name = sceneName(message.scene);
    viewer.setScene(message, { refit: name !== currentScene });
    overlays.clear();
    inspector.show(-1);
    // A new scene (not a reset of the same one, nor a box added to it) shows its description.
    if (name !== currentScene) caption.show(message.scene?.description || sceneDrop.descriptionOf(name));
    currentScene = name;
    state = null;
    drawnFrame = null;
    plot.clear();
    hud.setScene(name, sceneIntegrator(message.scene));
    controls.setSceneName(name);
    controls.setIntegrator(sceneIntegrator(message.scene));
  },
  buffers({ buffers, update }) {
    pulling = false;
    if (update && state) state.attach(buffers);
    else if (!update) state = new StateReader(buffers);
  },
  status({ message }) {
    hud.setServerState(message);
    timeline.onStatus(message);
    controls.setSpeed(message.speed);
    if (message.integrator) controls.setIntegrator(message.integrator);
  },
  connection({ state: s, detail, connects: n }) {
    connectionState = s;
    connects = n;
    hud.setConnection(s, detail);
    if (s === 'open' && n > 1) controls.loadSceneList();
    if (s === 'open') hud.setMissingWorld(null);
    else checkWorld();
  },
  message({ message }) {
    if (message.type === 'contacts') overlays.showContacts(message);
  },
  error({ message }) {
    console.warn('tumble stream:', message);
  },
};
worker.onmessage = ({ data }) => handlers[data?.type]?.(data);
if (world === null || isWorldId(world)) worker.postMessage({ type: 'start', url: streamUrl() });
else hud.setMissingWorld(world);

let worldCheckedAt = -Infinity;
/**
 * Why ask: a socket to a world the server does not hold is refused with 404 before the upgrade,
 * and a browser's WebSocket reports every refusal alike. While the stream is down, GET
 * /api/worlds/{id} now and then tells a missing world (say so, offer the default) from a server
 * that is away (keep retrying).
 */
async function checkWorld() {
  const now = performance.now();
  if (world === null || now - worldCheckedAt < kWorldCheckMs) return;
  worldCheckedAt = now;
  try {
    await api.world(world);
    hud.setMissingWorld(null);
  } catch (e) {
    if (e.status === 404 || e.status === 400) hud.setMissingWorld(world);
  }
}

// A steer link pasted over the page's own address changes only the fragment: no reload.
window.addEventListener('hashchange', () => {
  if (!adoptTokenFromFragment()) return;
  hud.setWorld(world, true);
  hud.setNotice('');
  controls.worldMenu.updateSteer();
});

/** Draws the worker's newest state if it is newer than the one on screen. */
function drawNewest() {
  if (!state) return;
  hud.onCounters(state.counters());
  if (!state.update() || state.frame === drawnFrame || !viewer.applyFrame(state)) return;
  drawnFrame = state.frame;
  drawnTime = state.time;
  framesDrawn += 1;
  hud.onDrawn(state);
  plot.push(state.time, state.energy);
  overlays.update(state.time);
  timeline.onDrawn(state.time);
  controls.setPaused(state.paused);
}

function animate(now) {
  requestAnimationFrame(animate);
  drawNewest();
  if (state && !self.crossOriginIsolated && !pulling) {
    pulling = true;
    worker.postMessage({ type: 'pull' });
  }
  viewer.render();
  hud.onRender(now, drawnTime);
  plot.draw(now);
}

// A read-only window onto the page's state, for tests and the console.
window.tumble = Object.freeze({
  get simTime() { return hud.simTime; },
  get shownTime() { return drawnTime; },
  get lag() { return hud.lagAt(performance.now()); },
  get bytesPerSecond() { return hud.bytesPerSecond; },
  get bytesReceived() { return hud.bytesReceived; },
  get frames() { return hud.framesReceived; },
  get framesDrawn() { return framesDrawn; },
  get dropped() { return hud.dropped; },
  get connected() { return connectionState === 'open'; },
  get connectionState() { return connectionState; },
  get connects() { return connects; },
  get paused() { return hud.paused; },
  get scene() { return currentScene; },
  get bodies() { return viewer.bodyCount; },
  get world() { return world ?? 'default'; },
  get canSteer() { return worldToken(world) !== null; },
  get notice() { return hud.notice; },
  get worldMissing() { return !document.getElementById('no-world').hidden; },
  get description() { return caption.text; },
  get following() { return viewer.following; },
  get inspected() { return inspector.body; },
  get inspectedState() { return inspector.latest; },
  get lastKick() { return controls.lastKick; },
  get downloads() { return viewMenu.downloads; },
  get sceneError() { return sceneDrop.lastError; },
  get timeline() { return timeline.history && structuredClone(timeline.history); },
  get seeks() { return timeline.seeks; },
  get seeking() { return timeline.seeking !== null; },
  get timelineChanges() { return timeline.changes; },
  get boxesAdded() { return controls.addBox.added; },
  get addBoxError() { return controls.addBox.lastError; },
  get contacts() { return overlays.contacts && structuredClone(overlays.contacts); },
  get camera() { return { position: viewer.camera.position.toArray(), target: viewer.controls.target.toArray() }; },
  get viewDirection() { return viewer.viewDirection().toArray(); },
  /** The energy plot's newest axis ticks: {x, y}, each {values, step, labels}. */
  plotTicks: () => structuredClone(plot.ticks),
  bodyScreenPosition: (i) => viewer.bodyScreenPosition(i),
  worldToScreen: (p) => viewer.worldToScreen(p),
});

requestAnimationFrame(animate);
