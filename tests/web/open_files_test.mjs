// Opening characters and clips from the page with `pindrag serve` in headless Chromium: "Open…"
// opens a bundled character, a character file of the user's and a saved session, each in a new
// session while the one left stays saved; "Load clip…" with a clip of another skeleton offers to
// open it as its own character, which brings the clip, or to retarget it onto this character; a
// malformed file is refused with a message naming it and the session stays as it was. Every file
// of ../shared/data/{bvh,gltf,urdf} opens as a session standing on the ground; a
// BVH opens in the unit guessed from its height or in the one chosen. "Load clip…" with a marker
// trial (C3D) fits it onto the human figure.
// Usage: node tests/web/open_files_test.mjs PINDRAG_BINARY   (or PINDRAG_BIN=...)

import { test, before } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import { settle } from './support/browser.mjs';
import { serverAndBrowser } from './support/fixture.mjs';
import { SOURCE_DIR } from './support/env.mjs';

const fixture = await serverAndBrowser('open_files');
const out = fixture.out;

let browser;
let server;
before(async () => ({ server, browser } = await fixture.start()));

const DATA_DIR = process.env.PINDRAG_DATA_DIR || path.join(SOURCE_DIR, '..', 'shared', 'data');
const hasData = fs.existsSync(path.join(DATA_DIR, 'bvh'));
const noData = hasData ? false : `${DATA_DIR} is absent (set PINDRAG_DATA_DIR)`;

async function ready(page) {
  await page.waitForFunction(() => window.pindrag && window.pindrag.connection === 'open' && window.pindrag.poseFrames > 0, null, {
    timeout: 30000,
  });
  await settle(page);
}

async function openTab(context) {
  const page = await context.newPage();
  const problems = [];
  page.on('pageerror', (e) => problems.push(`page error: ${e.message}`));
  await page.goto(server.url);
  await ready(page);
  return { page, problems };
}

const sessionOf = (page) => page.evaluate(() => ({ id: window.pindrag.sessionId, token: window.pindrag.token }));

/** Waits until the tab has switched to another session than `from` and is live on it. */
async function switchedFrom(page, from) {
  await page.waitForFunction((id) => window.pindrag && window.pindrag.sessionId && window.pindrag.sessionId !== id, from, { timeout: 60000 });
  await ready(page);
  const s = await sessionOf(page);
  return { ...s, snapshot: await server.snapshot(s.id, s.token) };
}

/** Picks a character file of one's own in the Open dialog (a BVH read in `units`). */
async function openFileFromDialog(page, file, units = 'auto') {
  await page.click('#open-character');
  await page.waitForSelector('#open-dialog:not([hidden]) #open-file');
  await page.selectOption('#open-units', units);
  await page.setInputFiles('#open-character-file', file);
}

const storedIds = async () => (await (await fetch(`${server.url}api/sessions`)).json()).map((r) => r.id);

test('Open… opens a bundled character, a file of one’s own and a saved session, keeping the one left', async () => {
  const context = await browser.newContext({ viewport: { width: 1280, height: 800 } });
  const { page, problems } = await openTab(context);
  const first = await sessionOf(page);
  const firstSnapshot = await server.snapshot(first.id, first.token);
  assert.equal(firstSnapshot.character.name, 'human48');

  // a bundled character
  await page.click('#open-character');
  await page.waitForSelector('#open-dialog:not([hidden]) .open-characters li[data-name="human34"] button');
  const listed = await page.$$eval('.open-characters li[data-name]', (lis) => lis.map((li) => li.dataset.name));
  console.log(`bundled characters listed: ${listed.join(', ')}`);
  assert.ok(listed.includes('human48') && listed.includes('human34'), `listed: ${listed}`);
  await page.screenshot({ path: path.join(out, 'open-dialog.png') });
  await page.click('.open-characters li[data-name="human34"] button');
  const second = await switchedFrom(page, first.id);
  assert.equal(second.snapshot.character.name, 'human34');
  assert.notEqual(second.snapshot.q.length, firstSnapshot.q.length);
  assert.ok((await storedIds()).includes(first.id), 'the session left is still saved');
  // the one left is as it was
  assert.deepEqual((await server.snapshot(first.id, first.token)).q, firstSnapshot.q);

  // a character file of one's own (a pindrag JSON figure written here)
  const file = path.join(out, 'two-links.json');
  fs.writeFileSync(
    file,
    JSON.stringify({
      format: 'pindrag-character',
      version: 1,
      name: 'two-links',
      links: [
        { name: 'base', joint: { type: 'free', origin: { xyz: [0, 1, 0] } }, inertial: { mass: 5, com: [0, 0, 0], inertia: { ixx: 0.1, iyy: 0.1, izz: 0.1 } } },
        {
          name: 'arm',
          parent: 'base',
          joint: { name: 'shoulder', type: 'revolute', origin: { xyz: [0, 0.3, 0] }, axis: [1, 0, 0], limits: { lower: -1, upper: 1 } },
          inertial: { mass: 1, com: [0, 0.2, 0], inertia: { ixx: 0.01, iyy: 0.01, izz: 0.01 } },
        },
      ],
    }),
  );
  await openFileFromDialog(page, file);
  const third = await switchedFrom(page, second.id);
  assert.deepEqual(
    third.snapshot.character.links.map((l) => l.name),
    ['base', 'arm'],
  );

  // a saved session: back to the first, which is listed with its character
  await page.click('#open-character');
  await page.waitForSelector(`#open-dialog:not([hidden]) .open-sessions li[data-id="${first.id}"] button`);
  await page.click(`.open-sessions li[data-id="${first.id}"] button`);
  const back = await switchedFrom(page, third.id);
  assert.equal(back.id, first.id);
  assert.deepEqual(back.snapshot.q, firstSnapshot.q);
  assert.deepEqual(problems, []);
  await context.close();
});

test('a malformed character file is refused naming the file; the session stays', async () => {
  const context = await browser.newContext({ viewport: { width: 1280, height: 800 } });
  const { page, problems } = await openTab(context);
  const before = await sessionOf(page);
  const snapshot = await server.snapshot(before.id, before.token);
  const file = path.join(out, 'broken.bvh');
  fs.writeFileSync(file, 'HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0\n');
  const storedBefore = await storedIds();
  await openFileFromDialog(page, file);
  await page.waitForFunction(() => /422/.test(document.querySelector('#open-dialog .open-status')?.textContent || ''), null, {
    timeout: 20000,
  });
  const message = await page.$eval('#open-dialog .open-status', (e) => e.textContent);
  console.log(`malformed file: "${message}"`);
  assert.match(message, /422/);
  assert.match(message, /broken\.bvh/);
  assert.equal((await sessionOf(page)).id, before.id);
  assert.deepEqual((await server.snapshot(before.id, before.token)).q, snapshot.q);
  assert.deepEqual((await storedIds()).sort(), storedBefore.sort(), 'no session was made');
  assert.deepEqual(problems, []);
  await context.close();
});

test('a .gltf chosen together with its .bin opens as a character or a clip; alone it is refused naming the buffer', async () => {
  const context = await browser.newContext({ viewport: { width: 1280, height: 800 } });
  const { page, problems } = await openTab(context);
  const before = await sessionOf(page);
  // this session's figure exported as .gltf, its buffer then moved into a file beside it (the
  // layout of Blender's "glTF Separate")
  const res = await fetch(`${server.url}api/sessions/${before.id}/export?format=gltf`, { headers: { 'X-Session-Token': before.token } });
  assert.equal(res.status, 200);
  const doc = await res.json();
  const uri = doc.buffers[0].uri;
  const dir = path.join(out, 'separate');
  fs.mkdirSync(dir, { recursive: true });
  const gltf = path.join(dir, 'figure.gltf');
  const bin = path.join(dir, 'figure.bin');
  fs.writeFileSync(bin, Buffer.from(uri.slice(uri.indexOf(',') + 1), 'base64'));
  doc.buffers[0].uri = 'figure.bin';
  fs.writeFileSync(gltf, JSON.stringify(doc));

  // as a clip of this human48 session: another skeleton (its 21 bodies), which the mapping editor
  // reads with its buffer
  await page.setInputFiles('#clip-file', [gltf, bin]);
  await page.waitForSelector('#open-dialog:not([hidden]) #edit-mapping', { timeout: 30000 });
  await page.click('#edit-mapping');
  await page.waitForSelector('#mapping-table select', { timeout: 30000 });
  assert.equal(await page.$eval('#mapping-table select[data-source="pelvis"]', (e) => e.value), 'pelvis');
  await page.click('#open-dialog button:has-text("Back")');
  await page.click('#open-dialog button:has-text("Cancel")');
  await page.waitForSelector('#open-dialog', { state: 'hidden' });

  // alone: refused, naming the buffer it needs; this session stays
  const storedBefore = await storedIds();
  await openFileFromDialog(page, gltf);
  await page.waitForFunction(() => /422/.test(document.querySelector('#open-dialog .open-status')?.textContent || ''), null, {
    timeout: 20000,
  });
  const message = await page.$eval('#open-dialog .open-status', (e) => e.textContent);
  assert.match(message, /references the buffer "figure\.bin", which was not sent with it/);
  assert.equal((await sessionOf(page)).id, before.id);
  assert.deepEqual((await storedIds()).sort(), storedBefore.sort(), 'no session was made');

  // chosen together (in either order): a new session on the skinned figure
  await page.setInputFiles('#open-character-file', [bin, gltf]);
  const opened = await switchedFrom(page, before.id);
  assert.equal(opened.snapshot.character.name, 'figure');
  assert.equal(opened.snapshot.character.skinned, true);
  assert.deepEqual(
    opened.snapshot.character.links.slice(0, 3).map((l) => l.name),
    ['pelvis', 'abdomen', 'chest'],
  );
  assert.deepEqual(problems, []);
  await context.close();
});

test('Load clip with another skeleton offers to open it as its own character, clip and all', { skip: noData }, async () => {
  const context = await browser.newContext({ viewport: { width: 1280, height: 800 } });
  const { page, problems } = await openTab(context);
  const before = await sessionOf(page);
  const clip = path.join(DATA_DIR, 'bvh', 'cmu_walk_cgspeed.bvh');
  await page.setInputFiles('#clip-file', clip);
  await page.waitForSelector('#open-dialog:not([hidden]) #open-as-own', { timeout: 30000 });
  const text = await page.$eval('#open-dialog', (e) => e.textContent);
  assert.match(text, /cmu_walk_cgspeed\.bvh animates a skeleton that differs from human48/);
  await page.screenshot({ path: path.join(out, 'another-skeleton.png') });
  await page.click('#open-as-own');
  const opened = await switchedFrom(page, before.id);
  const links = opened.snapshot.character.links.map((l) => l.name);
  console.log(`opened as its own character: ${links.length} links, clip of ${opened.snapshot.clip?.frames} frames`);
  assert.ok(links.includes('Hips') || links.includes('hip'), `links: ${links.slice(0, 5)}`);
  assert.ok(opened.snapshot.clip && opened.snapshot.clip.frames > 100, 'the clip came with it');
  assert.deepEqual(problems, []);
  await context.close();
});

test('Load clip with another skeleton can retarget it onto this character', { skip: noData }, async () => {
  const context = await browser.newContext({ viewport: { width: 1280, height: 800 } });
  const { page, problems } = await openTab(context);
  const before = await sessionOf(page);
  const clip = path.join(DATA_DIR, 'bvh', 'mixamo_naming_freebvh.bvh');
  await page.setInputFiles('#clip-file', clip);
  await page.waitForSelector('#open-dialog:not([hidden]) #retarget-clip', { timeout: 30000 });
  assert.match(await page.$eval('#retarget-clip', (e) => e.textContent), /Retarget it onto human48/);
  await page.click('#retarget-clip');
  await page.waitForSelector('#open-dialog', { state: 'hidden', timeout: 60000 });
  const s = await server.snapshot(before.id, before.token);
  console.log(`retargeted onto human48: clip of ${s.clip?.frames} frames at ${(1 / s.clip?.frame_time).toFixed(1)} fps`);
  assert.equal((await sessionOf(page)).id, before.id, 'the tab stays on its session');
  assert.equal(s.character.name, 'human48');
  assert.ok(s.clip && s.clip.frames > 30, 'the retargeted clip is the clip now');
  assert.deepEqual(problems, []);
  await context.close();
});

test('the mapping editor shows the guess, saves and loads a mapping, and retargets with it', { skip: noData }, async () => {
  const context = await browser.newContext({ viewport: { width: 1280, height: 800 }, acceptDownloads: true });
  const { page, problems } = await openTab(context);
  const before = await sessionOf(page);
  await page.setInputFiles('#clip-file', path.join(DATA_DIR, 'bvh', 'mixamo_naming_freebvh.bvh'));
  await page.waitForSelector('#open-dialog:not([hidden]) #edit-mapping', { timeout: 30000 });
  await page.click('#edit-mapping');
  await page.waitForSelector('#mapping-table select', { timeout: 30000 });
  const target = (source) => page.$eval(`#mapping-table select[data-source="${source}"]`, (s) => s.value);
  const rows = await page.$$eval('#mapping-table select', (all) => all.length);
  console.log(`mapping editor: ${rows} joints; LeftHand → ${await target('mixamorig:LeftHand')}`);
  assert.equal(await target('mixamorig:LeftHand'), 'l_hand');
  assert.equal(await target('mixamorig:Hips'), 'pelvis');
  await page.screenshot({ path: path.join(out, 'mapping-editor.png') });
  // leave the left arm out, save the mapping, and read it back
  for (const joint of ['LeftArm', 'LeftForeArm', 'LeftHand']) await page.selectOption(`#mapping-table select[data-source="mixamorig:${joint}"]`, '');
  const [download] = await Promise.all([page.waitForEvent('download'), page.click('#mapping-save')]);
  const saved = JSON.parse(fs.readFileSync(await download.path(), 'utf8'));
  assert.equal(saved['mixamorig:LeftHand'], null);
  assert.equal(saved['mixamorig:RightHand'], 'r_hand');
  assert.equal(Object.keys(saved).length, rows);
  await page.selectOption('#mapping-table select[data-source="mixamorig:LeftHand"]', 'l_hand');
  const file = path.join(out, 'mapping.json');
  fs.writeFileSync(file, JSON.stringify({ 'mixamorig:LeftHand': null, 'mixamorig:NoSuchJoint': 'l_hand' }));
  await page.setInputFiles('#mapping-file', file);
  await page.waitForFunction(() => /NoSuchJoint/.test(document.querySelector('#open-dialog .open-status')?.textContent || ''), null, { timeout: 5000 });
  assert.equal(await target('mixamorig:LeftHand'), '', 'the loaded mapping did not set its row');
  await page.click('#retarget-mapped');
  await page.waitForSelector('#open-dialog', { state: 'hidden', timeout: 60000 });
  const s = await server.snapshot(before.id, before.token);
  // the left elbow, driven by nothing now, stays near its neutral bend at time 0
  const R = (name) => s.links.find((l) => l.name === name).R;
  const bend = (a, b) => {
    const [p, q] = [R(a), R(b)];
    const dot = Math.abs(p[0] * q[0] + p[1] * q[1] + p[2] * q[2] + p[3] * q[3]);
    return 2 * Math.acos(Math.min(1, dot));
  };
  console.log(`retargeted with the mapping: ${s.clip?.frames} frames; elbow bend left ${bend('l_uarm', 'l_farm').toFixed(3)}, right ${bend('r_uarm', 'r_farm').toFixed(3)} rad`);
  assert.ok(s.clip && s.clip.frames > 30);
  assert.ok(bend('l_uarm', 'l_farm') < 0.1, 'the unmapped left elbow bends with the clip');
  assert.ok(bend('r_uarm', 'r_farm') > 0.1, 'the right elbow does not follow the clip');
  assert.deepEqual(problems.filter((p) => !/NoSuchJoint/.test(p)), []);
  await context.close();
});

/** Switches a view option of the bar over the 3D view (by its label). */
const setView = (page, key, value) =>
  page.evaluate(
    ([k, v]) => {
      const box = [...document.querySelectorAll('#view-options label.toggle')].find((l) => l.textContent.trim() === k);
      const input = box.querySelector('input');
      if (input.checked !== v) input.click();
    },
    [key, value],
  );

test('Load clip with a marker trial fits it onto the human figure, and draws its markers', { skip: noData }, async () => {
  const context = await browser.newContext({ viewport: { width: 1280, height: 800 } });
  const { page, problems } = await openTab(context);
  const before = await sessionOf(page);
  await page.setInputFiles('#clip-file', path.join(DATA_DIR, 'c3d', 'cmu_85_02.c3d'));
  // the fitted clip becomes this session's clip (810 frames at 120 Hz), and the page plays it
  await page.waitForFunction(() => window.pindrag?.session?.clip?.frames === 810, null, { timeout: 60000 });
  const s = await server.snapshot(before.id, before.token);
  console.log(`cmu_85_02.c3d fitted onto ${s.character.name}: clip of ${s.clip?.frames} frames at ${(1 / s.clip?.frame_time).toFixed(1)} fps`);
  assert.equal((await sessionOf(page)).id, before.id, 'the tab stays on its session');
  assert.equal(s.character.name, 'human48');
  assert.ok(s.clip && s.clip.frames === 810, `clip: ${JSON.stringify(s.clip)}`);
  assert.ok(Math.abs(s.clip.frame_time - 1 / 120) < 1e-9);

  // the trial's markers are drawn in the frame shown, each near the figure's virtual marker
  await page.waitForFunction(() => window.pindrag.markers().shown > 30, null, { timeout: 10000 });
  const drawn = await page.evaluate(() => ({ markers: window.pindrag.markers(), time: window.pindrag.lastPose.time }));
  const legend = await page.textContent('#marker-legend');
  console.log(`frame ${drawn.markers.frame}: ${drawn.markers.shown} markers drawn, mean ${(drawn.markers.mean * 1000).toFixed(1)} mm; legend "${legend}"`);
  assert.equal(drawn.markers.frame, Math.round(drawn.time * 120));
  assert.ok(drawn.markers.mean < 0.03, `the markers are ${(drawn.markers.mean * 1000).toFixed(0)} mm from the figure's on average`);
  assert.match(legend, /^markers, frame \d+: \d+ seen, mean \d+ mm, worst \w+ \d+ mm$/);
  // pixels where the measured markers project change when the "markers" option hides them
  const pixels = () =>
    page.evaluate(() =>
      window.pindrag
        .markers()
        .measured.filter(Boolean)
        .map((p) => {
          const s = window.pindrag.projectPoint(p);
          return s.visible ? window.pindrag.pixelAt(s.x, s.y) : null;
        }),
    );
  const shown = await pixels();
  await page.screenshot({ path: path.join(out, 'c3d-markers.png') });
  await setView(page, 'markers', false);
  assert.equal((await page.evaluate(() => window.pindrag.markers())).visible, false);
  assert.equal(await page.isVisible('#marker-legend'), false);
  const hidden = await pixels();
  await setView(page, 'markers', true);
  const onScreen = shown.filter(Boolean).length;
  const changed = shown.filter((c, k) => c && Math.max(...c.map((v, j) => Math.abs(v - hidden[k][j]))) > 10).length;
  console.log(`${changed} of ${onScreen} marker pixels change when the markers are hidden`);
  assert.ok(onScreen > 30 && changed >= 0.8 * onScreen, `only ${changed} of ${onScreen} marker pixels show a marker`);
  // the last frame shows the last frame's markers
  await page.click('#tl-last');
  await page.waitForFunction(() => window.pindrag.markers().frame === 809, null, { timeout: 5000 });
  assert.ok((await page.evaluate(() => window.pindrag.markers())).mean < 0.03);
  assert.deepEqual(problems, []);
  await context.close();
});

test('a BVH character opens in the unit guessed from its height, or in the unit chosen', { skip: noData }, async () => {
  const context = await browser.newContext({ viewport: { width: 1280, height: 800 } });
  const { page, problems } = await openTab(context);
  const file = path.join(DATA_DIR, 'bvh', 'cmu_walk_cgspeed.bvh');
  const heights = {};
  for (const units of ['auto', 'm']) {
    const from = await sessionOf(page);
    await openFileFromDialog(page, file, units);
    const opened = await switchedFrom(page, from.id);
    heights[units] = { height: opened.snapshot.character.height, unit: opened.snapshot.character.unit };
  }
  console.log(`cmu_walk_cgspeed.bvh: ${JSON.stringify(heights)}`);
  const guessed = heights.auto;
  assert.ok(guessed.height > 1.2 && guessed.height < 2.2, `guessed unit gives a ${guessed.height} m figure`);
  assert.notEqual(guessed.unit, 'metres');
  assert.equal(heights.m.unit, 'metres');
  // the same file in metres: the figure is as many metres tall as it is units tall
  const scales = { centimetres: 0.01, millimetres: 0.001, inches: 0.0254, 'CMU units (1/0.45 inch)': 2.54 / 45 };
  assert.ok(guessed.unit in scales, `unit ${guessed.unit}`);
  assert.ok(Math.abs(heights.m.height * scales[guessed.unit] - guessed.height) < 1e-9 * heights.m.height);
  // a unit that is not one of them is refused naming the field
  const form = new FormData();
  form.append('character', new Blob([fs.readFileSync(file)]), 'walk.bvh');
  form.append('units', 'furlong');
  const refused = await fetch(`${server.url}api/sessions`, { method: 'POST', body: form });
  assert.equal(refused.status, 400);
  assert.match((await refused.json()).error, /^units: 'furlong' \(rule: one of auto, m, cm, mm, in, cmu\)/);
  // the dialog says which unit the open character was read in
  await page.click('#open-character');
  await page.waitForSelector('#open-dialog:not([hidden]) #open-current-unit');
  assert.match(await page.$eval('#open-current-unit', (e) => e.textContent), /metres/);
  assert.deepEqual(problems, []);
  await context.close();
});

test('every file of the shared bvh, gltf and urdf folders opens as a session', { skip: noData }, async () => {
  const files = [];
  for (const dir of ['bvh', 'gltf', 'urdf']) {
    const walk = (d) => {
      for (const e of fs.readdirSync(d, { withFileTypes: true })) {
        const p = path.join(d, e.name);
        if (e.isDirectory()) {
          if (e.name !== 'meshes') walk(p); // a robot's visual meshes are parts, not characters
        }
        else if (/\.(bvh|glb|gltf|fbx|dae|urdf)$/i.test(e.name)) files.push(p);
      }
    };
    walk(path.join(DATA_DIR, dir));
  }
  assert.ok(files.length >= 10, `found ${files.length} files`);
  for (const file of files) {
    const form = new FormData();
    form.append('character', new Blob([fs.readFileSync(file)]), path.basename(file));
    const res = await fetch(`${server.url}api/sessions`, { method: 'POST', body: form });
    const body = await res.text();
    assert.equal(res.status, 201, `${path.relative(DATA_DIR, file)}: ${res.status} ${body}`);
    const { id, token } = JSON.parse(body);
    const s = await server.snapshot(id, token);
    console.log(`${path.relative(DATA_DIR, file)}: ${s.character.links.length} links, clip ${s.clip ? s.clip.frames : 0} frames`);
    assert.ok(s.character.links.length >= 2, `${file}: ${s.character.links.length} links`);
    // every figure stands on the ground (its lowest point at y = 0), none of its links under it
    const lowest = Math.min(...s.links.map((l) => l.p[1]));
    console.log(`  root ${s.character.links[0].joint_type}, lowest link origin at y = ${lowest.toFixed(3)} m`);
    assert.ok(lowest >= -1e-6, `${file}: a link origin at y = ${lowest}`);
    if (file.endsWith('.urdf')) {
      // robot descriptions (all legged here) stand on a free root
      assert.equal(s.character.links[0].joint_type, 'free', `${file}: the root of a legged robot floats`);
    }
  }
});
