// What the physics is doing, drawn from the pose frames' physics object (docs/protocol.md "Pose
// frames") while the session simulates: the ground plane, the ground's force at each contact as an
// arrow (1 mm per newton), the support polygon and the centre of pressure on the ground, the centre
// of mass with its projection on the ground, and a banner when the centre of mass leaves the
// support polygon ("Balance lost") or the figure has fallen and let go. Nothing of this is shown
// while posing is kinematic.

import * as THREE from 'three';
import { h } from './panel_util.js';

export const METRES_PER_NEWTON = 0.001;
const LOST_TEXT = 'Balance lost: the centre of mass is outside the support polygon';
const FALLEN_TEXT = 'Fallen: the figure has let go of its pins. Undo (Ctrl+Z) stands it up again';
const LIFT = 0.003; // drawn this far above the ground so it does not flicker with the grid
const COLORS = { plane: 0x4f7d62, arrow: 0x3fd0f0, polygon: 0x7ee081, cop: 0xff4d4d, com: 0xffd23f, lost: 0xff6b4a };

function overlay(material) {
  material.depthTest = false;
  material.transparent = true;
  return material;
}

function makeGroundMarks() {
  const plane = new THREE.Mesh(
    new THREE.PlaneGeometry(8, 8),
    new THREE.MeshBasicMaterial({ color: COLORS.plane, transparent: true, opacity: 0.3, depthWrite: false, side: THREE.DoubleSide }),
  );
  plane.rotation.x = -Math.PI / 2;
  plane.name = 'physics-ground';
  const polygonLine = new THREE.LineLoop(new THREE.BufferGeometry(), overlay(new THREE.LineBasicMaterial({ color: COLORS.polygon })));
  const polygonFill = new THREE.Mesh(
    new THREE.BufferGeometry(),
    overlay(new THREE.MeshBasicMaterial({ color: COLORS.polygon, opacity: 0.25, side: THREE.DoubleSide, depthWrite: false })),
  );
  const cop = new THREE.Mesh(new THREE.CircleGeometry(0.018, 24), overlay(new THREE.MeshBasicMaterial({ color: COLORS.cop, side: THREE.DoubleSide })));
  cop.rotation.x = -Math.PI / 2;
  const comGround = new THREE.Mesh(new THREE.RingGeometry(0.02, 0.03, 28), overlay(new THREE.MeshBasicMaterial({ color: COLORS.com, side: THREE.DoubleSide })));
  comGround.rotation.x = -Math.PI / 2;
  const com = new THREE.Mesh(new THREE.SphereGeometry(0.022, 16, 12), overlay(new THREE.MeshBasicMaterial({ color: COLORS.com })));
  const plumb = new THREE.Line(new THREE.BufferGeometry(), overlay(new THREE.LineDashedMaterial({ color: COLORS.com, dashSize: 0.03, gapSize: 0.02 })));
  for (const o of [polygonLine, polygonFill, cop, comGround, com, plumb]) {
    o.renderOrder = 12;
    o.frustumCulled = false;
  }
  return { plane, polygonLine, polygonFill, cop, comGround, com, plumb };
}

/** The support polygon (points on the ground) as a line loop and a triangle fan. */
function setPolygon(marks, polygon) {
  const pts = polygon.map((p) => new THREE.Vector3(p[0], p[1] + LIFT, p[2]));
  marks.polygonLine.geometry.setFromPoints(pts);
  const fan = [];
  for (let i = 1; i + 1 < pts.length; i++) fan.push(pts[0], pts[i], pts[i + 1]);
  marks.polygonFill.geometry.setFromPoints(fan);
  marks.polygonLine.visible = pts.length >= 2;
  marks.polygonFill.visible = pts.length >= 3;
}

export function createPhysicsView(state, viewport, stage) {
  const { signals } = state;
  const group = new THREE.Group();
  group.name = 'physics';
  group.visible = false;
  viewport.scene.add(group);
  const marks = makeGroundMarks();
  group.add(...Object.values(marks));
  const arrows = []; // a pool, grown as contacts appear
  const banner = h('div.physics-banner#balance-banner', { role: 'status', hidden: true }, LOST_TEXT);
  stage.append(banner);

  function arrow(i) {
    while (arrows.length <= i) {
      const a = new THREE.ArrowHelper(new THREE.Vector3(0, 1, 0), new THREE.Vector3(), 0.1, COLORS.arrow, 0.03, 0.018);
      a.line.material = overlay(a.line.material);
      a.cone.material = overlay(a.cone.material);
      a.renderOrder = 13;
      a.line.renderOrder = a.cone.renderOrder = 13;
      group.add(a);
      arrows.push(a);
    }
    return arrows[i];
  }

  function setContacts(contacts) {
    const dir = new THREE.Vector3();
    contacts.forEach((c, i) => {
      const a = arrow(i);
      dir.fromArray(c.force);
      const length = dir.length() * METRES_PER_NEWTON;
      a.visible = length > 1e-4;
      if (!a.visible) return;
      a.position.fromArray(c.point);
      a.setDirection(dir.normalize());
      a.setLength(length, Math.min(0.03, 0.4 * length), Math.min(0.018, 0.25 * length));
    });
    for (let i = contacts.length; i < arrows.length; i++) arrows[i].visible = false;
  }

  function show(physics) {
    group.visible = Boolean(physics);
    banner.hidden = !physics || (physics.balanced && !physics.fallen);
    if (physics) banner.textContent = physics.fallen ? FALLEN_TEXT : LOST_TEXT;
    if (!physics) return;
    setContacts(physics.contacts || []);
    setPolygon(marks, physics.support_polygon || []);
    marks.cop.visible = Boolean(physics.cop);
    if (physics.cop) marks.cop.position.set(physics.cop[0], physics.cop[1] + 2 * LIFT, physics.cop[2]);
    const [x, y, z] = physics.com;
    marks.com.position.set(x, y, z);
    marks.comGround.position.set(x, 2 * LIFT, z);
    marks.comGround.material.color.setHex(physics.balanced ? COLORS.com : COLORS.lost);
    marks.plumb.geometry.setFromPoints([new THREE.Vector3(x, y, z), new THREE.Vector3(x, LIFT, z)]);
    marks.plumb.computeLineDistances();
  }

  let shown = false;
  signals.poseChanged.add((pose) => {
    if (!pose.physics && !shown) return;
    shown = Boolean(pose.physics);
    show(pose.physics);
    signals.renderRequested.dispatch();
  });
  return { group, banner };
}
