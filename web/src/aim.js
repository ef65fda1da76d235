// The aimed kick: press on a box and drag to set the direction and size of the impulse, as
// MuJoCo's mouse perturbation does; an arrow shows it while aiming. The drag moves a point in
// the plane through the pressed point that faces the camera: the impulse points from the
// pressed point to it, and its length sets the size.
import * as THREE from 'three';

/** A drag of this many metres (arrow length) gives the panel's impulse; longer ones more. */
export const kAimMetresPerStrength = 1;
/** The aimed impulse is at most this many times the panel's. */
export const kAimMaxFactor = 10;
/** Shortest arrow that counts as aimed, m (shorter: the kick goes along the view ray). */
const kMinAimMetres = 0.05;
const kArrowColor = 0x7fd4ff;

export class KickAim {
  /** @param {import('./viewer.js').Viewer} viewer */
  constructor(viewer) {
    this.viewer = viewer;
    this.raycaster = new THREE.Raycaster();
    this.plane = new THREE.Plane();
    this.start = null;   // world point pressed, m
    this.end = null;     // world point under the pointer now, m
    this.body = -1;
    this.arrow = new THREE.ArrowHelper(new THREE.Vector3(1, 0, 0), new THREE.Vector3(), 1, kArrowColor);
    this.arrow.visible = false;
    // Drawn over the boxes so that an arrow into a box is still seen.
    for (const part of [this.arrow.line, this.arrow.cone]) {
      part.material.depthTest = false;
      part.material.transparent = true;
      part.renderOrder = 10;
    }
    // SwiftShader and some GPUs draw GL lines one pixel wide or not at all: a shaft of triangles.
    this.shaft = new THREE.Mesh(new THREE.CylinderGeometry(1, 1, 1, 8).translate(0, 0.5, 0),
      new THREE.MeshBasicMaterial({ color: kArrowColor, depthTest: false, transparent: true }));
    this.shaft.renderOrder = 10;
    this.arrow.add(this.shaft);
    viewer.scene.add(this.arrow);
  }

  /** Starts aiming from `hit` (viewer.pick's answer): body index and world point. */
  begin(hit) {
    this.body = hit.body;
    this.start = hit.point.clone();
    this.end = hit.point.clone();
    this.plane.setFromNormalAndCoplanarPoint(this.viewer.viewDirection(), this.start);
  }

  /** Moves the arrow's head under client point (x, y); returns the arrow's length in m. */
  update(x, y) {
    if (!this.start) return 0;
    const rect = this.viewer.renderer.domElement.getBoundingClientRect();
    const ndc = new THREE.Vector2(((x - rect.left) / rect.width) * 2 - 1, -((y - rect.top) / rect.height) * 2 + 1);
    this.raycaster.setFromCamera(ndc, this.viewer.camera);
    const point = this.raycaster.ray.intersectPlane(this.plane, new THREE.Vector3());
    if (!point) return this.length;
    this.end.copy(point);
    const d = this.end.clone().sub(this.start), length = d.length();
    this.arrow.visible = length >= kMinAimMetres;
    if (this.arrow.visible) {
      this.arrow.position.copy(this.start);
      this.arrow.setDirection(d.normalize());
      const head = Math.min(0.35 * length, 0.4);
      this.arrow.setLength(length, head, head * 0.5);
      const r = Math.max(0.012, head * 0.12);
      this.shaft.scale.set(r, Math.max(length - head, 1e-3), r);
    }
    return length;
  }

  /** Length of the arrow now, m. */
  get length() {
    return this.start ? this.end.distanceTo(this.start) : 0;
  }

  /**
   * Ends aiming. Returns {body, impulse: Vector3 (N·s), point: Vector3 (m)} for an arrow long
   * enough, else null; `strength` is the panel's impulse, N·s.
   */
  finish(strength) {
    const length = this.length;
    const result = length >= kMinAimMetres && this.start ? {
      body: this.body,
      point: this.start.clone(),
      impulse: this.end.clone().sub(this.start).normalize()
        .multiplyScalar(strength * Math.min(length / kAimMetresPerStrength, kAimMaxFactor)),
    } : null;
    this.cancel();
    return result;
  }

  /** Stops aiming without a kick. */
  cancel() {
    this.start = this.end = null;
    this.body = -1;
    this.arrow.visible = false;
  }
}
