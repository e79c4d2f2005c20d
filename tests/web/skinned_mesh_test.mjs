// A skinned character in the page with `pindrag serve` in headless Chromium: CesiumMan (glTF) is
// drawn as its mesh with its texture (three.js SkinnedMesh fed by GET /api/sessions/{id}/mesh):
// where its vertices project, the pixels change when the mesh is switched off for the capsules;
// dragging a link with the mouse carries the vertices bound to it rigidly (linear blend skinning
// with weight 1); a reloaded page gets the mesh again.
// Usage: node tests/web/skinned_mesh_test.mjs PINDRAG_BINARY   (or PINDRAG_BIN=...)

import { test, before } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import { openPage, dragMouse, settle } from './support/browser.mjs';
import { serverAndBrowser } from './support/fixture.mjs';
import { SOURCE_DIR } from './support/env.mjs';
import { dist, handle } from './support/session_page.mjs';

const fixture = await serverAndBrowser('skinned_mesh');
const out = fixture.out;

let browser;
let server;
before(async () => ({ server, browser } = await fixture.start()));

const DATA_DIR = process.env.PINDRAG_DATA_DIR || path.join(SOURCE_DIR, '..', 'shared', 'data');
const CESIUM = path.join(DATA_DIR, 'gltf', 'CesiumMan.glb');
const noData = fs.existsSync(CESIUM) ? false : `${CESIUM} is absent (set PINDRAG_DATA_DIR)`;

async function openOnFile(file) {
  const form = new FormData();
  form.append('character', new Blob([fs.readFileSync(file)]), path.basename(file));
  const res = await fetch(`${server.url}api/sessions`, { method: 'POST', body: form });
  if (res.status !== 201) assert.fail(`creating a session from ${file}: ${res.status} ${await res.text()}`);
  const { id, token } = await res.json();
  const opened = await openPage(browser, server.url, { sessionStorage: { 'pindrag.session': JSON.stringify({ id, token }) } });
  await opened.page.waitForFunction(() => window.pindrag.mesh() && window.pindrag.mesh().vertices > 0, null, { timeout: 20000 });
  await settle(opened.page);
  return opened;
}

// q = [x, y, z, w]: v expressed in the frame (p, q)
function toLocal(pose, v) {
  const [x, y, z, w] = pose.q;
  const d = [v[0] - pose.p[0], v[1] - pose.p[1], v[2] - pose.p[2]];
  // rotate d by the conjugate quaternion
  const [qx, qy, qz, qw] = [-x, -y, -z, w];
  const tx = 2 * (qy * d[2] - qz * d[1]);
  const ty = 2 * (qz * d[0] - qx * d[2]);
  const tz = 2 * (qx * d[1] - qy * d[0]);
  return [d[0] + qw * tx + (qy * tz - qz * ty), d[1] + qw * ty + (qz * tx - qx * tz), d[2] + qw * tz + (qx * ty - qy * tx)];
}

const setView = (page, key, value) =>
  page.evaluate(([k, v]) => {
    const box = [...document.querySelectorAll('#view-options label.toggle')].find((l) => l.textContent.trim() === k);
    const input = box.querySelector('input');
    if (input.checked !== v) input.click();
  }, [key, value]);

test('CesiumMan is drawn as its skinned mesh, and a dragged link carries its vertices', { skip: noData }, async () => {
  const { page, context, problems } = await openOnFile(CESIUM);
  const info = await page.evaluate(() => window.pindrag.mesh());
  console.log(`mesh: ${info.vertices} vertices, visible ${info.visible}, ${info.parts} parts, ${info.textured} textured`);
  assert.equal(info.visible, true);
  // the skin's texture came with the mesh and was decoded (CesiumMan has one, on its one part)
  assert.equal(info.textured, info.parts, 'every part of CesiumMan is drawn with its texture');
  await page.screenshot({ path: path.join(out, 'cesium-mesh.png') });

  // pixels where the mesh's vertices project change when the capsules stand in for it
  const samples = [];
  for (let i = 0; i < info.vertices; i += Math.floor(info.vertices / 40)) samples.push(i);
  const pixels = () =>
    page.evaluate((idx) => {
      return idx.map((i) => {
        const p = window.pindrag.projectPoint(window.pindrag.skinnedVertex(i));
        return window.pindrag.pixelAt(p.x, p.y);
      });
    }, samples);
  const withMesh = await pixels();
  await setView(page, 'mesh', false);
  assert.equal((await page.evaluate(() => window.pindrag.mesh())).visible, false);
  const withCapsules = await pixels();
  await page.screenshot({ path: path.join(out, 'cesium-capsules.png') });
  await setView(page, 'mesh', true);
  const changed = withMesh.filter((c, k) => Math.max(...c.map((v, j) => Math.abs(v - withCapsules[k][j]))) > 10).length;
  console.log(`${changed} of ${samples.length} sampled vertex pixels change when the mesh is switched off`);
  assert.ok(changed >= 0.6 * samples.length, `only ${changed} of ${samples.length} pixels show the mesh`);

  // a link whose bone holds some vertex with weight 1, away from the root: drag it by the mouse
  const names = await page.evaluate(() => window.pindrag.linkNames());
  let chosen = null;
  for (const name of names.slice(1).reverse()) {
    const v = await page.evaluate((n) => window.pindrag.vertexOfLink(n), name);
    const onScreen = await page.evaluate((n) => window.pindrag.project(n), name);
    if (v && v.weight > 0.999 && onScreen && onScreen.visible) {
      chosen = { name, vertex: v.index };
      break;
    }
  }
  assert.ok(chosen, 'no link holds a vertex with weight 1');
  const before = await page.evaluate((c) => ({ pose: window.pindrag.linkPose(c.name), v: window.pindrag.skinnedVertex(c.vertex) }), chosen);
  const A = await handle(page, chosen.name);
  await page.mouse.move(A.x, A.y);
  await page.mouse.down();
  const B = { x: A.x + 60, y: A.y - 50 };
  // every frame of the gesture: the vertex stays where its bone puts it
  let worst = 0;
  for (let k = 1; k <= 8; k++) {
    await dragMouse(page, A, { x: A.x + (k * (B.x - A.x)) / 8, y: A.y + (k * (B.y - A.y)) / 8 }, { steps: 1, skipPressRelease: true });
    await page.waitForTimeout(80);
    const now = await page.evaluate((c) => ({ pose: window.pindrag.linkPose(c.name), v: window.pindrag.skinnedVertex(c.vertex) }), chosen);
    worst = Math.max(worst, dist(toLocal(now.pose, now.v), toLocal(before.pose, before.v)));
  }
  await page.waitForTimeout(500);
  await page.mouse.up();
  await page.waitForTimeout(300);
  const after = await page.evaluate((c) => ({ pose: window.pindrag.linkPose(c.name), v: window.pindrag.skinnedVertex(c.vertex) }), chosen);
  worst = Math.max(worst, dist(toLocal(after.pose, after.v), toLocal(before.pose, before.v)));
  const moved = dist(after.v, before.v);
  console.log(`dragged ${chosen.name}: its vertex ${chosen.vertex} moved ${(moved * 100).toFixed(1)} cm, off its bone by at most ${(worst * 1000).toFixed(4)} mm over the gesture`);
  assert.ok(moved > 0.01, `the vertex moved only ${moved} m`);
  assert.ok(worst < 1e-4, `the vertex left its bone by ${worst} m`);
  await page.screenshot({ path: path.join(out, 'cesium-dragged.png') });

  // a reload gets the mesh again
  await page.reload();
  await page.waitForFunction(() => window.pindrag && window.pindrag.mesh() && window.pindrag.mesh().vertices > 0, null, { timeout: 20000 });
  assert.equal((await page.evaluate(() => window.pindrag.mesh())).vertices, info.vertices);
  assert.deepEqual(problems, []);
  await context.close();
});

test('a character without a mesh keeps its capsules', async () => {
  const { page, context, problems } = await openPage(browser, server.url);
  await page.waitForFunction(() => window.pindrag && window.pindrag.poseFrames > 0, null, { timeout: 20000 });
  assert.equal(await page.evaluate(() => window.pindrag.mesh()), null);
  const res = await fetch(`${server.url}api/sessions/${await page.evaluate(() => window.pindrag.sessionId)}/mesh`, {
    headers: { 'X-Session-Token': await page.evaluate(() => window.pindrag.token) },
  });
  assert.equal(res.status, 404);
  assert.deepEqual(problems, []);
  await context.close();
});
