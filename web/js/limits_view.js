// The selected joint's range, drawn at its pivot: a hinge's allowed arc (a sector about its axis
// with a needle at the current angle), or a spherical joint's allowed link directions (the range
// triangles mapped through the swing, as a cone with its rim, and the current direction). Green
// inside the range, red when the pose is outside it.

import * as THREE from 'three';
import { boundaryEdges, jointLimitStatus, qconj, qmul, qrotate, swingDirection } from './joint_ranges.js';

const OK = new THREE.Color(0x3ddc84);
const BAD = new THREE.Color(0xff3b30);
const SUBDIV = 6; // each range triangle is split into SUBDIV² pieces on the sphere

function linkLength(character, i) {
  // distance to the farthest child pivot, else the shapes' extent, else 15 cm
  let best = 0;
  character.links.forEach((l) => {
    if (l.parent === i && l.X_PJ) best = Math.max(best, Math.hypot(...l.X_PJ.p));
  });
  if (best > 0) return best;
  for (const s of character.links[i].shapes || []) {
    const p = s.p || [0, 0, 0];
    best = Math.max(best, Math.hypot(...p) * 2, (s.length || 0) + (s.radius || 0), s.size ? Math.max(...s.size) : 0);
  }
  return best > 0 ? best : 0.15;
}

/** A reference direction perpendicular to the hinge axis: towards the child bone at q = 0. */
function hingeReference(character, i, axis) {
  const a = new THREE.Vector3(...axis).normalize();
  const candidates = [];
  character.links.forEach((l) => {
    if (l.parent === i && l.X_PJ) candidates.push(new THREE.Vector3(...l.X_PJ.p));
  });
  for (const s of character.links[i].shapes || []) if (s.p) candidates.push(new THREE.Vector3(...s.p));
  candidates.push(new THREE.Vector3(0, -1, 0), new THREE.Vector3(0, 0, 1), new THREE.Vector3(1, 0, 0));
  for (const c of candidates) {
    const v = c.clone().sub(a.clone().multiplyScalar(c.dot(a)));
    if (v.length() > 1e-6) return v.normalize();
  }
  return new THREE.Vector3(1, 0, 0);
}

export function createLimitsView(state, viewport, skeleton) {
  const { signals } = state;
  const group = new THREE.Group();
  group.name = 'limits';
  viewport.scene.add(group);
  let current = null; // {link, kind, fillMat, lineMat, needle, ...}

  const fillMaterial = () =>
    new THREE.MeshBasicMaterial({ color: OK, transparent: true, opacity: 0.22, side: THREE.DoubleSide, depthWrite: false, depthTest: false });
  const lineMaterial = () => new THREE.LineBasicMaterial({ color: OK, depthTest: false, transparent: true, opacity: 0.95 });

  function clear() {
    group.traverse((o) => {
      if (o.geometry) o.geometry.dispose();
      if (o.material) o.material.dispose();
    });
    group.clear();
    current = null;
  }

  function buildHinge(i, link) {
    const len = Math.min(0.3, Math.max(0.08, linkLength(state.character, i) * 0.6));
    const axis = new THREE.Vector3(...link.axis).normalize();
    const ref = hingeReference(state.character, i, link.axis);
    const [lo, hi] = link.limits;
    const steps = Math.max(8, Math.ceil(((hi - lo) / Math.PI) * 48));
    const pts = [new THREE.Vector3()];
    const q = new THREE.Quaternion();
    for (let k = 0; k <= steps; k++) {
      q.setFromAxisAngle(axis, lo + ((hi - lo) * k) / steps);
      pts.push(ref.clone().applyQuaternion(q).multiplyScalar(len));
    }
    const idx = [];
    for (let k = 1; k <= steps; k++) idx.push(0, k, k + 1);
    const fillGeom = new THREE.BufferGeometry().setFromPoints(pts);
    fillGeom.setIndex(idx);
    const fillMat = fillMaterial();
    const fill = new THREE.Mesh(fillGeom, fillMat);
    const lineMat = lineMaterial();
    const outline = new THREE.LineLoop(new THREE.BufferGeometry().setFromPoints(pts), lineMat);
    const needleGeom = new THREE.BufferGeometry().setFromPoints([new THREE.Vector3(), ref.clone().multiplyScalar(len * 1.15)]);
    const needle = new THREE.Line(needleGeom, new THREE.LineBasicMaterial({ color: 0xffffff, depthTest: false }));
    const frame = new THREE.Group(); // the joint frame (parent side)
    frame.add(fill, outline);
    for (const o of [fill, outline, needle]) { o.renderOrder = 8; o.frustumCulled = false; }
    group.add(frame, needle);
    return { link: i, kind: 'hinge', frame, needle, fillMat, lineMat, ref, axis, len };
  }

  function buildCone(i, link) {
    const len = Math.min(0.3, Math.max(0.1, linkLength(state.character, i) * 0.55));
    const { vertices: V, triangles: T } = link.range;
    const dir = (ay, az) => new THREE.Vector3(...swingDirection(ay, az)).multiplyScalar(len);
    // the cap: every triangle subdivided and mapped through the swing onto the sphere of radius len
    const cap = [];
    for (const [a, b, c] of T) {
      const A = V[a], B = V[b], C = V[c];
      const at = (u, v) => {
        const w = 1 - u - v;
        return dir(w * A[0] + u * B[0] + v * C[0], w * A[1] + u * B[1] + v * C[1]);
      };
      for (let r = 0; r < SUBDIV; r++) {
        for (let s = 0; s < SUBDIV - r; s++) {
          const u0 = r / SUBDIV, v0 = s / SUBDIV, d = 1 / SUBDIV;
          cap.push(at(u0, v0), at(u0 + d, v0), at(u0, v0 + d));
          if (s < SUBDIV - r - 1) cap.push(at(u0 + d, v0), at(u0 + d, v0 + d), at(u0, v0 + d));
        }
      }
    }
    // the sides and the rim: apex -> each outline edge
    const side = [];
    const rim = [];
    for (const [a, b] of boundaryEdges(link.range)) {
      for (let k = 0; k < SUBDIV; k++) {
        const t0 = k / SUBDIV, t1 = (k + 1) / SUBDIV;
        const p0 = dir(V[a][0] + (V[b][0] - V[a][0]) * t0, V[a][1] + (V[b][1] - V[a][1]) * t0);
        const p1 = dir(V[a][0] + (V[b][0] - V[a][0]) * t1, V[a][1] + (V[b][1] - V[a][1]) * t1);
        side.push(new THREE.Vector3(), p0, p1);
        rim.push(p0, p1);
      }
    }
    const fillMat = fillMaterial();
    const capMesh = new THREE.Mesh(new THREE.BufferGeometry().setFromPoints(cap), fillMat);
    const sideMat = fillMaterial();
    sideMat.opacity = 0.12;
    const sideMesh = new THREE.Mesh(new THREE.BufferGeometry().setFromPoints(side), sideMat);
    const lineMat = lineMaterial();
    const rimLines = new THREE.LineSegments(new THREE.BufferGeometry().setFromPoints(rim), lineMat);
    const frame = new THREE.Group(); // the range frame (parent side)
    frame.add(capMesh, sideMesh, rimLines);
    const needle = new THREE.Line(
      new THREE.BufferGeometry().setFromPoints([new THREE.Vector3(), new THREE.Vector3(len * 1.2, 0, 0)]),
      new THREE.LineBasicMaterial({ color: 0xffffff, depthTest: false }),
    );
    for (const o of [capMesh, sideMesh, rimLines, needle]) { o.renderOrder = 8; o.frustumCulled = false; }
    group.add(frame, needle);
    return { link: i, kind: 'spherical', frame, needle, fillMat, sideMat, lineMat, len, F: link.range.frame || [1, 0, 0, 0] };
  }

  function rebuild() {
    clear();
    const i = state.selected;
    if (i < 0 || !state.character || !state.view.limits) {
      signals.renderRequested.dispatch();
      return;
    }
    const link = state.character.links[i];
    if (link.joint_type === 'revolute' && link.limits && link.axis) current = buildHinge(i, link);
    else if (link.joint_type === 'spherical' && link.range && (link.range.triangles || []).length) current = buildCone(i, link);
    update();
  }

  function update() {
    if (!current || !state.character) return;
    const i = current.link;
    const w = skeleton.linkWorld(i);
    if (!w) return;
    const qJoint = state.pose ? state.pose.links[i].q : [1, 0, 0, 0];
    const Rlink = [w.quaternion.w, w.quaternion.x, w.quaternion.y, w.quaternion.z];
    // parent-side joint frame: R_link · q_joint⁻¹
    const Rps = qmul(Rlink, qconj(qJoint));
    const status = jointLimitStatus(state.character.links[i], qJoint);
    const color = status.inside ? OK : BAD;
    current.fillMat.color.copy(color);
    current.lineMat.color.copy(color);
    if (current.sideMat) current.sideMat.color.copy(color);
    current.frame.position.copy(w.position);
    current.needle.position.copy(w.position);
    if (current.kind === 'hinge') {
      current.frame.quaternion.set(Rps[1], Rps[2], Rps[3], Rps[0]);
      // needle: the reference direction turned by the current angle, in the parent-side frame
      const q = new THREE.Quaternion().setFromAxisAngle(current.axis, status.angle);
      current.needle.quaternion.set(Rps[1], Rps[2], Rps[3], Rps[0]).multiply(q);
    } else {
      const Rf = qmul(Rps, current.F);
      current.frame.quaternion.set(Rf[1], Rf[2], Rf[3], Rf[0]);
      // needle: the link's nominal direction now, R_link · F · x
      const d = qrotate(qmul(Rlink, current.F), [1, 0, 0]);
      const len = current.len * 1.2;
      current.needle.quaternion.identity();
      current.needle.geometry.attributes.position.setXYZ(1, d[0] * len, d[1] * len, d[2] * len);
      current.needle.geometry.attributes.position.needsUpdate = true;
    }
    signals.renderRequested.dispatch();
  }

  signals.selectionChanged.add(rebuild);
  signals.characterLoaded.add(() => clear());
  signals.viewOptionsChanged.add(rebuild);
  signals.poseChanged.add(update);
  signals.sessionStateChanged.add(() => {
    if (!current && state.selected >= 0) rebuild();
    else update();
  });
}
