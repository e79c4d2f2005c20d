// "Follow": the camera travels with the figure. While the switch is on, every new pose moves the
// orbit target and the camera by the root link's horizontal motion, so a walking clip stays in
// view at the distance and angle the user chose; height and orbiting are left to the user. While a
// link is dragged the camera stands still (a camera following the pelvis under the pointer would
// carry the drag's target away with it), and it follows on from where the figure is after.

import * as THREE from 'three';

export function createCameraFollow(state, viewport, skeleton) {
  const { signals } = state;
  let last = null; // the root's position the camera last followed
  const now = new THREE.Vector3();

  function follow() {
    if (!state.view.follow || !state.character || state.dragging) {
      last = null;
      return;
    }
    const root = skeleton.linkWorld(0);
    if (!root) return;
    now.copy(root.position);
    if (last) {
      const dx = now.x - last.x;
      const dz = now.z - last.z;
      if (dx !== 0 || dz !== 0) {
        viewport.camera.position.x += dx;
        viewport.camera.position.z += dz;
        viewport.controls.target.x += dx;
        viewport.controls.target.z += dz;
        viewport.controls.update();
      }
    } else {
      last = new THREE.Vector3();
    }
    last.copy(now);
  }

  signals.poseChanged.add(follow);
  signals.viewOptionsChanged.add(follow);
  signals.characterLoaded.add(() => (last = null));
}
