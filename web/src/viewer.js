// The three.js scene: boxes rebuilt from every frame's vertices, lights, shadows, floor, camera,
// orbit controls and picking. Knows nothing of the network.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { Activity, sceneFloor } from './protocol.js';

const kBackground = 0x16191f;
const kFrozenTint = new THREE.Color(0xff4d4d);
const kEdgeColor = new THREE.Color(0x0b0d10);
const kFrozenEdgeColor = new THREE.Color(0xff3030);
const kMaxShadowExtent = 60; // m: beyond this the shadow map would be too coarse to be useful.
const kShadowFitFrames = 25; // frames between two fits of the shadow map to the bodies.
const kMaxLabels = 16;
const kKickMs = 700; // lifetime of the kick arrow
/** Lowest the camera may look from: just above the horizontal plane through its target, rad. */
const kMaxPolarAngle = Math.PI / 2 - 0.03;
/** "Frame bodies" keeps bodies within this many robust standard deviations (1.4826 · MAD) of the median. */
const kFrameSigmas = 3;

// The 12 box edges as vertex-index pairs (vertex i: bit 0 → +x, bit 1 → +y, bit 2 → +z).
const kEdges = [[0, 1], [2, 3], [4, 5], [6, 7], [0, 2], [1, 3], [4, 6], [5, 7], [0, 4], [1, 5], [2, 6], [3, 7]];

const kFloorSize = 1000;    // m, edge of the square floor (it follows the camera's target)
const kGridTileMetres = 5; // one texture tile: 5 × 5 one-metre cells

/** A 5 m × 5 m floor tile: a line every metre, a stronger one on the tile's edge. */
function drawGridTile() {
  const px = 320, cell = px / kGridTileMetres;
  const canvas = document.createElement('canvas');
  canvas.width = canvas.height = px;
  const g = canvas.getContext('2d');
  g.fillStyle = '#2b3039';
  g.fillRect(0, 0, px, px);
  g.fillStyle = '#394050';
  for (let i = 1; i < kGridTileMetres; i++) {
    g.fillRect(i * cell - 1, 0, 2, px);
    g.fillRect(0, i * cell - 1, px, 2);
  }
  g.fillStyle = '#4a5366';
  g.fillRect(0, 0, 3, px);
  g.fillRect(0, 0, px, 3);
  return canvas;
}

/** True when WebGL runs on a CPU rasteriser (as in headless Chromium). */
function isSoftwareRenderer() {
  const gl = document.createElement('canvas').getContext('webgl2');
  if (!gl) return false;
  const info = gl.getExtension('WEBGL_debug_renderer_info');
  const name = String(gl.getParameter(info ? info.UNMASKED_RENDERER_WEBGL : gl.RENDERER));
  gl.getExtension('WEBGL_lose_context')?.loseContext();
  return /swiftshader|llvmpipe|softpipe|software/i.test(name);
}

/** Bounds of a scene's bodies at their initial poses (spheres around each centre), or null. */
function initialBounds(scene) {
  const box = new THREE.Box3();
  for (const body of scene?.bodies ?? []) {
    const p = body.position, size = body.size ?? [1, 1, 1];
    if (!Array.isArray(p) || !p.every(Number.isFinite)) continue;
    const r = 0.5 * Math.hypot(...size);
    box.expandByPoint(new THREE.Vector3(p[0] - r, p[1] - r, p[2] - r));
    box.expandByPoint(new THREE.Vector3(p[0] + r, p[1] + r, p[2] + r));
  }
  return box.isEmpty() ? null : box;
}

/** Colour of a body for its activity: asleep ones desaturated, frozen ones tinted red. */
function displayColor(base, activity, out) {
  out.copy(base);
  if (activity === Activity.asleep) {
    const hsl = {};
    out.getHSL(hsl, THREE.SRGBColorSpace); // perceptual HSL, so the hue stays put
    out.setHSL(hsl.h, hsl.s * 0.5, hsl.l * 0.9, THREE.SRGBColorSpace);
  } else if (activity === Activity.frozen) {
    out.lerp(kFrozenTint, 0.45);
  }
  return out;
}

export class Viewer {
  /** @param {HTMLElement} container the element the canvas fills. */
  constructor(container) {
    this.container = container;
    // A software rasteriser (SwiftShader, llvmpipe) pays for every pixel: no MSAA, one device
    // pixel per CSS pixel and a smaller shadow map there.
    this.software = isSoftwareRenderer();
    this.renderer = new THREE.WebGLRenderer({ antialias: !this.software, powerPreference: 'high-performance' });
    this.renderer.setPixelRatio(this.software ? 1 : Math.min(window.devicePixelRatio, 2));
    this.renderer.shadowMap.enabled = true;
    this.renderer.shadowMap.type = THREE.PCFShadowMap;
    container.appendChild(this.renderer.domElement);

    this.scene = new THREE.Scene();
    this.scene.background = new THREE.Color(kBackground);
    this.scene.fog = new THREE.Fog(kBackground, 40, 120);

    this.camera = new THREE.PerspectiveCamera(45, 1, 0.05, 2000);
    this.camera.position.set(6, 4.5, 8);
    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.controls.enableDamping = true;
    this.controls.dampingFactor = 0.08;
    this.controls.target.set(0, 1, 0);
    // The camera never goes under the floor: it stays above the horizontal plane through its
    // target, and render() keeps the target on or above the floor.
    this.controls.maxPolarAngle = kMaxPolarAngle;
    this.following = -1; // body the camera follows, or -1

    this.#addLights();
    this.floor = this.#makeFloor();
    this.scene.add(this.floor);

    this.boxes = null;  // THREE.Mesh of all boxes (one draw call)
    this.edges = null;  // THREE.LineSegments of all box edges
    this.bodyCount = 0;
    this.faces = [];
    this.baseColors = [];
    this.activity = new Uint8Array(0);
    this.hasPose = false;
    this.needsFit = true;
    this.framesSinceShadowFit = 0;
    this.labels = this.#makeLabels();
    this.raycaster = new THREE.Raycaster();
    this.kicks = [];

    window.addEventListener('resize', () => this.resize());
    this.resize();
  }

  #addLights() {
    this.scene.add(new THREE.HemisphereLight(0xdfe8ff, 0x40362e, 1.1));
    const sun = new THREE.DirectionalLight(0xfff6ea, 2.8);
    sun.castShadow = true;
    const mapSize = this.software ? 1024 : 2048;
    sun.shadow.mapSize.set(mapSize, mapSize);
    sun.shadow.radius = 4;
    sun.shadow.bias = -0.0004;
    sun.shadow.normalBias = 0.02;
    this.sunDirection = new THREE.Vector3(0.7, 1, 0.4).normalize();
    this.sun = sun;
    this.scene.add(sun, sun.target);
    this.#fitShadow(new THREE.Vector3(0, 1, 0), 6);
  }

  #makeFloor() {
    // The grid is a texture, not GL lines: software renderers (headless Chromium's SwiftShader)
    // draw no lines at all, and a texture also fades out properly at grazing angles.
    const texture = new THREE.CanvasTexture(drawGridTile());
    texture.wrapS = texture.wrapT = THREE.RepeatWrapping;
    texture.repeat.set(kFloorSize / kGridTileMetres, kFloorSize / kGridTileMetres);
    texture.anisotropy = this.renderer.capabilities.getMaxAnisotropy();
    texture.colorSpace = THREE.SRGBColorSpace;
    const plane = new THREE.Mesh(
      new THREE.PlaneGeometry(kFloorSize, kFloorSize),
      // Lambert: the floor covers most pixels, and a software renderer pays for every one.
      new THREE.MeshLambertMaterial({ map: texture }),
    );
    plane.rotation.x = -Math.PI / 2;
    plane.receiveShadow = true;
    return plane;
  }

  #makeLabels() {
    const labels = [];
    for (let i = 0; i < kMaxLabels; i++) {
      const el = document.createElement('div');
      el.className = 'body-label';
      el.hidden = true;
      this.container.appendChild(el);
      labels.push(el);
    }
    return labels;
  }

  /** Rebuilds all meshes for a scene message (docs/protocol.md "scene"). */
  setScene({ scene, faces, bodies }, { refit }) {
    const floor = sceneFloor(scene);
    this.floor.visible = floor !== null;
    if (floor) this.floor.position.y = floor.height;
    this.floorHeight = floor ? floor.height : null;

    if (this.boxes) {
      this.scene.remove(this.boxes, this.edges);
      this.boxes.geometry.dispose();
      this.edges.geometry.dispose();
    }
    const n = bodies.length;
    this.bodyCount = n;
    this.faces = faces;
    this.baseColors = bodies.map((b) => new THREE.Color(b.color ?? '#d9822b'));
    this.bodyNames = bodies.map((b, i) => b.name ?? `body ${i}`);
    this.bodySizes = bodies.map((b, i) => b.size ?? scene?.bodies?.[i]?.size ?? [1, 1, 1]);
    this.bodyMasses = (scene?.bodies ?? []).map((b) => b.mass ?? 1);
    this.following = -1;
    this.activity = new Uint8Array(n);
    this.hasPose = false;
    this.sceneBounds = initialBounds(scene);
    if (refit) this.needsFit = true;

    // Boxes: 6 faces × 4 corners each (flat normals), two triangles per face.
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array(n * 72), 3).setUsage(THREE.DynamicDrawUsage));
    geometry.setAttribute('normal', new THREE.BufferAttribute(new Float32Array(n * 72), 3).setUsage(THREE.DynamicDrawUsage));
    geometry.setAttribute('color', new THREE.BufferAttribute(new Float32Array(n * 72), 3));
    const index = new Uint32Array(n * 36);
    for (let q = 0; q < n * 6; q++) {
      const v = q * 4;
      index.set([v, v + 1, v + 2, v, v + 2, v + 3], q * 6);
    }
    geometry.setIndex(new THREE.BufferAttribute(index, 1));
    const material = new THREE.MeshStandardMaterial({ vertexColors: true, roughness: 0.55, metalness: 0.05 });
    this.boxes = new THREE.Mesh(geometry, material);
    this.boxes.castShadow = true;
    this.boxes.receiveShadow = true;
    this.boxes.frustumCulled = false;

    const edgeGeometry = new THREE.BufferGeometry();
    edgeGeometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array(n * 72), 3).setUsage(THREE.DynamicDrawUsage));
    edgeGeometry.setAttribute('color', new THREE.BufferAttribute(new Float32Array(n * 72), 3));
    this.edges = new THREE.LineSegments(edgeGeometry,
      new THREE.LineBasicMaterial({ vertexColors: true, transparent: true, opacity: 0.6 }));
    this.edges.frustumCulled = false;

    this.boxes.visible = this.edges.visible = false; // until the first frame gives a pose
    this.scene.add(this.boxes, this.edges);
    for (let i = 0; i < n; i++) this.#writeColors(i);
  }

  #writeColors(i) {
    const color = displayColor(this.baseColors[i], this.activity[i], new THREE.Color());
    const faceColors = this.boxes.geometry.attributes.color.array;
    for (let k = 0; k < 24; k++) color.toArray(faceColors, (i * 24 + k) * 3);
    const edge = this.activity[i] === Activity.frozen ? kFrozenEdgeColor : kEdgeColor;
    const edgeColors = this.edges.geometry.attributes.color.array;
    for (let k = 0; k < 24; k++) edge.toArray(edgeColors, (i * 24 + k) * 3);
  }

  /**
   * Shows the newest poses of `frame` (a BodyStates): vertex positions, flat normals and
   * activity colours of the bodies marked dirty, whose marks it clears.
   */
  applyFrame(frame) {
    if (!this.boxes || frame.count !== this.bodyCount) return false;
    const src = frame.vertices, dirty = frame.dirty;
    const pos = this.boxes.geometry.attributes.position.array;
    const nrm = this.boxes.geometry.attributes.normal.array;
    const edgePos = this.edges.geometry.attributes.position.array;
    let colorsChanged = false;
    for (let i = 0; i < frame.count; i++) {
      if (!dirty[i]) continue;
      dirty[i] = 0;
      const b = i * 24;
      for (let f = 0; f < 6; f++) {
        const quad = this.faces[f];
        const a = b + quad[0] * 3, c = b + quad[2] * 3;
        const bb = b + quad[1] * 3, d = b + quad[3] * 3;
        // Normal of a CCW quad a b c d: (c − a) × (d − b), normalised.
        const ux = src[c] - src[a], uy = src[c + 1] - src[a + 1], uz = src[c + 2] - src[a + 2];
        const vx = src[d] - src[bb], vy = src[d + 1] - src[bb + 1], vz = src[d + 2] - src[bb + 2];
        let nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
        const len = Math.hypot(nx, ny, nz) || 1;
        nx /= len; ny /= len; nz /= len;
        for (let k = 0; k < 4; k++) {
          const s = b + quad[k] * 3, o = (i * 24 + f * 4 + k) * 3;
          pos[o] = src[s]; pos[o + 1] = src[s + 1]; pos[o + 2] = src[s + 2];
          nrm[o] = nx; nrm[o + 1] = ny; nrm[o + 2] = nz;
        }
      }
      for (let e = 0; e < 12; e++) {
        for (let k = 0; k < 2; k++) {
          const s = b + kEdges[e][k] * 3, o = (i * 24 + e * 2 + k) * 3;
          edgePos[o] = src[s]; edgePos[o + 1] = src[s + 1]; edgePos[o + 2] = src[s + 2];
        }
      }
      if (frame.activity[i] !== this.activity[i]) {
        this.activity[i] = frame.activity[i];
        this.#writeColors(i);
        colorsChanged = true;
      }
    }
    const geometry = this.boxes.geometry;
    geometry.attributes.position.needsUpdate = true;
    geometry.attributes.normal.needsUpdate = true;
    geometry.boundingSphere = null;
    geometry.boundingBox = null;
    this.edges.geometry.attributes.position.needsUpdate = true;
    if (colorsChanged) {
      geometry.attributes.color.needsUpdate = true;
      this.edges.geometry.attributes.color.needsUpdate = true;
    }
    this.frameVertices = src;
    this.boxes.visible = this.edges.visible = true;
    this.hasPose = true;

    // The shadow map follows the bodies every kShadowFitFrames frames, and at once when the
    // camera is framed anew: a page must not show one shadow at load and another 25 frames on.
    if (this.needsFit) {
      this.#fitCamera();
      this.needsFit = false;
      this.framesSinceShadowFit = kShadowFitFrames;
    }
    if (++this.framesSinceShadowFit >= kShadowFitFrames) {
      this.framesSinceShadowFit = 0;
      const sphere = this.#bodiesSphere();
      if (sphere) this.#fitShadow(sphere.center, sphere.radius);
    }
    return true;
  }

  /** Bounding sphere of the bodies' current vertices (finite ones only), or null. */
  #bodiesSphere() {
    if (!this.hasPose) return null;
    const geometry = this.boxes.geometry;
    geometry.computeBoundingBox();
    const box = geometry.boundingBox;
    if (box.isEmpty() || !Number.isFinite(box.min.x + box.max.x + box.min.y + box.max.y)) return null;
    const sphere = box.getBoundingSphere(new THREE.Sphere());
    return sphere;
  }

  #fitShadow(center, radius) {
    const r = Math.min(Math.max(radius * 1.3 + 1, 4), kMaxShadowExtent);
    const cam = this.sun.shadow.camera;
    cam.left = -r; cam.right = r; cam.top = r; cam.bottom = -r;
    cam.near = 0.1; cam.far = 4 * r + 20;
    cam.updateProjectionMatrix();
    this.sun.target.position.copy(center);
    this.sun.position.copy(center).addScaledVector(this.sunDirection, 2 * r + 10);
  }

  /**
   * Bounds of the bulk of the bodies: those whose centre lies within kFrameSigmas robust
   * standard deviations (1.4826 × the median absolute deviation, per axis) of the median centre,
   * so one runaway body does not shrink the rest to a speck. Null before the first pose.
   */
  bulkBounds() {
    if (!this.hasPose || this.bodyCount === 0) return null;
    const n = this.bodyCount, centres = [];
    for (let i = 0; i < n; i++) {
      const c = this.bodyCentre(i);
      if (Number.isFinite(c.x + c.y + c.z)) centres.push([i, c]);
    }
    if (centres.length === 0) return null;
    const limits = ['x', 'y', 'z'].map((axis) => {
      const values = centres.map(([, c]) => c[axis]);
      const mid = median(values);
      const mad = median(values.map((v) => Math.abs(v - mid)));
      // A floor under the spread: bodies in a row (MAD 0 across it) are never cut.
      return { axis, mid, reach: Math.max(kFrameSigmas * 1.4826 * mad, 1) };
    });
    const box = new THREE.Box3(), v = this.frameVertices, p = new THREE.Vector3();
    for (const [i, c] of centres) {
      if (!limits.every(({ axis, mid, reach }) => Math.abs(c[axis] - mid) <= reach)) continue;
      for (let k = 0; k < 8; k++) box.expandByPoint(p.fromArray(v, i * 24 + k * 3));
    }
    return box.isEmpty() ? null : box;
  }

  /** Frames the bodies: the camera looks at the bulk's bounds from above and to the side. */
  #fitCamera() {
    const box = new THREE.Box3();
    const current = this.bulkBounds();
    if (current) box.copy(current);
    if (this.sceneBounds) box.union(this.sceneBounds);
    if (box.isEmpty()) return;
    if (this.floorHeight !== null) box.expandByPoint(new THREE.Vector3(box.min.x, this.floorHeight, box.min.z));
    const sphere = box.getBoundingSphere(new THREE.Sphere());
    const radius = Math.max(sphere.radius, 2);
    const halfFov = THREE.MathUtils.degToRad(this.camera.fov / 2);
    const fit = Math.min(halfFov, Math.atan(Math.tan(halfFov) * this.camera.aspect));
    const distance = (radius / Math.sin(fit)) * 1.25;
    // Aim a little below the centre: the overlays sit at the screen's corners and bottom.
    const target = sphere.center.clone();
    target.y -= radius * 0.12;
    const direction = new THREE.Vector3(0.62, 0.5, 0.95).normalize();
    this.camera.position.copy(target).addScaledVector(direction, distance);
    this.controls.target.copy(target);
    this.camera.near = Math.max(0.01, distance / 500);
    this.camera.far = distance * 50 + 200;
    this.camera.updateProjectionMatrix();
    // The fog hides the floor's edge: it ends before half the floor's size.
    this.scene.fog.far = Math.min(distance * 10 + 40, kFloorSize * 0.45);
    this.scene.fog.near = Math.min(distance * 3, this.scene.fog.far * 0.5);
    this.controls.update();
  }

  /** Re-centres the camera on the bodies' current poses at the next frame. */
  refit() {
    this.sceneBounds = null;
    this.needsFit = true;
  }

  /** Keeps body `i` at the centre of the view as it moves (-1 or null: stop following). */
  follow(i) {
    this.following = Number.isInteger(i) && i >= 0 && i < this.bodyCount ? i : -1;
  }

  /**
   * The body under a canvas point, with the world hit point and the view ray's direction.
   * @param {number} x client x, px  @param {number} y client y, px
   * @returns {null | {body: number, point: THREE.Vector3, direction: THREE.Vector3}}
   */
  pick(x, y) {
    if (!this.boxes || !this.hasPose) return null;
    const rect = this.renderer.domElement.getBoundingClientRect();
    const ndc = new THREE.Vector2(((x - rect.left) / rect.width) * 2 - 1, -((y - rect.top) / rect.height) * 2 + 1);
    this.raycaster.setFromCamera(ndc, this.camera);
    const hits = this.raycaster.intersectObject(this.boxes, false);
    if (hits.length === 0) return null;
    const hit = hits[0];
    return { body: Math.floor(hit.faceIndex / 12), point: hit.point.clone(), direction: this.raycaster.ray.direction.clone() };
  }

  /** Screen position (client px) of a body's centre, or null when it has no pose. */
  bodyScreenPosition(i) {
    if (!this.hasPose || i < 0 || i >= this.bodyCount) return null;
    const c = this.bodyCentre(i);
    c.project(this.camera);
    const rect = this.renderer.domElement.getBoundingClientRect();
    return { x: rect.left + ((c.x + 1) / 2) * rect.width, y: rect.top + ((1 - c.y) / 2) * rect.height, visible: c.z < 1 };
  }

  /** Client px of a world point (Vector3 or [x, y, z], m), with `visible` false behind the camera. */
  worldToScreen(point) {
    const c = (Array.isArray(point) ? new THREE.Vector3(...point) : point.clone()).project(this.camera);
    const rect = this.renderer.domElement.getBoundingClientRect();
    return { x: rect.left + ((c.x + 1) / 2) * rect.width, y: rect.top + ((1 - c.y) / 2) * rect.height, visible: c.z < 1 };
  }

  /** Unit vector the camera looks along (world frame). */
  viewDirection() {
    return this.camera.getWorldDirection(new THREE.Vector3());
  }

  /** Centre of body `i` as drawn (the mean of its 8 vertices), m. */
  bodyCentre(i) {
    const v = this.frameVertices, c = new THREE.Vector3();
    for (let k = 0; k < 8; k++) c.x += v[i * 24 + k * 3], c.y += v[i * 24 + k * 3 + 1], c.z += v[i * 24 + k * 3 + 2];
    return c.multiplyScalar(1 / 8);
  }

  #updateLabels() {
    let used = 0;
    if (this.hasPose) {
      for (let i = 0; i < this.bodyCount && used < kMaxLabels; i++) {
        if (this.activity[i] !== Activity.frozen) continue;
        const p = this.bodyScreenPosition(i);
        if (!p?.visible) continue;
        const el = this.labels[used++];
        el.textContent = `✖ frozen: ${this.bodyNames[i]}`;
        el.style.transform = `translate(${Math.round(p.x)}px, ${Math.round(p.y)}px) translate(-50%, -180%)`;
        el.hidden = false;
      }
    }
    for (let k = used; k < kMaxLabels; k++) this.labels[k].hidden = true;
  }

  /** Draws a short-lived arrow ending at `point` along `direction` (feedback for a kick). */
  showKick(point, direction) {
    const length = Math.max(0.6, this.camera.position.distanceTo(point) * 0.12);
    const from = point.clone().addScaledVector(direction, -length);
    const arrow = new THREE.ArrowHelper(direction, from, length, 0xfff2c0, length * 0.3, length * 0.15);
    arrow.line.material.transparent = arrow.cone.material.transparent = true;
    this.scene.add(arrow);
    this.kicks.push({ arrow, born: performance.now() });
  }

  #updateKicks(now) {
    this.kicks = this.kicks.filter(({ arrow, born }) => {
      const age = (now - born) / kKickMs;
      if (age >= 1) {
        this.scene.remove(arrow);
        arrow.dispose();
        return false;
      }
      arrow.line.material.opacity = arrow.cone.material.opacity = 1 - age;
      return true;
    });
  }

  /** Moves camera and target together by the followed body's displacement: the view keeps its angle. */
  #followBody() {
    if (this.following < 0 || !this.hasPose || this.following >= this.bodyCount) return;
    const c = this.bodyCentre(this.following);
    if (!Number.isFinite(c.x + c.y + c.z)) return;
    const delta = c.sub(this.controls.target);
    this.camera.position.add(delta);
    this.controls.target.add(delta);
  }

  /** A target panned under the floor is lifted back onto it (with the camera). */
  #keepAboveFloor() {
    if (this.floorHeight === null || this.floorHeight === undefined) return;
    const below = this.floorHeight - this.controls.target.y;
    if (below <= 0) return;
    this.controls.target.y += below;
    this.camera.position.y += below;
  }

  resize() {
    const w = this.container.clientWidth, h = this.container.clientHeight;
    this.camera.aspect = w / Math.max(h, 1);
    this.camera.updateProjectionMatrix();
    this.renderer.setSize(w, h);
  }

  render() {
    this.#followBody();
    this.#keepAboveFloor();
    this.controls.update();
    // Keep the (finite) floor under the view, moved by whole grid tiles so the grid stays put.
    const t = this.controls.target;
    this.floor.position.x = Math.round(t.x / kGridTileMetres) * kGridTileMetres;
    this.floor.position.z = Math.round(t.z / kGridTileMetres) * kGridTileMetres;
    this.#updateLabels();
    this.#updateKicks(performance.now());
    this.renderer.render(this.scene, this.camera);
  }
}

/** The median of a non-empty list of numbers. */
function median(values) {
  const sorted = Float64Array.from(values).sort();
  const mid = sorted.length >> 1;
  return sorted.length % 2 ? sorted[mid] : (sorted[mid - 1] + sorted[mid]) / 2;
}
