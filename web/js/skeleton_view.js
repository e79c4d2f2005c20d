// The character as simple solids built from the snapshot's shapes (capsules, spheres, boxes,
// cylinders; one group per link placed by the pose frames), joint handles at the pivots (the
// pick targets of drag_controls.js), bones, and the colours that show hover, selection, pins and
// joints outside their ranges.

import * as THREE from 'three';
import { jointLimitStatus } from './joint_ranges.js';
import { pinOf } from './state.js';

const COLORS = {
  centre: new THREE.Color(0xc9ccd3),
  left: new THREE.Color(0x8fb3d9),
  right: new THREE.Color(0xd9b48f),
  pinned: new THREE.Color(0xf2a93b),
  handle: new THREE.Color(0xf4f6fa),
  handleHover: new THREE.Color(0xffe066),
  handleSelected: new THREE.Color(0x4fd1ff),
  handlePinned: new THREE.Color(0xff9d1c),
  outOfRange: new THREE.Color(0xff3b30),
};
const HANDLE_RADIUS = 0.018; // on a figure of REFERENCE_HEIGHT; handles scale with the figure
const REFERENCE_HEIGHT = 1.75;

const toQuat = (R) => new THREE.Quaternion(R[1], R[2], R[3], R[0]);

function sideOf(name) {
  if (/^(l_|left|L_)|_l$|\.L$/i.test(name) && !/^(lumbar|lower)/i.test(name)) return 'left';
  if (/^(r_|right|R_)|_r$|\.R$/i.test(name)) return 'right';
  return 'centre';
}

function shapeGeometry(s) {
  switch (s.shape) {
    case 'capsule': {
      const g = new THREE.CapsuleGeometry(s.radius, s.length || 0, 6, 18);
      g.rotateX(Math.PI / 2); // three's capsule runs along y; ours along the shape's z
      return g;
    }
    case 'cylinder': {
      const g = new THREE.CylinderGeometry(s.radius, s.radius, s.length || 0, 20);
      g.rotateX(Math.PI / 2);
      return g;
    }
    case 'sphere':
      return new THREE.SphereGeometry(s.radius, 20, 14);
    case 'box':
      return new THREE.BoxGeometry(s.size[0], s.size[1], s.size[2]);
    default:
      return null; // meshes: drawn as a bone only
  }
}

export function createSkeletonView(state, viewport) {
  const { signals } = state;
  const root = new THREE.Group();
  root.name = 'character';
  viewport.scene.add(root);
  const overlay = new THREE.Group(); // handles and bones, drawn over the body
  overlay.name = 'handles';
  viewport.scene.add(overlay);

  let links = []; // per link: {group, meshes, material, baseColor, handle, side}
  // the figure's size over a person's: a handle is the same part of any figure (1.8 cm on a
  // person, 0.6 mm on a 6 cm figure); measured from the solids of the first pose
  let figureScale = null;
  let bones = null;
  let boneParents = [];
  const status = []; // per link: limit status of its joint
  const pickables = [];

  function clear() {
    for (const l of links) {
      l.group.traverse((o) => {
        if (o.geometry) o.geometry.dispose();
      });
      l.material.dispose();
      l.handle.material.dispose();
    }
    root.clear();
    overlay.clear();
    links = [];
    pickables.length = 0;
    status.length = 0;
    bones = null;
  }

  function build(character) {
    clear();
    const handleGeometry = new THREE.SphereGeometry(HANDLE_RADIUS, 14, 10);
    figureScale = null; // measured on the first pose
    character.links.forEach((link, i) => {
      const group = new THREE.Group();
      group.name = link.name;
      group.matrixAutoUpdate = true;
      const side = sideOf(link.name);
      const baseColor = COLORS[side].clone();
      const material = new THREE.MeshStandardMaterial({ color: baseColor, roughness: 0.62, metalness: 0.05 });
      const meshes = [];
      for (const s of link.shapes || []) {
        const g = shapeGeometry(s);
        if (!g) continue;
        const mesh = new THREE.Mesh(g, material);
        if (s.p) mesh.position.set(s.p[0], s.p[1], s.p[2]);
        if (s.R) mesh.quaternion.copy(toQuat(s.R));
        mesh.castShadow = true;
        mesh.receiveShadow = true;
        mesh.userData.link = i;
        group.add(mesh);
        meshes.push(mesh);
        pickables.push(mesh);
      }
      root.add(group);
      const handleMaterial = new THREE.MeshBasicMaterial({
        color: COLORS.handle,
        transparent: true,
        opacity: 0.85,
        depthTest: false,
      });
      const handle = new THREE.Mesh(handleGeometry, handleMaterial);
      handle.renderOrder = 10;
      handle.userData.link = i;
      overlay.add(handle);
      links.push({ group, meshes, material, baseColor, handle, side });
      status.push({ kind: null, inside: true });
    });
    // bones: parent pivot -> child pivot, drawn faintly through the body
    boneParents = character.links.map((l) => l.parent);
    const count = boneParents.filter((p) => p >= 0).length;
    const geom = new THREE.BufferGeometry();
    geom.setAttribute('position', new THREE.BufferAttribute(new Float32Array(count * 6), 3));
    bones = new THREE.LineSegments(
      geom,
      new THREE.LineBasicMaterial({ color: 0xffffff, transparent: true, opacity: 0.35, depthTest: false }),
    );
    bones.renderOrder = 9;
    bones.frustumCulled = false;
    overlay.add(bones);
    overlay.visible = state.view.handles;
  }

  function applyLinkPoses(poses, jointRotations) {
    if (!poses || poses.length !== links.length) return;
    for (let i = 0; i < links.length; i++) {
      const p = poses[i];
      const l = links[i];
      l.group.position.set(p.p[0], p.p[1], p.p[2]);
      l.group.quaternion.set(p.R[1], p.R[2], p.R[3], p.R[0]);
      l.handle.position.copy(l.group.position);
      status[i] = jointRotations ? jointLimitStatus(state.character.links[i], jointRotations[i]) : status[i];
    }
    if (bones) {
      const arr = bones.geometry.attributes.position.array;
      let k = 0;
      for (let i = 0; i < links.length; i++) {
        const pi = boneParents[i];
        if (pi < 0) continue;
        const a = links[pi].group.position;
        const b = links[i].group.position;
        arr.set([a.x, a.y, a.z, b.x, b.y, b.z], k);
        k += 6;
      }
      bones.geometry.attributes.position.needsUpdate = true;
      bones.geometry.computeBoundingSphere();
    }
    if (figureScale === null) {
      const size = new THREE.Box3().setFromObject(root).getSize(new THREE.Vector3());
      const largest = Math.max(size.x, size.y, size.z);
      figureScale = Number.isFinite(largest) && largest > 0 ? largest / REFERENCE_HEIGHT : 1;
    }
    restyle();
  }

  function restyle() {
    for (let i = 0; i < links.length; i++) {
      const l = links[i];
      const pinned = !!pinOf(state, i);
      const out = !status[i].inside;
      const hovered = state.hover === i;
      const selected = state.selected === i;
      const dragged = state.dragging && state.dragging.link === i;
      l.material.color.copy(pinned ? COLORS.pinned : l.baseColor);
      const emissive = l.material.emissive;
      if (out) emissive.copy(COLORS.outOfRange).multiplyScalar(0.55);
      else if (dragged || selected) emissive.setRGB(0.12, 0.22, 0.3);
      else if (hovered) emissive.setRGB(0.16, 0.16, 0.1);
      else emissive.setRGB(0, 0, 0);
      const hc = l.handle.material.color;
      if (hovered || dragged) hc.copy(COLORS.handleHover);
      else if (selected) hc.copy(COLORS.handleSelected);
      else if (pinned) hc.copy(COLORS.handlePinned);
      else if (out) hc.copy(COLORS.outOfRange);
      else hc.copy(COLORS.handle);
      l.handle.scale.setScalar((figureScale ?? 1) * (hovered || selected || dragged ? 1.45 : pinned ? 1.2 : 1));
    }
    signals.renderRequested.dispatch();
  }

  signals.characterLoaded.add((character) => build(character));
  signals.sessionStateChanged.add((s) => {
    // before the first binary pose, place the figure from the snapshot's link poses
    if (!state.pose && s.links) applyLinkPoses(s.links, null);
    else restyle();
  });
  signals.poseChanged.add((pose) => applyLinkPoses(pose.links, pose.links.map((l) => l.q)));
  signals.hoverChanged.add(restyle);
  signals.selectionChanged.add(restyle);
  signals.dragChanged.add(restyle);
  signals.viewOptionsChanged.add((v) => {
    overlay.visible = v.handles;
    signals.renderRequested.dispatch();
  });

  const tmp = new THREE.Vector3();
  return {
    pickables,
    /** The figure's size over a person's (1.75 m), for marks drawn at a person's size. */
    figureScale: () => figureScale ?? 1,
    /** Draws the solids or not (a skinned mesh stands in for them); they stay pick targets. */
    setBodyVisible(visible) {
      for (const l of links) for (const m of l.meshes) m.visible = visible;
    },
    /** World pose of link i: {position, quaternion} (live objects: do not modify). */
    linkWorld(i) {
      const l = links[i];
      return l ? { position: l.group.position, quaternion: l.group.quaternion, object: l.group } : null;
    },
    /** World position of a point given in link i's frame. */
    linkPointWorld(i, point, out = new THREE.Vector3()) {
      const l = links[i];
      if (!l) return null;
      return out.set(point[0], point[1], point[2]).applyQuaternion(l.group.quaternion).add(l.group.position);
    },
    /** Link-frame coordinates of a world point. */
    worldToLink(i, world, out = new THREE.Vector3()) {
      const l = links[i];
      tmp.copy(world).sub(l.group.position);
      return out.copy(tmp).applyQuaternion(l.group.quaternion.clone().invert());
    },
    handlePositions() {
      return links.map((l) => l.handle.position);
    },
    /** The figure's bounding box as drawn now: its shapes and every link's origin. */
    bounds(out = new THREE.Box3()) {
      out.setFromObject(root);
      for (const l of links) out.expandByPoint(l.group.position);
      return out;
    },
    limitStatus(i) {
      return status[i];
    },
    get count() {
      return links.length;
    },
  };
}
