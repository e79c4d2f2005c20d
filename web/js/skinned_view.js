// The character's skinned mesh (a glTF, FBX or DAE character), drawn with three.js SkinnedMesh
// and following the pose stream: one bone per skin joint, placed at its link's world pose, so
// linear blend skinning gives what the server's exports give. The mesh comes once per session
// (GET /api/sessions/{id}/mesh, binary, kept by the browser's cache; server/mesh_binary.hpp). With
// the mesh shown the capsules stay as pick targets but are not drawn; the "mesh" view option
// brings the capsules back, and a character without a mesh keeps them. Each part of the mesh has
// its own material: its base colour times its texture (PNG or JPEG from the same download).

import * as THREE from 'three';

/** Decodes the binary mesh: {header, positions, normals, indices, joints, weights, uvs, images}. */
export function decodeMesh(buffer) {
  const magic = new TextDecoder().decode(new Uint8Array(buffer, 0, 4));
  if (magic !== 'PDMS') throw new Error('mesh: not a pindrag mesh (magic)');
  const length = new DataView(buffer).getUint32(4, true);
  const header = JSON.parse(new TextDecoder().decode(new Uint8Array(buffer, 8, length)));
  let at = 8 + length;
  const take = (Type, count) => {
    const a = new Type(buffer, at, count);
    at += Math.ceil((count * Type.BYTES_PER_ELEMENT) / 4) * 4;
    return a;
  };
  const n = header.vertices;
  const positions = take(Float32Array, 3 * n);
  const normals = header.normals ? take(Float32Array, 3 * n) : null;
  const indices = take(Uint32Array, 3 * header.triangles);
  const joints = take(Uint16Array, 4 * n);
  const weights = take(Float32Array, 4 * n);
  const uvs = header.uvs ? take(Float32Array, 2 * n) : null;
  const images = (header.textures || []).map((t) => ({ mimeType: t.mime_type, bytes: take(Uint8Array, t.bytes) }));
  if (at > buffer.byteLength) throw new Error('mesh: shorter than its header says');
  return { header, positions, normals, indices, joints, weights, uvs, images };
}

/** A three.js texture of an image file's bytes, once the browser has decoded it. */
async function textureOf({ mimeType, bytes }) {
  const url = URL.createObjectURL(new Blob([bytes], { type: mimeType }));
  try {
    const image = new Image();
    image.src = url;
    await image.decode();
    const texture = new THREE.Texture(image);
    texture.colorSpace = THREE.SRGBColorSpace; // glTF's base colour textures are sRGB
    texture.wrapS = texture.wrapT = THREE.RepeatWrapping;
    texture.needsUpdate = true;
    return texture;
  } finally {
    URL.revokeObjectURL(url);
  }
}

export function createSkinnedView(state, viewport, skeleton, api) {
  const { signals } = state;
  let mesh = null; // {object, bones: [{bone, link}]}
  let loading = 0; // the characterLoaded generation a fetch belongs to

  function clear() {
    if (!mesh) return;
    viewport.scene.remove(mesh.object);
    for (const { bone } of mesh.bones) viewport.scene.remove(bone);
    mesh.object.geometry.dispose();
    for (const material of mesh.object.material) {
      if (material.map) material.map.dispose();
      material.dispose();
    }
    mesh.object.skeleton.dispose();
    mesh = null;
  }

  // one material per part (the whole mesh in the header's base colour when it has no parts);
  // a texture the browser cannot decode leaves its part in its base colour
  async function materialsOf(decoded) {
    const { header } = decoded;
    const parts = header.parts && header.parts.length ? header.parts : [{ first: 0, count: header.triangles, base_color: header.base_color, texture: -1 }];
    const textures = await Promise.all(
      decoded.images.map((image, k) =>
        textureOf(image).catch(() => {
          signals.notify.dispatch({ text: `mesh: texture ${k} (${image.mimeType}) could not be decoded: drawn in its base colour`, kind: 'error' });
          return null;
        }),
      ),
    );
    return parts.map((part) => {
      const [r, g, b, a] = part.base_color;
      return {
        part,
        material: new THREE.MeshStandardMaterial({
          color: new THREE.Color(r, g, b),
          map: decoded.uvs && part.texture >= 0 ? textures[part.texture] : null,
          roughness: 0.7,
          metalness: 0.0,
          transparent: a < 1,
          opacity: a,
          side: THREE.DoubleSide,
        }),
      };
    });
  }

  function build(decoded, materials) {
    const { header } = decoded;
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(decoded.positions, 3));
    if (decoded.normals) geometry.setAttribute('normal', new THREE.BufferAttribute(decoded.normals, 3));
    geometry.setIndex(new THREE.BufferAttribute(decoded.indices, 1));
    geometry.setAttribute('skinIndex', new THREE.Uint16BufferAttribute(decoded.joints, 4));
    geometry.setAttribute('skinWeight', new THREE.BufferAttribute(decoded.weights, 4));
    if (decoded.uvs) geometry.setAttribute('uv', new THREE.BufferAttribute(decoded.uvs, 2));
    materials.forEach(({ part }, k) => geometry.addGroup(3 * part.first, 3 * part.count, k));
    if (!decoded.normals) geometry.computeVertexNormals();
    // bones live in the scene, not in a hierarchy: each one's world matrix is its link's pose
    const bones = header.bones.map((link) => {
      const bone = new THREE.Bone();
      bone.userData.link = link;
      return { bone, link };
    });
    const inverses = header.inverse_bind.map((m) => new THREE.Matrix4().fromArray(m));
    const skeletonObject = new THREE.Skeleton(
      bones.map((b) => b.bone),
      inverses,
    );
    const object = new THREE.SkinnedMesh(
      geometry,
      materials.map((m) => m.material),
    );
    object.name = 'skinned-mesh';
    object.frustumCulled = false; // the bind-pose bounds say nothing about the posed figure
    object.castShadow = true;
    object.bindMode = THREE.DetachedBindMode;
    object.bind(skeletonObject, new THREE.Matrix4());
    for (const { bone } of bones) viewport.scene.add(bone);
    viewport.scene.add(object);
    mesh = { object, bones };
    place();
    showCapsules();
  }

  // each bone at its link's world pose (the skeleton view has placed the links)
  function place() {
    if (!mesh) return;
    for (const { bone, link } of mesh.bones) {
      const w = skeleton.linkWorld(link);
      if (!w) continue;
      bone.position.copy(w.position);
      bone.quaternion.copy(w.quaternion);
      bone.updateMatrixWorld(true);
    }
    signals.renderRequested.dispatch();
  }

  function showCapsules() {
    const meshShown = !!mesh && state.view.mesh !== false;
    if (mesh) mesh.object.visible = meshShown;
    skeleton.setBodyVisible(!meshShown);
    signals.renderRequested.dispatch();
  }

  async function load(generation) {
    try {
      const decoded = decodeMesh(await api.mesh());
      const materials = await materialsOf(decoded);
      if (generation !== loading) {
        // another character arrived meanwhile
        for (const { material } of materials) {
          if (material.map) material.map.dispose();
          material.dispose();
        }
        return;
      }
      clear();
      build(decoded, materials);
      state.meshVertices = decoded.header.vertices;
      signals.meshLoaded.dispatch();
    } catch (err) {
      signals.notify.dispatch({ text: `${err.message}: the character is drawn as capsules`, kind: 'error' });
    }
  }

  signals.characterLoaded.add((character) => {
    loading += 1;
    clear();
    state.meshVertices = 0;
    showCapsules();
    if (character.skinned) load(loading);
  });
  signals.poseChanged.add(place);
  signals.sessionStateChanged.add(() => {
    if (!state.pose) place();
  });
  signals.viewOptionsChanged.add(showCapsules);
  return {
    /** The SkinnedMesh drawn now, or null. */
    object: () => (mesh ? mesh.object : null),
    /** Grows a box (THREE.Box3) by the mesh as posed now, when it is shown: a mesh may reach far
     *  beyond the links' capsules (a rigid part carried by a link). */
    expandBounds(box) {
      if (mesh && mesh.object.visible) box.expandByObject(mesh.object, true);
      return box;
    },
  };
}
