// The camera frames characters of any size with `pindrag serve` in headless Chromium: a figure
// 60 m tall (a character file in metres), the same figure 6 cm tall and the bundled human48 open
// with every link on screen, and Home view frames them again after the camera was moved away.
// Usage: node tests/web/framing_test.mjs PINDRAG_BINARY   (or PINDRAG_BIN=...)

import { test, before } from 'node:test';
import assert from 'node:assert/strict';
import path from 'node:path';
import { openPage } from './support/browser.mjs';
import { serverAndBrowser } from './support/fixture.mjs';

const fixture = await serverAndBrowser('framing');
const out = fixture.out;

let browser;
let server;
before(async () => ({ server, browser } = await fixture.start()));

// a figure 60 m tall: a trunk on a free joint and a head on a neck joint, in metres
const GIANT = JSON.stringify({
  format: 'pindrag-character',
  version: 1,
  name: 'giant',
  links: [
    {
      name: 'trunk',
      joint: { type: 'free', origin: { xyz: [0, 25, 0] } },
      inertial: { mass: 5000, com: [0, 0, 0], inertia: { ixx: 1e5, iyy: 1e5, izz: 1e5 } },
      collision: [{ shape: 'capsule', radius: 5, length: 40, origin: { xyz: [0, 0, 0], quaternion: [0.7071067811865476, 0.7071067811865476, 0, 0] } }],
    },
    {
      name: 'neck',
      parent: 'trunk',
      joint: { name: 'neck', type: 'revolute', origin: { xyz: [0, 25, 0] }, axis: [1, 0, 0], limits: { lower: -1, upper: 1 } },
      inertial: { mass: 500, com: [0, 5, 0], inertia: { ixx: 1e3, iyy: 1e3, izz: 1e3 } },
      collision: [{ shape: 'box', size: [8, 10, 8], origin: { xyz: [0, 5, 0] } }],
    },
  ],
});

// the same figure a thousand times smaller: 6 cm tall
const TINY = JSON.stringify(
  JSON.parse(GIANT, (key, value) => {
    if (key === 'name' && value === 'giant') return 'tiny';
    if (key === 'mass') return value * 1e-9;
    if (['ixx', 'iyy', 'izz'].includes(key)) return value * 1e-15;
    if (['radius', 'length'].includes(key)) return value * 1e-3;
    if (['xyz', 'size', 'com'].includes(key)) return value.map((x) => x * 1e-3);
    return value;
  }),
);

/** Creates a session from a character file and opens the page on it. */
async function openOnUpload(name, text) {
  const form = new FormData();
  form.append('character', new Blob([text], { type: 'text/plain' }), name);
  const res = await fetch(`${server.url}api/sessions`, { method: 'POST', body: form });
  if (res.status !== 201) assert.fail(`creating a session from ${name}: ${res.status} ${await res.text()}`);
  const { id, token } = await res.json();
  return openPage(browser, server.url, { sessionStorage: { 'pindrag.session': JSON.stringify({ id, token }) } });
}

/** How many links are on the canvas, and the largest link height in the world. */
async function linksOnScreen(page) {
  return page.evaluate(() => {
    const canvas = document.querySelector('canvas').getBoundingClientRect();
    const names = window.pindrag.linkNames();
    let inside = 0;
    let top = -Infinity;
    for (const n of names) {
      const p = window.pindrag.project(n);
      if (p && p.visible && p.x >= canvas.left && p.x <= canvas.right && p.y >= canvas.top && p.y <= canvas.bottom) inside++;
      top = Math.max(top, window.pindrag.linkPosition(n)[1]);
    }
    return { inside, total: names.length, top };
  });
}

async function checkFramed(page, what) {
  const seen = await linksOnScreen(page);
  console.log(`${what}: ${seen.inside} of ${seen.total} links on screen, top at ${seen.top.toFixed(2)} m, camera at ${JSON.stringify((await page.evaluate(() => window.pindrag.camera())).position.map((x) => +x.toFixed(2)))}`);
  assert.equal(seen.inside, seen.total, `${what}: only ${seen.inside} of ${seen.total} links are on screen`);
  return seen;
}

test('a 60 m figure, a 6 cm figure and the bundled human are framed when they open and by Home view', async () => {
  for (const [name, opened] of [
    ['human48', () => openPage(browser, server.url)],
    ['the 60 m figure', () => openOnUpload('giant.json', GIANT)],
    ['the 6 cm figure', () => openOnUpload('tiny.json', TINY)],
  ]) {
    const { page, context, problems } = await opened();
    await page.waitForTimeout(300);
    const seen = await checkFramed(page, `${name} when opened`);
    if (name === 'the 60 m figure') assert.ok(seen.top > 45, `the figure is only ${seen.top} m tall`);
    if (name === 'the 6 cm figure') assert.ok(seen.top < 0.06, `the figure is ${seen.top} m tall`);
    // move the camera far off, then Home view
    const box = await page.locator('canvas').first().boundingBox();
    for (let k = 0; k < 15; k++) await page.mouse.wheel(0, -400); // zoom in
    await page.mouse.move(box.x + 20, box.y + 20);
    await page.mouse.down({ button: 'right' });
    await page.mouse.move(box.x + 600, box.y + 400, { steps: 10 }); // pan away
    await page.mouse.up({ button: 'right' });
    await page.click('#view-options button:has-text("Home view")');
    await page.waitForTimeout(200);
    await checkFramed(page, `${name} after Home view`);
    await page.screenshot({ path: path.join(out, `${name.replace(/\W+/g, '_')}.png`) });
    assert.deepEqual(problems, []);
    await context.close();
  }
});

// A crane as a rigid mechanism without bones: a base and a 30 m boom that turns, each a mesh its
// node carries. Its links are a metre apart; its mesh reaches 30 m beyond them.
function craneGltf() {
  const floats = (a) => Buffer.from(new Float32Array(a).buffer);
  const bin = Buffer.concat([
    floats([-0.5, 0, -0.5, 0.5, 0, -0.5, 0, 0, 0.5]), // base triangle: 36 bytes
    floats([0, 0, -0.2, 30, 0, 0, 0, 0, 0.2]), // boom triangle: 36 bytes
    Buffer.from(new Uint16Array([0, 1, 2, 0]).buffer), // indices (padded): 8 bytes
    floats([0, 1]), // key times: 8 bytes
    floats([0, 0, 0, 1, 0, 0, Math.sin(Math.PI / 12), Math.cos(Math.PI / 12)]), // 30° about z: 32 bytes
  ]);
  const view = (byteOffset, byteLength) => ({ buffer: 0, byteOffset, byteLength });
  return JSON.stringify({
    asset: { version: '2.0' },
    scene: 0,
    scenes: [{ nodes: [0] }],
    nodes: [
      { name: 'base', mesh: 0, children: [1] },
      { name: 'boom', mesh: 1, translation: [0, 1, 0] },
    ],
    meshes: [0, 1].map((k) => ({ primitives: [{ attributes: { POSITION: k }, indices: 2 }] })),
    buffers: [{ byteLength: bin.length, uri: `data:application/octet-stream;base64,${bin.toString('base64')}` }],
    bufferViews: [view(0, 36), view(36, 36), view(72, 6), view(80, 8), view(88, 32)],
    accessors: [
      { bufferView: 0, componentType: 5126, count: 3, type: 'VEC3', min: [-0.5, 0, -0.5], max: [0.5, 0, 0.5] },
      { bufferView: 1, componentType: 5126, count: 3, type: 'VEC3', min: [0, 0, -0.2], max: [30, 0, 0.2] },
      { bufferView: 2, componentType: 5123, count: 3, type: 'SCALAR' },
      { bufferView: 3, componentType: 5126, count: 2, type: 'SCALAR', min: [0], max: [1] },
      { bufferView: 4, componentType: 5126, count: 2, type: 'VEC4' },
    ],
    animations: [{ samplers: [{ input: 3, output: 4 }], channels: [{ sampler: 0, target: { node: 1, path: 'rotation' } }] }],
  });
}

/** How many of the skinned mesh's vertices are on the canvas. */
async function meshVerticesOnScreen(page) {
  return page.evaluate(() => {
    const canvas = document.querySelector('canvas').getBoundingClientRect();
    const { vertices } = window.pindrag.mesh();
    let inside = 0;
    for (let v = 0; v < vertices; v++) {
      const p = window.pindrag.projectPoint(window.pindrag.skinnedVertex(v));
      if (p.visible && p.x >= canvas.left && p.x <= canvas.right && p.y >= canvas.top && p.y <= canvas.bottom) inside++;
    }
    return { inside, total: vertices };
  });
}

test('a mechanism whose mesh reaches far beyond its links is framed with its mesh, when it opens and by Home view', async () => {
  const { page, context, problems } = await openOnUpload('crane.gltf', craneGltf());
  await page.waitForFunction(() => window.pindrag.mesh() !== null, null, { timeout: 10000 });
  await page.waitForTimeout(300);
  for (const when of ['when opened', 'after Home view']) {
    const seen = await meshVerticesOnScreen(page);
    console.log(`the crane ${when}: ${seen.inside} of ${seen.total} mesh vertices on screen`);
    assert.equal(seen.total, 6);
    assert.equal(seen.inside, seen.total, `the crane ${when}: only ${seen.inside} of ${seen.total} mesh vertices are on screen`);
    await checkFramed(page, `the crane ${when}`);
    for (let k = 0; k < 15; k++) await page.mouse.wheel(0, -400); // zoom in on it
    await page.click('#view-options button:has-text("Home view")');
    await page.waitForTimeout(200);
  }
  await page.screenshot({ path: path.join(out, 'crane.png') });
  assert.deepEqual(problems, []);
  await context.close();
});
