// The effects panel and the physics view with `pindrag serve` in headless Chromium: "Stand" makes
// the server simulate the figure standing (the pose frames carry the physics object, the panel
// shows each effect's cost); dragging the left hand 12 cm down with the mouse moves the pelvis
// sideways away from the hand while the centre of pressure stays inside the support polygon;
// "Pose" returns to kinematic posing. The screenshot (contact arrows, support polygon) goes to
// web-test-output/physics_stand/.
// Usage: node tests/web/physics_stand_test.mjs PINDRAG_BINARY   (or PINDRAG_BIN=...)

import { test, before } from 'node:test';
import assert from 'node:assert/strict';
import path from 'node:path';
import { openPage, settle } from './support/browser.mjs';
import { serverAndBrowser } from './support/fixture.mjs';
import { linkP, serverSnapshot } from './support/session_page.mjs';

const fixture = await serverAndBrowser('physics_stand');
const out = fixture.out;
const DRAG_DOWN_M = 0.12;
const COP_TOLERANCE_M = 0.01;

let browser;
let server;
before(async () => ({ server, browser } = await fixture.start()));

const serverLink = async (page, name) => linkP(await serverSnapshot(server, page), name);

const physicsNow = (page) => page.evaluate(() => window.pindrag.lastPose?.physics ?? null);

/** Distance (m) in x–z from p to the segment a–b. */
function segmentDistance(p, a, b) {
  const ex = b[0] - a[0];
  const ez = b[2] - a[2];
  const t = Math.max(0, Math.min(1, ((p[0] - a[0]) * ex + (p[2] - a[2]) * ez) / (ex * ex + ez * ez || 1)));
  return Math.hypot(p[0] - a[0] - t * ex, p[2] - a[2] - t * ez);
}

/** Distance (m) from the ground point p to the convex polygon (x–z), 0 inside; a polygon of one
 * or two points is a point or a segment (as sim::inside_polygon reads it). */
function outsidePolygon(p, polygon) {
  const n = polygon.length;
  if (n === 0) return Infinity;
  if (n < 3) return segmentDistance(p, polygon[0], polygon[n - 1]);
  let sign = 0;
  let inside = true;
  let nearest = Infinity;
  for (let i = 0; i < n; i++) {
    const a = polygon[i];
    const b = polygon[(i + 1) % n];
    const cross = (b[0] - a[0]) * (p[2] - a[2]) - (b[2] - a[2]) * (p[0] - a[0]);
    if (cross !== 0) {
      if (sign === 0) sign = Math.sign(cross);
      else if (Math.sign(cross) !== sign) inside = false;
    }
    nearest = Math.min(nearest, segmentDistance(p, a, b));
  }
  return inside ? 0 : nearest;
}

test('Stand, then a drag of the left hand down moves the pelvis away from it', async () => {
  const { page, context, problems } = await openPage(browser, server.url);
  await page.click('#preset-stand');
  await page.waitForFunction(() => window.pindrag.session?.scene?.dynamic_pins === true, null, { timeout: 5000 });
  await page.waitForFunction(() => window.pindrag.lastPose?.physics?.contacts?.length > 0, null, { timeout: 5000 });
  for (const id of ['gravity', 'ground_contact', 'friction', 'dynamic_pins']) {
    assert.equal(await page.isChecked(`#effect-${id}`), true, `${id} is not switched on`);
  }
  await page.waitForTimeout(800); // standing settles
  const shown = await page.textContent('[data-effect="dynamic_pins"]');
  assert.ok(Number(shown) > 0, `the dynamic pins' cost reads '${shown}'`);
  assert.equal(await page.isVisible('#balance-banner'), false, 'the figure standing still is said to be off balance');

  const pelvis0 = await serverLink(page, 'pelvis');
  const hand0 = await serverLink(page, 'l_hand');
  assert.ok(hand0[0] > pelvis0[0], 'the left hand is not on the +x side of the pelvis');
  const from = await page.evaluate((n) => window.pindrag.project(n), 'l_hand');
  const to = await page.evaluate((p) => window.pindrag.projectPoint(p), [hand0[0], hand0[1] - DRAG_DOWN_M, hand0[2]]);
  assert.ok(from.visible && to.visible, 'the left hand is not on screen');

  await page.mouse.move(from.x, from.y);
  await page.mouse.down();
  const steps = 10;
  for (let k = 1; k <= steps; k++) {
    await page.mouse.move(from.x + ((to.x - from.x) * k) / steps, from.y + ((to.y - from.y) * k) / steps);
    await page.waitForTimeout(50);
  }
  // while held: the centre of pressure stays in the support polygon, frame after frame
  let worst = 0;
  let unbalanced = 0;
  for (let k = 0; k < 10; k++) {
    await page.waitForTimeout(60);
    const physics = await physicsNow(page);
    assert.ok(physics && physics.cop, 'the figure left the ground');
    worst = Math.max(worst, outsidePolygon(physics.cop, physics.support_polygon));
    if (!physics.balanced) ++unbalanced;
  }
  const pelvis1 = await serverLink(page, 'pelvis');
  const hand1 = await serverLink(page, 'l_hand');
  await settle(page);
  await page.screenshot({ path: path.join(out, 'stand_drag_left_hand.png') });
  await page.mouse.up();

  const shift = pelvis1[0] - pelvis0[0];
  console.log(
    `left hand down ${((hand0[1] - hand1[1]) * 100).toFixed(1)} cm; pelvis moved ${(shift * 100).toFixed(1)} cm in x; ` +
      `centre of pressure at most ${(worst * 1000).toFixed(1)} mm outside the support polygon`,
  );
  assert.ok(hand1[1] < hand0[1] - 0.04, 'the left hand did not go down');
  assert.ok(shift < -0.01, `the pelvis moved ${(shift * 100).toFixed(1)} cm in x, not away from the left hand (−x)`);
  assert.ok(Math.abs(pelvis1[1] - pelvis0[1]) < 0.05, 'the pelvis dropped: the figure fell');
  assert.ok(worst <= COP_TOLERANCE_M, `the centre of pressure left the support polygon by ${(worst * 1000).toFixed(1)} mm`);
  assert.equal(unbalanced, 0, `balance was lost in ${unbalanced} of 10 samples while the hand was held down`);

  // let go: the figure stays up, balanced, in the posture the drag left
  await page.waitForTimeout(2000);
  const rest = await physicsNow(page);
  assert.ok(rest && rest.balanced, 'the figure lost its balance after the drag was let go');
  assert.equal(await page.isVisible('#balance-banner'), false);
  const pelvis2 = await serverLink(page, 'pelvis');
  assert.ok(Math.abs(pelvis2[1] - pelvis0[1]) < 0.05, 'the figure fell after the drag was let go');

  await page.click('#preset-pose');
  await page.waitForFunction(() => window.pindrag.session?.scene?.gravity === false, null, { timeout: 5000 });
  await page.waitForFunction(() => window.pindrag.lastPose && window.pindrag.lastPose.physics === null, null, { timeout: 5000 });
  assert.equal(await page.isVisible('#balance-banner'), false);
  assert.deepEqual(problems, []);
  await context.close();
});
