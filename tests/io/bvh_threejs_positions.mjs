// An independent reader for tests/io/bvh_test.cpp: loads a BVH file with three.js's
// BVHLoader, poses the skeleton at every keyframe from the loader's own tracks, and prints the
// world position of every bone (joints and End Sites, in file order) as JSON:
//   {"names": ["Hips", ..., "ENDSITE", ...], "frames": [[x0, y0, z0, x1, ...], ...]}
// Any console.error or console.warn from the loader is a failure (exit code 1).
// Usage: node bvh_threejs_positions.mjs <web/node_modules> <file.bvh>
import { readFileSync } from 'node:fs';
import path from 'node:path';
import { pathToFileURL } from 'node:url';

const [modulesDir, file] = process.argv.slice(2);
if (!modulesDir || !file) {
  console.log('usage: node bvh_threejs_positions.mjs <web/node_modules> <file.bvh>');
  process.exit(2);
}

const complaints = [];
console.error = (...args) => complaints.push(args.join(' '));
console.warn = (...args) => complaints.push(args.join(' '));

const url = (p) => pathToFileURL(path.join(modulesDir, p)).href;
const THREE = await import(url('three/build/three.module.js'));
const { BVHLoader } = await import(url('three/examples/jsm/loaders/BVHLoader.js'));

const { skeleton, clip } = new BVHLoader().parse(readFileSync(file, 'utf8'));
const bones = skeleton.bones;

// tracks by bone name: "<bone>.position" and "<bone>.quaternion"
const tracks = new Map();
for (const track of clip.tracks) {
  const dot = track.name.lastIndexOf('.');
  const bone = track.name.slice(0, dot);
  if (!tracks.has(bone)) tracks.set(bone, {});
  tracks.get(bone)[track.name.slice(dot + 1)] = track;
}
const frames = clip.tracks.length ? clip.tracks[0].times.length : 0;

const out = { names: bones.map((b) => b.name), frames: [] };
const p = new THREE.Vector3();
for (let f = 0; f < frames; ++f) {
  for (const bone of bones) {
    const t = tracks.get(bone.name);
    if (!t || bone.name === 'ENDSITE') continue;
    if (t.position) bone.position.fromArray(t.position.values, 3 * f);
    if (t.quaternion) bone.quaternion.fromArray(t.quaternion.values, 4 * f);
  }
  bones[0].updateMatrixWorld(true);
  const row = [];
  for (const bone of bones) {
    bone.getWorldPosition(p);
    row.push(p.x, p.y, p.z);
  }
  out.frames.push(row);
}

if (complaints.length) {
  process.stderr.write('BVHLoader complained:\n' + complaints.join('\n') + '\n');
  process.exit(1);
}
process.stdout.write(JSON.stringify(out));
