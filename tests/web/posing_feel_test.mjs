// Posing feel with `pindrag serve` in headless Chromium, sampled while the pointer is held (not
// only at the end of the gesture): with both feet pinned, a squat dragged at the pelvis keeps
// each foot within 1 mm of its pin on every sample and the torso upright; with nothing pinned, a
// hand dragged up keeps the feet where they stand on the floor. Screenshots go to
// web-test-output/posing_feel/.
// Usage: node tests/web/posing_feel_test.mjs PINDRAG_BINARY   (or PINDRAG_BIN=...)

import { test, before } from 'node:test';
import assert from 'node:assert/strict';
import path from 'node:path';
import { openPage, settle } from './support/browser.mjs';
import { serverAndBrowser } from './support/fixture.mjs';
import { linkP, dist, handle, serverSnapshot as snapshotOf } from './support/session_page.mjs';

const fixture = await serverAndBrowser('posing_feel');
const out = fixture.out;
const PIN_TOLERANCE_M = 1e-3;
const SAMPLE_MS = 100;

let browser;
let server;
before(async () => ({ server, browser } = await fixture.start()));

const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
const angle = (a, b) => {
  const c = (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) / (Math.hypot(...a) * Math.hypot(...b));
  return Math.acos(Math.max(-1, Math.min(1, c)));
};

const serverSnapshot = (page) => snapshotOf(server, page);

/**
 * Drags `link` by `offset` (metres, world) with the mouse in 10 moves 50 ms apart, holds it for
 * `holdMs`, and samples the server's snapshot every SAMPLE_MS from the press to the release.
 * Returns the snapshots taken while the pointer was held.
 */
async function dragSampling(page, link, offset, holdMs = 800) {
  const s0 = await serverSnapshot(page);
  const p0 = linkP(s0, link);
  const from = await handle(page, link);
  const to = await page.evaluate((p) => window.pindrag.projectPoint(p), [p0[0] + offset[0], p0[1] + offset[1], p0[2] + offset[2]]);
  assert.ok(to.visible, `the drag target of ${link} is not on screen`);
  const samples = [];
  let sampling = true;
  const sampler = (async () => {
    while (sampling) {
      samples.push(await serverSnapshot(page));
      await new Promise((r) => setTimeout(r, SAMPLE_MS));
    }
  })();
  await page.mouse.move(from.x, from.y);
  await page.mouse.down();
  const steps = 10;
  for (let k = 1; k <= steps; k++) {
    await page.mouse.move(from.x + ((to.x - from.x) * k) / steps, from.y + ((to.y - from.y) * k) / steps);
    await page.waitForTimeout(50);
  }
  await page.waitForTimeout(holdMs);
  sampling = false;
  await sampler;
  await settle(page);
  return { samples, release: async () => page.mouse.up() };
}

test('with both feet pinned, a squat keeps each foot within 1 mm of its pin on every sample', async () => {
  const { page, context, problems } = await openPage(browser, server.url);
  for (const foot of ['l_foot', 'r_foot']) {
    const h = await handle(page, foot);
    await page.mouse.click(h.x, h.y, { button: 'right' });
    await page.waitForFunction((f) => (window.pindrag.session?.pins || []).some((p) => p.link === f), foot, { timeout: 5000 });
  }
  const s0 = await serverSnapshot(page);
  assert.deepEqual(s0.pins.map((p) => p.link).sort(), ['l_foot', 'r_foot']);
  const feet0 = { l_foot: linkP(s0, 'l_foot'), r_foot: linkP(s0, 'r_foot') };
  const torso0 = sub(linkP(s0, 'neck'), linkP(s0, 'pelvis'));
  const pelvis0 = linkP(s0, 'pelvis');

  const { samples, release } = await dragSampling(page, 'pelvis', [0, -0.12, 0]);
  let drift = 0;
  for (const s of samples) {
    for (const foot of ['l_foot', 'r_foot']) drift = Math.max(drift, dist(linkP(s, foot), feet0[foot]));
  }
  const last = samples[samples.length - 1];
  const drop = pelvis0[1] - linkP(last, 'pelvis')[1];
  const tilt = angle(sub(linkP(last, 'neck'), linkP(last, 'pelvis')), torso0);
  await page.screenshot({ path: path.join(out, 'squat.png') });
  await release();
  console.log(
    `squat: pelvis down ${(drop * 100).toFixed(1)} cm; largest foot drift ${(drift * 1000).toFixed(3)} mm over ` +
      `${samples.length} samples; torso tilted ${tilt.toFixed(3)} rad`,
  );
  assert.ok(samples.length >= 8, `only ${samples.length} samples while the pointer was held`);
  assert.ok(drop > 0.06, `the pelvis went down only ${(drop * 100).toFixed(1)} cm`);
  assert.ok(drift <= PIN_TOLERANCE_M, `a pinned foot drifted ${(drift * 1000).toFixed(3)} mm while the pointer was held`);
  assert.ok(tilt < 0.2, `the torso tilted ${tilt.toFixed(3)} rad`);
  assert.deepEqual(problems, []);
  await context.close();
});

test('with nothing pinned, a hand dragged up keeps the feet where they stand', async () => {
  const { page, context, problems } = await openPage(browser, server.url);
  const s0 = await serverSnapshot(page);
  assert.deepEqual(s0.pins, []);
  const feet0 = { l_foot: linkP(s0, 'l_foot'), r_foot: linkP(s0, 'r_foot') };
  const hand0 = linkP(s0, 'r_hand');

  const { samples, release } = await dragSampling(page, 'r_hand', [0, 0.3, 0.1]);
  let drift = 0;
  for (const s of samples) {
    for (const foot of ['l_foot', 'r_foot']) drift = Math.max(drift, dist(linkP(s, foot), feet0[foot]));
  }
  const lift = linkP(samples[samples.length - 1], 'r_hand')[1] - hand0[1];
  await page.screenshot({ path: path.join(out, 'hand_up.png') });
  await release();
  console.log(`hand up ${(lift * 100).toFixed(1)} cm; feet moved at most ${(drift * 1000).toFixed(3)} mm over ${samples.length} samples`);
  assert.ok(lift > 0.1, `the hand went up only ${(lift * 100).toFixed(1)} cm`);
  assert.ok(drift <= PIN_TOLERANCE_M, `the feet moved ${(drift * 1000).toFixed(3)} mm: the figure left the floor`);
  assert.deepEqual(problems, []);
  await context.close();
});
