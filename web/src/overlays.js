// Overlays on the scene, toggled in the panel: velocity arrows (from the centres of successive
// drawn states), short trails, and contact points with their normals and impulses (from the
// stream's contacts messages, docs/protocol.md). Arrows and points are triangles (instanced
// cylinders, cones and spheres), so software renderers that draw no GL lines show them too.
import * as THREE from 'three';

/** Most bodies given an arrow (the fastest first), and a trail. */
const kMaxArrows = 512;
const kMaxTrails = 64;
/** Arrow length per speed, m per (m/s): an arrow shows where the body is in this many seconds. */
const kArrowSeconds = 0.25;
const kMaxArrowMetres = 5;
/** Slower bodies get no arrow, m/s. */
const kMinSpeed = 0.05;
/** Samples kept per trail (one per drawn state that moved). */
const kTrailSamples = 48;
const kArrowColor = 0x5ad1ff;
const kTrailColor = 0xffe08a;
/** Most contact points drawn. */
const kMaxContacts = 4096;
const kContactColor = 0xff3b6b;
/** Radius of a contact point's dot, m; a normal's length is kNormalMetres × impulse / the largest. */
const kContactRadius = 0.06;
const kNormalMetres = 0.8;

export class Overlays {
  /** @param {import('./viewer.js').Viewer} viewer */
  constructor(viewer) {
    this.viewer = viewer;
    this.velocityOn = false;
    this.trailsOn = false;
    this.previous = null; // {time, centres: Float64Array}
    this.velocities = new Float64Array(0); // m/s, 3 per body
    const material = new THREE.MeshBasicMaterial({ color: kArrowColor });
    this.shafts = new THREE.InstancedMesh(new THREE.CylinderGeometry(1, 1, 1, 6).translate(0, 0.5, 0), material, kMaxArrows);
    this.heads = new THREE.InstancedMesh(new THREE.ConeGeometry(1, 1, 8).translate(0, -0.5, 0), material, kMaxArrows);
    for (const mesh of [this.shafts, this.heads]) {
      mesh.count = 0;
      mesh.frustumCulled = false;
      mesh.visible = false;
      viewer.scene.add(mesh);
    }
    const trailGeometry = new THREE.BufferGeometry();
    trailGeometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array(6 * kMaxTrails * kTrailSamples), 3)
      .setUsage(THREE.DynamicDrawUsage));
    trailGeometry.setDrawRange(0, 0);
    this.trails = new THREE.LineSegments(trailGeometry,
      new THREE.LineBasicMaterial({ color: kTrailColor, transparent: true, opacity: 0.8 }));
    this.trails.frustumCulled = false;
    this.trails.visible = false;
    viewer.scene.add(this.trails);
    this.history = new Map(); // body → [x, y, z, …] newest last

    const contactMaterial = new THREE.MeshBasicMaterial({ color: kContactColor, depthTest: false, transparent: true });
    this.contactDots = new THREE.InstancedMesh(new THREE.SphereGeometry(1, 10, 6), contactMaterial, kMaxContacts);
    this.contactNormals = new THREE.InstancedMesh(new THREE.CylinderGeometry(1, 1, 1, 6).translate(0, 0.5, 0), contactMaterial, kMaxContacts);
    for (const mesh of [this.contactDots, this.contactNormals]) {
      mesh.count = 0;
      mesh.frustumCulled = false;
      mesh.visible = false;
      mesh.renderOrder = 5; // over the boxes: a contact is mostly inside or under one
      viewer.scene.add(mesh);
    }
    this.contactsOn = false;
    this.contacts = null; // the newest contacts message shown: {step, points}
  }

  /** Shows or hides the contact points (the page asks the stream for them only while shown). */
  setContacts(on) {
    this.contactsOn = on;
    this.contactDots.visible = this.contactNormals.visible = on;
    if (!on) this.contacts = null;
  }

  /**
   * Draws a contacts message: `points` as [x, y, z, nx, ny, nz, impulse] (m, unit normal, N·s):
   * a dot at each point and a normal whose length grows with the impulse (the largest of the
   * message gets kNormalMetres).
   */
  showContacts({ step, points }) {
    if (!this.contactsOn || !Array.isArray(points)) return;
    this.contacts = { step, points };
    const m = new THREE.Matrix4(), q = new THREE.Quaternion(), up = new THREE.Vector3(0, 1, 0);
    const at = new THREE.Vector3(), n = new THREE.Vector3(), s = new THREE.Vector3();
    const largest = Math.max(1e-12, ...points.map((p) => Math.abs(p[6] ?? 0)));
    let count = 0;
    for (const p of points) {
      if (count >= kMaxContacts || p.length < 6 || !p.every(Number.isFinite)) continue;
      at.set(p[0], p[1], p[2]);
      this.contactDots.setMatrixAt(count, m.compose(at, q.identity(), s.setScalar(kContactRadius)));
      n.set(p[3], p[4], p[5]);
      if (n.lengthSq() > 0) n.normalize(); else n.copy(up);
      q.setFromUnitVectors(up, n);
      const length = Math.max(0.05, (kNormalMetres * Math.abs(p[6] ?? 0)) / largest);
      this.contactNormals.setMatrixAt(count, m.compose(at, q, s.set(0.015, length, 0.015)));
      count++;
    }
    this.contactDots.count = this.contactNormals.count = count;
    this.contactDots.instanceMatrix.needsUpdate = this.contactNormals.instanceMatrix.needsUpdate = true;
  }

  /** Forgets what was measured (a new scene). */
  clear() {
    this.previous = null;
    this.velocities = new Float64Array(0);
    this.history.clear();
    this.shafts.count = this.heads.count = 0;
    this.trails.geometry.setDrawRange(0, 0);
    this.contactDots.count = this.contactNormals.count = 0;
    this.contacts = null;
  }

  /** Shows or hides the velocity arrows. */
  setVelocity(on) {
    this.velocityOn = on;
    this.shafts.visible = this.heads.visible = on;
  }

  /** Shows or hides the trails. */
  setTrails(on) {
    this.trailsOn = on;
    this.trails.visible = on;
    if (!on) this.history.clear();
  }

  /** Velocity of body `i` measured from the drawn states, m/s (a Vector3), or null. */
  velocity(i) {
    if (3 * i + 2 >= this.velocities.length) return null;
    return new THREE.Vector3().fromArray(this.velocities, 3 * i);
  }

  /** Takes the newly drawn state (sim time `time`, s): measures velocities, extends trails. */
  update(time) {
    const viewer = this.viewer, n = viewer.bodyCount;
    if (!viewer.hasPose || (!this.velocityOn && !this.trailsOn)) { this.previous = null; return; }
    const centres = new Float64Array(3 * n);
    for (let i = 0; i < n; i++) viewer.bodyCentre(i).toArray(centres, 3 * i);
    const prev = this.previous;
    if (prev && prev.centres.length === centres.length && time > prev.time) {
      const dt = time - prev.time;
      if (this.velocities.length !== centres.length) this.velocities = new Float64Array(centres.length);
      for (let k = 0; k < centres.length; k++) this.velocities[k] = (centres[k] - prev.centres[k]) / dt;
    } else if (prev && time < prev.time) {
      this.history.clear(); // time ran backwards: a reset or a seek
    }
    if (!prev || time !== prev.time) this.previous = { time, centres };
    if (this.velocityOn) this.#drawArrows(centres);
    if (this.trailsOn) this.#drawTrails(centres);
  }

  #drawArrows(centres) {
    const v = this.velocities, n = Math.min(v.length, centres.length) / 3;
    const moving = [];
    for (let i = 0; i < n; i++) {
      const speed = Math.hypot(v[3 * i], v[3 * i + 1], v[3 * i + 2]);
      if (speed >= kMinSpeed && Number.isFinite(speed)) moving.push([speed, i]);
    }
    moving.sort((a, b) => b[0] - a[0]);
    const m = new THREE.Matrix4(), q = new THREE.Quaternion(), up = new THREE.Vector3(0, 1, 0);
    const dir = new THREE.Vector3(), at = new THREE.Vector3(), tip = new THREE.Vector3(), s = new THREE.Vector3();
    let count = 0;
    for (const [speed, i] of moving.slice(0, kMaxArrows)) {
      const length = Math.min(speed * kArrowSeconds, kMaxArrowMetres);
      const size = this.viewer.bodySizes[i] ?? [1, 1, 1];
      const r = Math.max(0.01, 0.04 * Math.min(...size));
      const head = Math.min(length * 0.35, 6 * r);
      dir.fromArray(v, 3 * i).normalize();
      q.setFromUnitVectors(up, dir);
      at.fromArray(centres, 3 * i);
      this.shafts.setMatrixAt(count, m.compose(at, q, s.set(r, Math.max(length - head, 1e-3), r)));
      tip.copy(at).addScaledVector(dir, length);
      this.heads.setMatrixAt(count, m.compose(tip, q, s.set(2.2 * r, head, 2.2 * r)));
      count++;
    }
    this.shafts.count = this.heads.count = count;
    this.shafts.instanceMatrix.needsUpdate = this.heads.instanceMatrix.needsUpdate = true;
  }

  #drawTrails(centres) {
    const v = this.velocities, n = centres.length / 3;
    // The trails follow the fastest bodies (and keep those that have one while they move).
    const speeds = [];
    for (let i = 0; i < n; i++) speeds.push([Math.hypot(v[3 * i] ?? 0, v[3 * i + 1] ?? 0, v[3 * i + 2] ?? 0), i]);
    speeds.sort((a, b) => b[0] - a[0]);
    const keep = new Set(speeds.slice(0, kMaxTrails).filter(([s]) => s >= kMinSpeed).map(([, i]) => i));
    for (const i of this.history.keys()) if (!keep.has(i)) this.history.delete(i);
    for (const i of keep) {
      const samples = this.history.get(i) ?? [];
      samples.push(centres[3 * i], centres[3 * i + 1], centres[3 * i + 2]);
      if (samples.length > 3 * kTrailSamples) samples.splice(0, samples.length - 3 * kTrailSamples);
      this.history.set(i, samples);
    }
    const attribute = this.trails.geometry.attributes.position, positions = attribute.array;
    let o = 0;
    for (const samples of this.history.values()) {
      for (let k = 3; k < samples.length && o + 6 <= positions.length; k += 3) {
        for (let j = 0; j < 6; j++) positions[o + j] = samples[k - 3 + j];
        o += 6;
      }
    }
    attribute.needsUpdate = true;
    this.trails.geometry.setDrawRange(0, o / 3);
  }
}
