// Editing in motion in the page with `pindrag serve` in headless Chromium: a clip recorded with
// the mouse plays at 1× in a loop; a pin on a link the clip moves is drawn where that link is at
// every frame shown; the other hand grabbed while the clip plays, and held while the loop comes
// round, makes one edit layer, listed in the layers panel, which mutes and deletes it; the grab
// leaves the camera where it was.
// Screenshots go to web-test-output/motion_editing/.
// Usage: node tests/web/motion_editing_test.mjs PINDRAG_BINARY   (or PINDRAG_BIN=...)

import { test, before } from 'node:test';
import assert from 'node:assert/strict';
import path from 'node:path';
import { openPage, settle } from './support/browser.mjs';
import { serverAndBrowser } from './support/fixture.mjs';
import { dist, handle, serverSnapshot, waitForServer } from './support/session_page.mjs';

const fixture = await serverAndBrowser('motion_editing');
const out = fixture.out;

let browser;
let server;
before(async () => ({ server, browser } = await fixture.start()));

const session = (page) => page.evaluate(() => window.pindrag.session);

/**
 * Records a link (the right hand) moved with the mouse; it becomes the clip. The gesture lasts at
 * least a second and `moves` pointer moves, and goes on (up to 10 s) until the server has moved the
 * link `minTravel` metres: a slow server still records a clip that moves. What the clip shows is
 * checked by the tests; a server that does not follow the drag fails here, saying so.
 */
async function recordClip(page, link = 'r_hand', path = (k) => ({ dx: k, dy: -60 * Math.sin((Math.PI * k) / 6) }), { moves = 12, minTravel = 0.05 } = {}) {
  const from = await handle(page, link);
  // the link's largest distance from where it started, kept by the page at every frame it draws
  const watchTravel = (n) => {
    const s = window.pindrag.linkPosition(n);
    window.recordTravel = { travel: 0, on: true };
    const watch = () => {
      const p = window.pindrag.linkPosition(n);
      window.recordTravel.travel = Math.max(window.recordTravel.travel, Math.hypot(p[0] - s[0], p[1] - s[1], p[2] - s[2]));
      if (window.recordTravel.on) requestAnimationFrame(watch);
    };
    requestAnimationFrame(watch);
  };
  await page.evaluate(watchTravel, link);
  // (the record button blinks while recording: clicked without waiting for it to stand still)
  const toggleRecord = () => page.$eval('#tl-record', (b) => b.click());
  await toggleRecord();
  await page.waitForFunction(() => window.pindrag.session?.recording === true, null, { timeout: 5000 });
  await page.mouse.move(from.x, from.y);
  await page.mouse.down();
  const start = Date.now();
  let travel = 0;
  for (let k = 1; ; k++) {
    const { dx, dy } = path(k);
    await page.mouse.move(from.x + dx, from.y + dy);
    await page.waitForTimeout(30);
    if (k < moves || Date.now() - start < 1000) continue;
    travel = await page.evaluate(() => window.recordTravel.travel);
    if (travel > minTravel || Date.now() - start > 10000) break;
  }
  await page.evaluate(() => (window.recordTravel.on = false));
  console.log(`recorded ${link}: ${(travel * 100).toFixed(1)} cm in ${Date.now() - start} ms`);
  await page.mouse.up();
  await page.waitForTimeout(150);
  await toggleRecord();
  await page.waitForFunction(() => window.pindrag.session?.recording === false && window.pindrag.session?.clip?.frames > 10, null, { timeout: 5000 });
  assert.ok(travel > minTravel, `the server moved ${link} only ${(travel * 100).toFixed(1)} cm in 10 s of dragging it`);
  return session(page);
}

/** Clicks a timeline button that seeks, and waits until the page shows the pose of time `t`. */
async function seek(page, button, t) {
  const before = await page.evaluate(() => window.pindrag.lastPose?.frame ?? -1);
  await page.click(button);
  await page.waitForFunction(([f, time]) => window.pindrag.lastPose?.frame > f && Math.abs(window.pindrag.lastPose.time - time) < 1e-6, [before, t], { timeout: 5000 });
}

test('a grab held while a looping clip plays makes one layer, listed and managed in the panel', async () => {
  const t0 = Date.now();
  const phase = (what) => console.log(`${what}: ${((Date.now() - t0) / 1000).toFixed(1)} s`);
  const { page, context, problems } = await openPage(browser, server.url);
  phase('page open');
  const recorded = await recordClip(page);
  console.log(`recorded clip: ${recorded.clip.frames} frames, ${recorded.clip.duration.toFixed(2)} s`);
  phase('recorded');
  if (!recorded.playback.loop) await page.click('#tl-loop');
  await page.waitForFunction(() => window.pindrag.session?.playback?.loop === true);

  // a pin on the right hand, which the clip moves; then play at 1x
  // (the pose can read time 0 before the seek: the seek's own pose is awaited, so the right click
  // lands on the hand where frame 0 places it)
  await seek(page, '#tl-first', 0);
  const h = await handle(page, 'r_hand');
  await page.mouse.click(h.x, h.y, { button: 'right' });
  await page
    .waitForFunction(() => (window.pindrag.session?.pins || []).some((p) => p.link === 'r_hand'), null, { timeout: 5000 })
    .catch(async (err) => {
      const now = await page.evaluate(() => ({ pins: window.pindrag.session?.pins, pose: window.pindrag.lastPose, hand: window.pindrag.project('r_hand') }));
      throw new Error(`a right click at (${h.x.toFixed(0)}, ${h.y.toFixed(0)}) did not pin the right hand: ${JSON.stringify(now)} (${err.message})`);
    });
  await page.click('#tl-play');
  await page.waitForFunction(() => window.pindrag.session?.playback?.playing === true);

  phase('playing');
  // the pin marker is drawn on the hand at every frame shown, sampled over a whole loop (a
  // recording on a busy machine can start with a second in which the hand has not moved yet)
  let markerOff = 0;
  const markers = [];
  const sampling = Date.now();
  for (let k = 0; k < 12 || Date.now() - sampling < recorded.clip.duration * 1000 + 200; k++) {
    const { marker, hand } = await page.evaluate(() => ({ marker: window.pindrag.pinMarker('r_hand'), hand: window.pindrag.linkPosition('r_hand') }));
    markerOff = Math.max(markerOff, dist(marker, hand));
    markers.push(marker);
    await page.waitForTimeout(70);
  }
  const markerTravel = Math.max(...markers.map((m) => dist(m, markers[0])));
  console.log(`pin marker: at most ${(markerOff * 1000).toFixed(3)} mm from the hand, travelled ${(markerTravel * 100).toFixed(1)} cm`);
  assert.ok(markerOff < 1e-3, `the pin marker was ${(markerOff * 1000).toFixed(1)} mm from its link`);
  assert.ok(markerTravel > 0.02, `the pin marker stayed put (${(markerTravel * 100).toFixed(1)} cm) while the clip moved the hand`);

  phase('markers checked');
  const camera = await page.evaluate(() => window.pindrag.camera());

  // the left hand grabbed while the clip plays, held for longer than the loop
  const grab = await handle(page, 'l_hand');
  await page.mouse.move(grab.x, grab.y);
  await page.mouse.down();
  const holdMs = Math.max(1500, recorded.clip.duration * 1000 * 1.6);
  const steps = Math.round(holdMs / 50);
  for (let k = 1; k <= steps; k++) {
    await page.mouse.move(grab.x - Math.min(k, 20) * 2, grab.y - Math.min(k, 20) * 3);
    await page.waitForTimeout(50);
  }
  await page.screenshot({ path: path.join(out, 'grabbed.png') });
  await page.mouse.up();
  assert.deepEqual(await page.evaluate(() => window.pindrag.camera()), camera, 'the grab orbited the camera');

  phase('released');
  const withLayer = await waitForServer(server, page, (s) => s.layers.length > 0, 'no layer after the grab');
  await page.waitForTimeout(300);
  const layers = (await serverSnapshot(server, page)).layers;
  console.log(`layers after one grab: ${JSON.stringify(layers)}`);
  assert.equal(layers.length, 1, `one grab across the loop made ${layers.length} layers`);
  assert.equal(withLayer.layers[0].first_frame, 0, 'the layer should span the loop it came round');
  await page.waitForFunction(() => document.querySelectorAll('#layer-list li').length === 1, null, { timeout: 5000 });
  const text = await page.textContent('#layer-list li');
  assert.match(text, /edit 1/);

  // mute, then delete, from the panel
  await page.click('#layer-list li .layer-mute');
  await waitForServer(server, page, (s) => s.layers[0]?.muted === true, 'muting from the panel did not reach the server');
  await page.click('#layer-list li .layer-remove');
  await waitForServer(server, page, (s) => s.layers.length === 0, 'deleting from the panel did not reach the server');
  await page.waitForFunction(() => document.querySelectorAll('#layer-list li').length === 0, null, { timeout: 5000 });
  phase('layer muted and deleted');
  await page.screenshot({ path: path.join(out, 'layers.png') });
  assert.deepEqual(problems, []);
  await context.close();
});

test('"follow" keeps the camera on a travelling figure, and "slow while dragging" slows the clip for the gesture only', async () => {
  const { page, context, problems } = await openPage(browser, server.url);
  const recorded = await recordClip(page, 'pelvis', (k) => ({ dx: Math.min(6 * k, 120), dy: 0 }), { moves: 20 }); // the root travels sideways
  await page.click('#view-options label:has-text("follow") input');
  await seek(page, '#tl-first', 0);
  await settle(page);
  const camera0 = await page.evaluate(() => window.pindrag.camera());
  const root0 = await page.evaluate(() => window.pindrag.linkPosition('pelvis'));
  await seek(page, '#tl-last', recorded.playback.duration);
  await settle(page);
  const camera1 = await page.evaluate(() => window.pindrag.camera());
  const root1 = await page.evaluate(() => window.pindrag.linkPosition('pelvis'));
  const moved = Math.hypot(root1[0] - root0[0], root1[2] - root0[2]);
  const off = Math.hypot(camera1.target[0] - camera0.target[0] - (root1[0] - root0[0]), camera1.target[2] - camera0.target[2] - (root1[2] - root0[2]));
  console.log(`follow: the root travelled ${(moved * 100).toFixed(1)} cm; the camera target followed it to ${(off * 1000).toFixed(3)} mm`);
  assert.ok(moved > 0.015, `the recorded clip moved the root only ${(moved * 100).toFixed(1)} cm`);
  assert.ok(off < 1e-3, `the camera target is ${(off * 1000).toFixed(1)} mm off the root's motion`);

  // slow while dragging: a quarter speed while the hand is held, the speed it had after
  await page.selectOption('#while-dragging', 'slow');
  await page.click('#tl-play');
  await page.waitForFunction(() => window.pindrag.session?.playback?.playing === true);
  const grab = await handle(page, 'l_hand');
  await page.mouse.move(grab.x, grab.y);
  await page.mouse.down();
  await page.mouse.move(grab.x - 20, grab.y - 30, { steps: 4 });
  const cameraInDrag = await page.evaluate(() => window.pindrag.camera());
  const slowed = await waitForServer(server, page, (s) => s.playback.speed !== 1, 'the clip did not slow down while the hand was held');
  await page.waitForTimeout(300);
  assert.deepEqual(await page.evaluate(() => window.pindrag.camera()), cameraInDrag, 'the camera followed during the drag');
  await page.mouse.up();
  const restored = await waitForServer(server, page, (s) => s.playback.speed === 1, 'the speed did not come back after the release');
  console.log(`while dragging: speed ${slowed.playback.speed}; after: ${restored.playback.speed}`);
  assert.equal(slowed.playback.speed, 0.25);
  assert.deepEqual(problems, []);
  await context.close();
});
