// The page and `pindrag serve` end to end in headless Chromium: the figure is drawn; dragging the
// right hand's handle changes the server's pose and not the camera; with the left foot pinned,
// dragging the pelvis keeps the foot within 1 mm; a key, playback and a BVH export that parses;
// undo and redo of a drag. Screenshots go to web-test-output/ in the working directory.
// Usage: node tests/web/pose_editing_test.mjs PINDRAG_BINARY   (or PINDRAG_BIN=...)

import { test, before } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import { pathToFileURL } from 'node:url';
import { NODE_MODULES } from './support/env.mjs';
import { openPage, dragMouse, canvasStats, settle } from './support/browser.mjs';
import { serverAndBrowser } from './support/fixture.mjs';
import { linkP, dist, handle, serverSnapshot as snapshotOf, waitForServer as waitFor } from './support/session_page.mjs';

const fixture = await serverAndBrowser('pose_editing');
const out = fixture.out;
const FOOT_TOLERANCE_M = 1e-3;
const SETTLE_MS = 600; // hold the pointer still this long before releasing, so the solver catches up

let browser;
let server;
before(async () => ({ server, browser } = await fixture.start()));

const serverSnapshot = (page) => snapshotOf(server, page);
const waitForServer = (page, ok, what, timeoutMs) => waitFor(server, page, ok, what, timeoutMs);

/** Drags with the pointer held still at the end for a moment. */
async function dragAndHold(page, from, to) {
  await page.mouse.move(from.x, from.y);
  await page.mouse.down();
  await dragMouse(page, from, to, { steps: 8, skipPressRelease: true });
  await page.waitForTimeout(SETTLE_MS);
  await page.mouse.up();
  await page.waitForTimeout(200);
}

test('the canvas shows the figure', async () => {
  const { page, context, problems } = await openPage(browser, server.url);
  assert.equal(await page.evaluate(() => window.pindrag.contextLost()), false);
  const stats = await canvasStats(page);
  assert.ok(stats.colours > 200, `the canvas has only ${stats.colours} colours`);
  assert.ok(stats.luminanceStd > 5, `the canvas is nearly flat (luminance std ${stats.luminanceStd.toFixed(2)})`);
  await page.screenshot({ path: path.join(out, 'loaded.png') });
  assert.deepEqual(problems, []);
  await context.close();
});

test('dragging the right hand changes the server pose, not the camera; undo and redo', async () => {
  const { page, context, problems } = await openPage(browser, server.url);
  const before0 = await serverSnapshot(page);
  const hand0 = linkP(before0, 'r_hand');
  const camera = await page.evaluate(() => window.pindrag.camera());
  const A = await handle(page, 'r_hand');
  const B = { x: A.x - 90, y: A.y - 110 };
  await dragAndHold(page, A, B);

  const after1 = await waitForServer(page, (s) => dist(linkP(s, 'r_hand'), hand0) > 0.05, 'the server did not move the right hand by 5 cm');
  const hand1 = linkP(after1, 'r_hand');
  const onScreen = await page.evaluate((p) => window.pindrag.projectPoint(p), hand1);
  const pixelsLeft = Math.hypot(onScreen.x - B.x, onScreen.y - B.y);
  const pixelsDragged = Math.hypot(B.x - A.x, B.y - A.y);
  console.log(`right hand moved ${(dist(hand1, hand0) * 100).toFixed(1)} cm; ${pixelsLeft.toFixed(1)} px from the release point after a ${pixelsDragged.toFixed(0)} px drag`);
  assert.ok(pixelsLeft < 0.5 * pixelsDragged, `the hand ended ${pixelsLeft.toFixed(0)} px from where it was dragged to`);
  assert.deepEqual(await page.evaluate(() => window.pindrag.camera()), camera, 'the camera moved during the drag');
  await page.screenshot({ path: path.join(out, 'dragged_hand.png') });

  await page.keyboard.press('Control+z');
  await waitForServer(page, (s) => dist(linkP(s, 'r_hand'), hand0) < 1e-3, 'undo did not put the right hand back');
  await page.keyboard.press('Control+Shift+z');
  await waitForServer(page, (s) => dist(linkP(s, 'r_hand'), hand1) < 1e-3, 'redo did not restore the dragged pose');
  assert.deepEqual(problems, []);
  await context.close();
});

test('with the left foot pinned, dragging the pelvis keeps the foot within 1 mm', async () => {
  const { page, context, problems } = await openPage(browser, server.url);
  const foot = await handle(page, 'l_foot');
  await page.mouse.click(foot.x, foot.y, { button: 'right' });
  await page.waitForFunction(() => (window.pindrag.session?.pins || []).some((p) => p.link === 'l_foot'), null, { timeout: 5000 });
  const pinned = await serverSnapshot(page);
  assert.deepEqual(pinned.pins.map((p) => p.link), ['l_foot'], 'the server does not have the left foot pinned');
  const foot0 = linkP(pinned, 'l_foot');
  const pelvis0 = linkP(pinned, 'pelvis');

  const A = await handle(page, 'pelvis');
  await dragAndHold(page, A, { x: A.x + 30, y: A.y + 20 });
  const moved = await waitForServer(page, (s) => dist(linkP(s, 'pelvis'), pelvis0) > 0.03, 'the server did not move the pelvis by 3 cm');
  const drift = dist(linkP(moved, 'l_foot'), foot0);
  console.log(`pelvis moved ${(dist(linkP(moved, 'pelvis'), pelvis0) * 100).toFixed(1)} cm; pinned foot drifted ${(drift * 1000).toFixed(3)} mm`);
  assert.ok(drift <= FOOT_TOLERANCE_M, `the pinned foot drifted ${(drift * 1000).toFixed(3)} mm`);

  // more gestures for the picture: the right hand up and out, the left hand forward; the left knee
  // selected to show its hinge range
  const right = await handle(page, 'r_hand');
  await dragAndHold(page, right, { x: right.x - 110, y: right.y - 70 });
  const left = await handle(page, 'l_hand');
  await dragAndHold(page, left, { x: left.x + 40, y: left.y - 90 });
  const knee = await handle(page, 'l_shank');
  await page.mouse.click(knee.x, knee.y);
  await page.mouse.move(5, 5);
  await settle(page);
  await page.screenshot({ path: path.join(out, 'pinned_foot_drag.png') });
  assert.deepEqual(problems, []);
  await context.close();
});

test('keys at 0 s and 1 s, play, and export BVH that three.js parses', async () => {
  const { page, context, problems } = await openPage(browser, server.url);
  await page.keyboard.press('i');
  await page.waitForFunction(() => (window.pindrag.session?.keys || []).length === 1, null, { timeout: 5000 });
  // scrub to the middle of the empty 2 s timeline, pose the right hand, key it
  const track = await page.locator('#tl-track').boundingBox();
  await page.mouse.click(track.x + track.width / 2, track.y + track.height / 2);
  await page.waitForFunction(() => Math.abs(window.pindrag.timeCursor - 1) < 0.02, null, { timeout: 5000 });
  const hand = await handle(page, 'r_hand');
  await dragAndHold(page, hand, { x: hand.x - 60, y: hand.y - 120 });
  await page.keyboard.press('i');
  await page.waitForFunction(() => (window.pindrag.session?.keys || []).length === 2, null, { timeout: 5000 });
  const keyTimes = (await serverSnapshot(page)).keys.map((k) => k.time);
  assert.ok(Math.abs(keyTimes[1] - 1) < 0.02, `the second key is at ${keyTimes[1]} s, not 1 s`);

  await page.keyboard.press('Home');
  await page.keyboard.press('Space');
  await page.waitForFunction(() => window.pindrag.session?.playback?.playing === true, null, { timeout: 5000 });
  await page.waitForFunction(() => (window.pindrag.lastPose?.time ?? 0) > 0.1, null, { timeout: 10000 });
  await page.keyboard.press('Space');
  await page.waitForFunction(() => window.pindrag.session?.playback?.playing === false, null, { timeout: 5000 });

  const [download] = await Promise.all([page.waitForEvent('download'), page.click('#export-bvh')]);
  const file = path.join(out, download.suggestedFilename() || 'export.bvh');
  await download.saveAs(file);
  const text = fs.readFileSync(file, 'utf8');
  const { BVHLoader } = await import(pathToFileURL(path.join(NODE_MODULES, 'three/examples/jsm/loaders/BVHLoader.js')).href);
  const parsed = new BVHLoader().parse(text);
  const links = (await serverSnapshot(page)).links.length;
  const bones = parsed.skeleton.bones.length;
  console.log(`${path.basename(file)}: ${text.length} bytes, ${bones} bones, ${parsed.clip.tracks.length} tracks, ${parsed.clip.duration.toFixed(3)} s`);
  assert.ok(bones >= links, `the BVH has ${bones} bones for ${links} links`);
  assert.ok(parsed.clip.tracks.length > 0, 'the BVH has no animation tracks');
  assert.ok(parsed.clip.tracks.every((t) => t.times.length >= 2 && t.values.every(Number.isFinite)), 'a BVH track has under 2 frames or non-finite values');
  assert.ok(parsed.clip.duration >= keyTimes[1] - 0.05, `the BVH lasts ${parsed.clip.duration} s, less than the keys span`);
  await page.screenshot({ path: path.join(out, 'keyed.png') });
  assert.deepEqual(problems, []);
  await context.close();
});
