// Pins in the 3D view: a marker at every pin target (with a line to the pinned point when the pin
// drifts; over a clip, where pins move with the motion, at the pinned point of the frame shown),
// and a TransformControls gizmo on the selected link's pin that moves its target (move_pin,
// latest-wins once per animation frame). Orbit is off while the gizmo is dragged.

import * as THREE from 'three';
import { TransformControls } from 'three/addons/controls/TransformControls.js';
import { msg } from './protocol.js';
import { pinOf, pinsMove } from './state.js';

const PIN_COLOR = 0xff9d1c;

function makeMarker() {
  const g = new THREE.Group();
  const mat = new THREE.MeshBasicMaterial({ color: PIN_COLOR, depthTest: false, transparent: true, opacity: 0.95 });
  const head = new THREE.Mesh(new THREE.SphereGeometry(0.016, 14, 10), mat);
  head.position.y = 0.075;
  const needle = new THREE.Mesh(new THREE.ConeGeometry(0.008, 0.06, 10), mat);
  needle.rotation.x = Math.PI; // point down onto the target
  needle.position.y = 0.035;
  const ring = new THREE.Mesh(
    new THREE.RingGeometry(0.022, 0.03, 28),
    new THREE.MeshBasicMaterial({ color: PIN_COLOR, depthTest: false, transparent: true, opacity: 0.7, side: THREE.DoubleSide }),
  );
  ring.rotation.x = -Math.PI / 2;
  for (const m of [head, needle, ring]) m.renderOrder = 11;
  g.add(head, needle, ring);
  const lineGeom = new THREE.BufferGeometry().setFromPoints([new THREE.Vector3(), new THREE.Vector3()]);
  const line = new THREE.Line(lineGeom, new THREE.LineBasicMaterial({ color: PIN_COLOR, depthTest: false }));
  line.renderOrder = 11;
  line.frustumCulled = false;
  return { group: g, line };
}

export function createPinsView(state, viewport, skeleton, connection) {
  const { signals } = state;
  const group = new THREE.Group();
  group.name = 'pins';
  viewport.scene.add(group);
  const markers = new Map(); // link name -> marker

  const proxy = new THREE.Object3D();
  proxy.name = 'pin-target';
  viewport.scene.add(proxy);
  const gizmo = new TransformControls(viewport.camera, viewport.renderer.domElement);
  gizmo.setSize(0.75);
  gizmo.setSpace('world');
  const helper = gizmo.getHelper();
  viewport.scene.add(helper);
  let gizmoPin = null; // the pin the gizmo edits
  let gizmoDragging = false;

  gizmo.addEventListener('dragging-changed', (e) => {
    gizmoDragging = e.value;
    viewport.controls.enabled = !e.value;
  });
  gizmo.addEventListener('change', () => signals.renderRequested.dispatch());
  gizmo.addEventListener('objectChange', () => {
    if (!gizmoPin || !gizmoDragging) return;
    const q = proxy.quaternion;
    const rotation = gizmoPin.mode === 'position' ? undefined : [q.w, q.x, q.y, q.z];
    connection.sendLatest(`pin:${gizmoPin.link}`, msg.movePin(gizmoPin.link, proxy.position.toArray(), rotation));
  });

  function syncGizmo() {
    const pin = pinOf(state, state.selected);
    // a moving pin (over a clip) has no fixed target to move
    if (!pin || !pin.target || pinsMove(state)) {
      gizmoPin = null;
      gizmo.detach();
      helper.visible = false;
      signals.renderRequested.dispatch();
      return;
    }
    gizmoPin = pin;
    if (!gizmoDragging) {
      proxy.position.fromArray(pin.target);
      if (pin.rotation) proxy.quaternion.set(pin.rotation[1], pin.rotation[2], pin.rotation[3], pin.rotation[0]);
      proxy.updateMatrixWorld();
    }
    if (gizmo.object !== proxy) gizmo.attach(proxy);
    const rotate = state.gizmoMode === 'rotate' && pin.mode !== 'position';
    gizmo.setMode(rotate ? 'rotate' : 'translate');
    helper.visible = true;
    signals.renderRequested.dispatch();
  }

  function syncMarkers() {
    const pins = state.session?.pins || [];
    const moving = pinsMove(state);
    const names = new Set(pins.map((p) => p.link));
    for (const [name, m] of markers) {
      if (!names.has(name)) {
        group.remove(m.group, m.line);
        markers.delete(name);
      }
    }
    for (const p of pins) {
      let m = markers.get(p.link);
      if (!m) {
        m = makeMarker();
        // drawn for a person-sized figure: as big a part of any other
        m.group.scale.setScalar(skeleton.figureScale());
        markers.set(p.link, m);
        group.add(m.group, m.line);
      }
      const i = state.linkIndex.get(p.link);
      const from = i !== undefined ? skeleton.linkPointWorld(i, p.point || [0, 0, 0]) : null;
      if (moving && from) {
        // over a clip a pin follows its link's motion: drawn where the link is at this frame
        m.group.position.copy(from);
        m.line.visible = false;
        continue;
      }
      if (p.target) m.group.position.fromArray(p.target);
      if (from && p.target) {
        const pos = m.line.geometry.attributes.position;
        pos.setXYZ(0, from.x, from.y, from.z);
        pos.setXYZ(1, p.target[0], p.target[1], p.target[2]);
        pos.needsUpdate = true;
        m.line.visible = from.distanceTo(m.group.position) > 0.002;
      }
    }
    signals.renderRequested.dispatch();
  }

  signals.sessionStateChanged.add(() => {
    syncMarkers();
    syncGizmo();
  });
  signals.poseChanged.add(() => {
    if (markers.size) syncMarkers();
  });
  signals.selectionChanged.add(syncGizmo);
  signals.gizmoModeChanged.add(syncGizmo);
  signals.characterLoaded.add(() => {
    for (const m of markers.values()) group.remove(m.group, m.line);
    markers.clear();
  });

  return {
    /** World position [x, y, z] of a link's pin marker as drawn now, or null. */
    markerPosition(link) {
      const m = markers.get(link);
      return m ? m.group.position.toArray() : null;
    },
    /** True when the pointer is over a gizmo handle (the press belongs to the gizmo). */
    wantsPointer: () => !!(gizmo.object && helper.visible && gizmo.axis !== null),
    /** The link whose pin the gizmo moves, or null. */
    get gizmoLink() {
      return gizmoPin ? gizmoPin.link : null;
    },
    get dragging() {
      return gizmoDragging;
    },
  };
}
