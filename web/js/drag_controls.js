// Picking and dragging links. A pointer press on a joint handle (screen-space, nearest within a
// few pixels) or on the body (raycast) grabs that link at that point; the target then moves on the
// camera-facing plane through the grabbed point (constant depth). Orbit is off for the whole
// gesture, and the press never reaches the orbit controls. A press that does not move is a click
// (select). Right-click toggles a pin. A gesture on a playing clip may slow or pause it until the
// release (the view option "while dragging"). The ghost (sphere and spring) shows the target until
// the server's pose acknowledges it.

import * as THREE from 'three';
import { msg } from './protocol.js';

const HANDLE_PICK_PX = 12;
// while a clip plays the handles move under the pointer: they are picked from further away, and a
// press near the figure that grabs nothing is swallowed instead of starting an orbit
const MOVING_HANDLE_PICK_PX = 28;
const MOVING_MISS_GUARD_PX = 90;
// "slow while dragging": the clip plays at this fraction of its speed while a link is held
const SLOW_WHILE_DRAGGING = 0.25;
const DRAG_THRESHOLD_PX = 3;

export function createDragControls(state, viewport, skeleton, connection, actions, pins) {
  const { signals } = state;
  const canvas = viewport.renderer.domElement;
  const raycaster = new THREE.Raycaster();
  const ndc = new THREE.Vector2();
  const plane = new THREE.Plane();
  const hitPoint = new THREE.Vector3();
  const camDir = new THREE.Vector3();

  // ghost: where the target is, and a spring from the grabbed point to it
  const ghost = new THREE.Group();
  ghost.name = 'drag-ghost';
  const ghostBall = new THREE.Mesh(
    new THREE.SphereGeometry(0.022, 16, 12),
    new THREE.MeshBasicMaterial({ color: 0x4fd1ff, transparent: true, opacity: 0.55, depthTest: false }),
  );
  ghostBall.renderOrder = 12;
  const ghostRing = new THREE.Mesh(
    new THREE.RingGeometry(0.03, 0.036, 32),
    new THREE.MeshBasicMaterial({ color: 0x4fd1ff, transparent: true, opacity: 0.8, depthTest: false, side: THREE.DoubleSide }),
  );
  ghostRing.renderOrder = 12;
  const springGeom = new THREE.BufferGeometry().setFromPoints([new THREE.Vector3(), new THREE.Vector3()]);
  const spring = new THREE.Line(
    springGeom,
    new THREE.LineDashedMaterial({ color: 0x4fd1ff, dashSize: 0.015, gapSize: 0.01, depthTest: false, transparent: true }),
  );
  spring.renderOrder = 12;
  spring.frustumCulled = false;
  ghost.add(ghostBall, ghostRing, spring);
  ghost.visible = false;
  viewport.scene.add(ghost);

  let press = null; // {link, grabWorld, pointLink, x, y, pointerId, started}
  let ghostTarget = null;
  let ghostLink = -1;
  let ghostPoint = null;
  let awaitingAck = false;
  let emptyPress = null;

  const playing = () => state.session?.playback?.playing === true;

  /** Screen distance (px) from the event to the nearest visible handle. */
  function nearestHandlePx(event) {
    let nearest = Infinity;
    for (const p of skeleton.handlePositions()) {
      const s = viewport.toClient(p);
      if (s.visible) nearest = Math.min(nearest, Math.hypot(s.x - event.clientX, s.y - event.clientY));
    }
    return nearest;
  }

  function pick(event) {
    // 1. handles, in screen space: the nearest within the pick radius, ties broken towards the
    // camera. The handles are where the figure is drawn, so a moving one is picked where it is seen.
    const radius = playing() ? MOVING_HANDLE_PICK_PX : HANDLE_PICK_PX;
    if (state.view.handles) {
      let best = -1;
      let bestD = radius;
      let bestDepth = Infinity;
      const positions = skeleton.handlePositions();
      for (let i = 0; i < positions.length; i++) {
        const s = viewport.toClient(positions[i]);
        if (!s.visible) continue;
        const d = Math.hypot(s.x - event.clientX, s.y - event.clientY);
        const depth = positions[i].distanceTo(viewport.camera.position);
        if (d < bestD - 2 || (d < radius && Math.abs(d - bestD) <= 2 && depth < bestDepth)) {
          best = i;
          bestD = d;
          bestDepth = depth;
        }
      }
      if (best >= 0) return { link: best, point: positions[best].clone(), handle: true };
    }
    // 2. the body
    raycaster.setFromCamera(viewport.toNdc(event, ndc), viewport.camera);
    const hits = raycaster.intersectObjects(skeleton.pickables, false);
    if (hits.length) return { link: hits[0].object.userData.link, point: hits[0].point.clone(), handle: false };
    return null;
  }

  function setHover(link) {
    if (link !== state.hover) signals.hoverChanged.dispatch(link);
    canvas.style.cursor = press && press.started ? 'grabbing' : link >= 0 ? 'grab' : '';
  }

  function targetAt(event, out) {
    raycaster.setFromCamera(viewport.toNdc(event, ndc), viewport.camera);
    return raycaster.ray.intersectPlane(plane, out);
  }

  function updateGhost() {
    if (!ghostTarget || ghostLink < 0) {
      ghost.visible = false;
      return;
    }
    ghost.visible = true;
    ghostBall.position.copy(ghostTarget);
    ghostRing.position.copy(ghostTarget);
    ghostRing.quaternion.copy(viewport.camera.quaternion);
    const from = skeleton.linkPointWorld(ghostLink, ghostPoint);
    if (from) {
      const pos = springGeom.attributes.position;
      pos.setXYZ(0, from.x, from.y, from.z);
      pos.setXYZ(1, ghostTarget.x, ghostTarget.y, ghostTarget.z);
      pos.needsUpdate = true;
      spring.computeLineDistances();
    }
    const acked = !awaitingAck;
    ghostBall.material.opacity = acked ? 0.3 : 0.6;
    signals.renderRequested.dispatch();
  }

  /** Slows or pauses a playing clip for the gesture (view option "while dragging"); returns the
   *  messages that restore it after the drag ends. */
  function adjustPlayback() {
    const pb = state.session?.playback;
    if (!state.session?.clip || !pb?.playing) return [];
    if (state.view.whileDragging === 'pause') {
      connection.send(msg.pause()); // the drag then edits the frame shown, kept as a layer
      return [msg.play()];
    }
    if (state.view.whileDragging === 'slow') {
      connection.send(msg.setSpeed(pb.speed * SLOW_WHILE_DRAGGING));
      return [msg.setSpeed(pb.speed)];
    }
    return [];
  }

  function beginServerDrag() {
    const name = state.character.links[press.link].name;
    const restore = adjustPlayback();
    if (!connection.dragBegin(name, press.grabWorld.toArray(), press.pointLink.toArray())) {
      for (const m of restore) connection.send(m);
      press = null;
      return;
    }
    press.restorePlayback = restore;
    press.started = true;
    ghostLink = press.link;
    ghostPoint = press.pointLink.toArray();
    ghostTarget = press.grabWorld.clone();
    awaitingAck = true;
    state.dragging = { link: press.link, target: ghostTarget };
    signals.dragChanged.dispatch({ active: true, link: press.link, target: ghostTarget });
    canvas.style.cursor = 'grabbing';
  }

  function onPointerDown(event) {
    if (!state.character) return;
    if (event.button !== 0 && event.button !== 2) return;
    const hit = pick(event);
    // the pin gizmo gets the press, unless it lands on another link's handle (the gizmo's arrows
    // must not hide the handles around the pin)
    const otherHandle = hit && hit.handle && state.character.links[hit.link].name !== pins.gizmoLink;
    if (pins.wantsPointer() && !otherHandle) return;
    if (!hit) {
      if (event.button === 0 && playing() && nearestHandlePx(event) < MOVING_MISS_GUARD_PX) {
        // a grab at a moving figure that missed: nothing happens (no orbit, no deselection)
        event.stopImmediatePropagation();
        event.preventDefault();
        return;
      }
      // empty space: orbit as usual; a click without movement clears the selection
      emptyPress = event.button === 0 ? { x: event.clientX, y: event.clientY } : null;
      return;
    }
    // a press on a link never orbits
    event.stopImmediatePropagation();
    event.preventDefault();
    canvas.focus({ preventScroll: true });
    if (event.button === 2) {
      actions.togglePin(hit.link);
      signals.selectionChanged.dispatch(hit.link);
      return;
    }
    viewport.controls.enabled = false;
    canvas.setPointerCapture(event.pointerId);
    viewport.camera.getWorldDirection(camDir);
    plane.setFromNormalAndCoplanarPoint(camDir, hit.point);
    press = {
      link: hit.link,
      grabWorld: hit.point,
      pointLink: hit.handle ? new THREE.Vector3() : skeleton.worldToLink(hit.link, hit.point),
      x: event.clientX,
      y: event.clientY,
      pointerId: event.pointerId,
      started: false,
    };
    if (hit.handle) press.grabWorld = skeleton.linkWorld(hit.link).position.clone();
    plane.setFromNormalAndCoplanarPoint(camDir, press.grabWorld);
    if (state.selected !== hit.link) signals.selectionChanged.dispatch(hit.link);
  }

  function onPointerMove(event) {
    if (!press) {
      if (event.buttons === 0 && state.character) setHover(pick(event)?.link ?? -1);
      return;
    }
    if (event.pointerId !== press.pointerId) return;
    if (!press.started) {
      if (Math.hypot(event.clientX - press.x, event.clientY - press.y) < DRAG_THRESHOLD_PX) return;
      beginServerDrag();
      if (!press) return;
    }
    if (targetAt(event, hitPoint)) {
      ghostTarget.copy(hitPoint);
      awaitingAck = true;
      connection.dragTo(hitPoint.toArray());
      updateGhost();
    }
  }

  function finish(cancel) {
    if (!press) return;
    const started = press.started;
    const restore = press.restorePlayback || [];
    if (canvas.hasPointerCapture(press.pointerId)) canvas.releasePointerCapture(press.pointerId);
    press = null;
    viewport.controls.enabled = true;
    if (started) {
      connection.dragEnd(cancel ? [msg.undo(), ...restore] : restore);
      state.dragging = null;
      signals.dragChanged.dispatch({ active: false, link: ghostLink, target: null, cancelled: cancel });
      if (cancel || !awaitingAck) {
        // nothing left to show: the last target is in the pose already (or the gesture is undone)
        ghostTarget = null;
        ghostLink = -1;
        updateGhost();
      }
    }
    canvas.style.cursor = state.hover >= 0 ? 'grab' : '';
  }

  function onPointerUp(event) {
    if (emptyPress && Math.hypot(event.clientX - emptyPress.x, event.clientY - emptyPress.y) < DRAG_THRESHOLD_PX) {
      if (state.selected >= 0) signals.selectionChanged.dispatch(-1);
    }
    emptyPress = null;
    if (press && event.pointerId === press.pointerId) finish(false);
  }

  canvas.addEventListener('pointerdown', onPointerDown, { capture: true });
  canvas.addEventListener('pointermove', onPointerMove);
  canvas.addEventListener('pointerup', onPointerUp);
  canvas.addEventListener('pointercancel', () => finish(false));
  canvas.addEventListener('lostpointercapture', () => finish(false));
  canvas.addEventListener('pointerleave', () => {
    if (!press) setHover(-1);
  });
  canvas.addEventListener('contextmenu', (e) => e.preventDefault());

  signals.poseChanged.add(() => {
    if (ghostTarget) updateGhost();
  });
  signals.dragTargetAcked.add((acked) => {
    if (!acked || !awaitingAck) return;
    awaitingAck = false;
    if (!press) {
      // released and acknowledged: the ghost has done its job
      ghostTarget = null;
      ghostLink = -1;
    }
    updateGhost();
  });
  signals.characterLoaded.add(() => {
    press = null;
    ghostTarget = null;
    ghostLink = -1;
    updateGhost();
  });
  signals.dragChanged.add((d) => {
    if (d.cancelled && !d.active && press) finish(true);
  });

  return {
    cancel() {
      if (press) finish(true);
    },
    get active() {
      return !!press;
    },
  };
}
