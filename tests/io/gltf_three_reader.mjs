// An independent glTF reader: three.js GLTFLoader in Node. Loads a .gltf or .glb, plays one
// animation with an AnimationMixer and prints, for every sample time, the world position and
// world quaternion of every glTF node (by node index), as one JSON document:
//   {"nodes": N, "bones": [node indices three.js made Bones], "animations": A, "times": [...],
//    "skinned_meshes": [{"vertices", "material" (a MeshStandardMaterial), "bones"}, ...],
//    "frames": [[[px, py, pz, qx, qy, qz, qw] or null, ... per node], ... per time]}
// Usage: node gltf_three_reader.mjs <node_modules folder> <file> keys [animation]
//          samples at the animation's own key times (the first track's input)
//        node gltf_three_reader.mjs <node_modules folder> <file> rate <t0> <fps> <count> [animation]
//          samples at t0 + k / fps, k = 0 .. count - 1
// Used by tests/io/gltf_test.cpp and assimp_import_test.cpp.
import { readFile } from 'node:fs/promises';
import path from 'node:path';
import { pathToFileURL } from 'node:url';

const [nodeModules, file, mode, ...rest] = process.argv.slice(2);
if (!nodeModules || !file || (mode !== 'keys' && mode !== 'rate')) {
  console.error('usage: node gltf_three_reader.mjs <node_modules> <file> keys|rate ...');
  process.exit(2);
}
const threeDir = path.join(path.resolve(nodeModules), 'three');
// GLTFLoader imports 'three', which resolves to this same module from inside node_modules
const THREE = await import(pathToFileURL(path.join(threeDir, 'build/three.module.js')).href);
const { GLTFLoader } = await import(
  pathToFileURL(path.join(threeDir, 'examples/jsm/loaders/GLTFLoader.js')).href);

// browser globals GLTFLoader touches in Node (data: URIs report progress with ProgressEvent)
globalThis.ProgressEvent ??= class ProgressEvent extends Event {
  constructor(type, init = {}) { super(type); Object.assign(this, init); }
};

const bytes = await readFile(file);
const data = file.toLowerCase().endsWith('.glb')
  ? bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength)
  : bytes.toString('utf8');

const loader = new GLTFLoader();
// textures are irrelevant to poses and need an image decoder Node lacks: load them as blanks
loader.register(() => ({ name: 'pindrag_blank_textures', loadTexture: () => Promise.resolve(new THREE.Texture()) }));
const gltf = await new Promise((resolve, reject) => loader.parse(data, '', resolve, reject));

// glTF node index of every object the loader made from a node
const nodeCount = gltf.parser.json.nodes?.length ?? 0;
const objectOfNode = new Array(nodeCount).fill(null);
gltf.scene.traverse((o) => {
  const a = gltf.parser.associations.get(o);
  if (a && a.nodes !== undefined && objectOfNode[a.nodes] === null) objectOfNode[a.nodes] = o;
});
const bones = [];
objectOfNode.forEach((o, i) => { if (o && o.isBone) bones.push(i); });
const skinnedMeshes = [];
gltf.scene.traverse((o) => {
  if (!o.isSkinnedMesh) return;
  skinnedMeshes.push({
    vertices: o.geometry.attributes.position.count,
    material: Boolean(o.material && o.material.isMeshStandardMaterial),
    bones: o.skeleton.bones.length,
  });
});

const animationIndex = Number(mode === 'keys' ? (rest[0] ?? 0) : (rest[3] ?? 0));
const clip = gltf.animations[animationIndex];
let times = [];
if (mode === 'keys') {
  times = clip ? Array.from(clip.tracks[0].times) : [0];
} else {
  const [t0, fps, count] = rest.slice(0, 3).map(Number);
  for (let k = 0; k < count; ++k) times.push(t0 + k / fps);
}

const mixer = new THREE.AnimationMixer(gltf.scene);
if (clip) {
  const action = mixer.clipAction(clip);
  action.setLoop(THREE.LoopOnce, 1);
  action.clampWhenFinished = true;
  action.play();
}
const p = new THREE.Vector3();
const q = new THREE.Quaternion();
const frames = [];
for (const t of times) {
  mixer.setTime(t);
  gltf.scene.updateMatrixWorld(true);
  frames.push(objectOfNode.map((o) => {
    if (!o) return null;
    o.getWorldPosition(p);
    o.getWorldQuaternion(q);
    return [p.x, p.y, p.z, q.x, q.y, q.z, q.w];
  }));
}
console.log(JSON.stringify({
  nodes: nodeCount, bones, animations: gltf.animations.length, times,
  skinned_meshes: skinnedMeshes, frames,
}));
