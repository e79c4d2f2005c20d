// The page against a protocol stub (no solver): it loads without errors and draws the figure; a drag
// from a joint handle sends drag_begin, increasing drag_move seqs and drag_end and leaves the camera
// alone; right-click and P send pin/unpin (also next to the pin gizmo); Space, I, Ctrl+Z and
// Ctrl+Shift+Z send play, key_insert, undo and redo; an edit the server could not save is shown as
// not saved and not drawn; the effects panel sends set_effects and the physics of the pose frames is
// drawn, with a banner when balance is lost; a dropped connection comes back by itself and asks for
// a new snapshot.
// Usage: node tests/web/page_protocol_test.mjs

import { test, after, before } from 'node:test';
import assert from 'node:assert/strict';
import path from 'node:path';
import { outputDir } from './support/env.mjs';
import { launchBrowser, openPage, dragMouse, canvasStats, settle } from './support/browser.mjs';
import { startProtocolStub } from './support/protocol_stub.mjs';

const out = outputDir('page_protocol');
let browser;
let stub;

before(async () => {
  browser = await launchBrowser();
  stub = await startProtocolStub();
});
after(async () => {
  await browser?.close();
  await stub?.close();
});

const typesSince = (start) => stub.received.slice(start).map((m) => m.type);

async function waitForMessage(predicate, start, what) {
  const deadline = Date.now() + 5000;
  while (Date.now() < deadline) {
    const m = stub.received.slice(start).find(predicate);
    if (m) return m;
    await new Promise((r) => setTimeout(r, 20));
  }
  assert.fail(`the page did not send ${what}; it sent ${JSON.stringify(typesSince(start))}`);
}

test('the page loads, connects and draws the figure', async () => {
  const { page, context, problems } = await openPage(browser, stub.url);
  assert.equal(await page.evaluate(() => window.pindrag.contextLost()), false, 'the WebGL context is lost');
  const stats = await canvasStats(page);
  assert.ok(stats.colours > 200, `the canvas has only ${stats.colours} colours`);
  assert.ok(stats.luminanceStd > 5, `the canvas is nearly flat (luminance std ${stats.luminanceStd.toFixed(2)})`);
  assert.ok(stub.received.some((m) => m.type === 'hello' && m.protocol === 1), 'no hello with protocol 1');
  await page.screenshot({ path: path.join(out, 'loaded.png') });
  assert.deepEqual(problems, []);
  await context.close();
});

test('dragging the right hand sends absolute targets with increasing seq and leaves the camera alone', async () => {
  const { page, context, problems } = await openPage(browser, stub.url);
  const cameraBefore = await page.evaluate(() => window.pindrag.camera());
  const hand = await page.evaluate(() => window.pindrag.project('r_hand'));
  assert.ok(hand && hand.visible, 'the right hand is not on screen');
  const start = stub.received.length;
  await dragMouse(page, hand, { x: hand.x + 120, y: hand.y - 90 });
  const end = await waitForMessage((m) => m.type === 'drag_end', start, 'drag_end');
  const sent = stub.received.slice(start, stub.received.indexOf(end) + 1);
  assert.equal(sent[0].type, 'drag_begin');
  assert.equal(sent[0].link, 'r_hand');
  const moves = sent.filter((m) => m.type === 'drag_move');
  assert.ok(moves.length >= 3, `only ${moves.length} drag_move messages`);
  for (let k = 1; k < moves.length; k++) assert.ok(moves[k].seq > moves[k - 1].seq, 'seq does not increase');
  const first = sent[0].target;
  const lastTarget = moves[moves.length - 1].target;
  const moved = Math.hypot(...lastTarget.map((x, k) => x - first[k]));
  assert.ok(moved > 0.1, `the drag target moved only ${moved.toFixed(3)} m`);
  // constant depth: the target stays on the camera-facing plane through the grabbed point
  const cam = cameraBefore.position;
  const dir = cameraBefore.target.map((x, k) => x - cam[k]);
  const depth = (p) => p.reduce((s, x, k) => s + (x - cam[k]) * dir[k], 0) / Math.hypot(...dir);
  assert.ok(Math.abs(depth(lastTarget) - depth(first)) < 0.02, 'the drag target left the constant-depth plane');
  assert.deepEqual(await page.evaluate(() => window.pindrag.camera()), cameraBefore, 'the camera moved during a joint drag');
  // a report of the drag arriving after it ended (or one of the figure at rest) shows no drag
  const report = { type: 'report', microseconds: 40, drag_error: 2.16, pin_position_error: 0, pin_orientation_error: 0, limit_violation: 0, top_rank: 3 };
  stub.sendMessage(report);
  await page.waitForFunction(() => document.querySelector('[data-key=microseconds]').textContent === '40');
  assert.equal(await page.textContent('[data-key=drag_error]'), '–', 'a stale drag error is shown after the drag');
  assert.equal(await page.textContent('[data-key=top_rank]'), '–');
  await page.screenshot({ path: path.join(out, 'after_drag.png') });
  assert.deepEqual(problems, []);
  await context.close();
});

test('pins, playback, keys and undo/redo go out as protocol messages', async () => {
  const { page, context, problems } = await openPage(browser, stub.url);
  const foot = await page.evaluate(() => window.pindrag.project('l_foot'));
  let start = stub.received.length;
  await page.mouse.click(foot.x, foot.y, { button: 'right' });
  const pin = await waitForMessage((m) => m.type === 'pin', start, 'pin');
  assert.equal(pin.link, 'l_foot');
  await page.waitForFunction(() => window.pindrag.session.pins.length === 1);
  assert.equal(await page.locator('#pin-list li[data-link="l_foot"]').count(), 1, 'the pin list does not show the pin');
  // the pinned foot is selected, so the pin gizmo sits on it; its arrows must not hide the other foot
  const otherFoot = await page.evaluate(() => window.pindrag.project('r_foot'));
  start = stub.received.length;
  await page.mouse.click(otherFoot.x, otherFoot.y, { button: 'right' });
  assert.equal((await waitForMessage((m) => m.type === 'pin', start, 'a pin of the other foot')).link, 'r_foot');

  start = stub.received.length;
  await page.mouse.move(foot.x, foot.y);
  await page.keyboard.press('p');
  assert.equal((await waitForMessage((m) => m.type === 'unpin', start, 'unpin')).link, 'l_foot');

  start = stub.received.length;
  await page.keyboard.press('Space');
  await waitForMessage((m) => m.type === 'play', start, 'play');
  await page.keyboard.press('i');
  await waitForMessage((m) => m.type === 'key_insert', start, 'key_insert');
  await page.waitForSelector('#tl-track .key');
  await page.keyboard.press('Control+z');
  await waitForMessage((m) => m.type === 'undo', start, 'undo');
  await page.keyboard.press('Control+Shift+z');
  await waitForMessage((m) => m.type === 'redo', start, 'redo');
  await page.screenshot({ path: path.join(out, 'key.png') });
  start = stub.received.length; // the pin strength switch
  await page.click('#set-hard_pins');
  const strength = await waitForMessage((m) => m.type === 'set_settings', start, 'set_settings');
  assert.deepEqual(strength.settings, { hard_pins: await page.isChecked('#set-hard_pins') });
  start = stub.received.length; // the floor switch
  await page.click('#set-floor');
  const floorSwitch = await waitForMessage((m) => m.type === 'set_settings', start, 'set_settings');
  assert.deepEqual(floorSwitch.settings, { floor: await page.isChecked('#set-floor') });
  assert.deepEqual(problems, []);
  await context.close();
});

test('an edit the server could not save shows as not saved and is not drawn', async () => {
  const { page, context, problems } = await openPage(browser, stub.url);
  const pinsBefore = await page.evaluate(() => window.pindrag.session.pins.length);
  const head = await page.evaluate(() => window.pindrag.project('head'));
  stub.control.failSaves = true;
  let start = stub.received.length;
  await page.mouse.click(head.x, head.y, { button: 'right' });
  const pin = await waitForMessage((m) => m.type === 'pin', start, 'pin');
  assert.equal(pin.link, 'head');
  assert.ok(pin.id !== undefined, 'the pin carries no id, so the page cannot hear about it');
  await page.waitForSelector('#not-saved:not([hidden])');
  await page.waitForSelector('.toast.error:has-text("not saved")');
  assert.equal(await page.locator('.readout .value[data-key="saving"]').textContent(), 'not saved');
  assert.equal(await page.evaluate(() => window.pindrag.session.pins.length), pinsBefore, 'the refused pin is shown');
  await page.screenshot({ path: path.join(out, 'not_saved.png') });
  // with room again the next edit is saved and the warning goes
  stub.control.failSaves = false;
  start = stub.received.length;
  await page.mouse.click(head.x, head.y, { button: 'right' });
  await waitForMessage((m) => m.type === 'pin', start, 'pin');
  await page.waitForSelector('#not-saved', { state: 'hidden' });
  assert.equal(await page.evaluate(() => window.pindrag.session.pins.length), pinsBefore + 1);
  assert.deepEqual(problems, []);
  await context.close();
});

test('the effects panel sends the presets; the physics of the pose frames is drawn, with a banner when balance is lost', async () => {
  const { page, context, problems } = await openPage(browser, stub.url);
  let start = stub.received.length;
  await page.click('#preset-stand');
  const stand = await waitForMessage((m) => m.type === 'set_effects', start, 'set_effects');
  assert.deepEqual(stand.scene, { gravity: true, ground_contact: true, friction: true, dynamic_pins: true, hard_limits: false, self_collision: false });
  await page.waitForFunction(() => document.querySelector('#effect-dynamic_pins').checked);
  start = stub.received.length;
  await page.click('#effect-hard_limits');
  const one = await waitForMessage((m) => m.type === 'set_effects', start, 'set_effects');
  assert.equal(one.scene.hard_limits, true);
  assert.equal(one.scene.gravity, true, 'a switch changed the other effects');

  // a figure off balance: the centre of mass outside the polygon of its one foot
  const foot = [[0.05, 0, -0.07], [0.14, 0, -0.07], [0.14, 0, 0.19], [0.05, 0, 0.19]];
  stub.control.physics = {
    com: [-0.2, 0.9, 0], cop: [0.1, 0, 0.05], support_polygon: foot, balanced: false,
    contacts: [{ point: [0.1, 0, -0.05], force: [0, 400, 0] }, { point: [0.1, 0, 0.15], force: [20, 300, 0] }],
    stage_us: { gravity: 11, ground_contact: 90, friction: 0, dynamic_pins: 1400, hard_limits: 3, self_collision: 0 },
    total_us: 1504,
  };
  stub.sendPose();
  await page.waitForSelector('#balance-banner', { state: 'visible' });
  assert.match(await page.textContent('#balance-banner'), /Balance lost/);
  await page.waitForFunction(() => document.querySelector('[data-effect="dynamic_pins"]').textContent === '1400');
  assert.equal(await page.textContent('#effects-total'), '1504');
  await settle(page);
  await page.screenshot({ path: path.join(out, 'balance_lost.png') });
  stub.control.physics = { ...stub.control.physics, com: [0.1, 0.9, 0.05], balanced: true };
  stub.sendPose();
  await page.waitForSelector('#balance-banner', { state: 'hidden' });

  start = stub.received.length;
  await page.click('#preset-pose');
  const pose = await waitForMessage((m) => m.type === 'set_effects', start, 'set_effects');
  assert.ok(Object.values(pose.scene).every((on) => on === false), 'Pose left an effect on');
  stub.control.physics = null;
  stub.sendPose();
  await page.waitForFunction(() => window.pindrag.lastPose?.physics === null);
  assert.deepEqual(problems, []);
  await context.close();
});

test('a key lands on the frame the time display shows, unless snapping is off', async () => {
  const { page, context, problems } = await openPage(browser, stub.url);
  const track = await page.locator('#tl-track').boundingBox();
  const keyAt = async (fraction) => {
    const start = stub.received.length;
    await page.mouse.click(track.x + fraction * track.width, track.y + track.height / 2);
    await page.waitForFunction(() => window.pindrag.timeCursor > 0);
    await page.click('#tl-key-insert');
    return (await waitForMessage((m) => m.type === 'key_insert', start, 'key_insert')).time;
  };
  const snapped = await keyAt(0.3137);
  const frame = Number((await page.textContent('#tl-frame')).replace('frame ', ''));
  assert.ok(Math.abs(snapped * 30 - Math.round(snapped * 30)) < 1e-9, `the key at ${snapped} s is between frames`);
  assert.equal(Math.round(snapped * 30), frame, 'the key and the time display disagree');
  await page.click('#view-options label:has-text("snap keys") input');
  const free = await keyAt(0.4221);
  assert.ok(Math.abs(free * 30 - Math.round(free * 30)) > 1e-6, `snapping off still snapped ${free} s`);
  assert.deepEqual(problems, []);
  await context.close();
});

test('while a clip plays, a handle is grabbed from further away and a near miss does not orbit', async () => {
  const { page, context, problems } = await openPage(browser, stub.url);
  const hand = await page.evaluate(() => window.pindrag.project('r_hand'));
  const pelvis = await page.evaluate(() => window.pindrag.project('pelvis'));
  // away from the body, on the line from the pelvis through the hand
  const len = Math.hypot(hand.x - pelvis.x, hand.y - pelvis.y);
  const away = (px) => ({ x: hand.x + ((hand.x - pelvis.x) * px) / len, y: hand.y + ((hand.y - pelvis.y) * px) / len });
  const pickedAt = async (px) => {
    const start = stub.received.length;
    const from = away(px);
    await dragMouse(page, from, { x: from.x + 60, y: from.y - 40 });
    await page.waitForTimeout(150);
    return stub.received.slice(start).find((m) => m.type === 'drag_begin')?.link ?? null;
  };
  let start = stub.received.length;
  if (await page.evaluate(() => window.pindrag.session?.playback?.playing === true)) {
    await page.keyboard.press('Space'); // the stub's session may still play from an earlier test
    await waitForMessage((m) => m.type === 'pause', start, 'pause');
    await page.waitForFunction(() => window.pindrag.session?.playback?.playing === false);
    start = stub.received.length;
  }
  await page.keyboard.press('Space');
  await waitForMessage((m) => m.type === 'play', start, 'play');
  await page.waitForFunction(() => window.pindrag.session?.playback?.playing === true);
  const camera = await page.evaluate(() => window.pindrag.camera());
  const handNow = await page.evaluate(() => window.pindrag.project('r_hand'));
  const pelvisNow = await page.evaluate(() => window.pindrag.project('pelvis'));
  assert.deepEqual([handNow.x, handNow.y, pelvisNow.x, pelvisNow.y], [hand.x, hand.y, pelvis.x, pelvis.y], 'the view moved');
  assert.equal(await pickedAt(20), 'r_hand', 'while playing, a press 20 px from the hand did not grab it');
  assert.equal(await pickedAt(60), null, 'a press 60 px from every handle grabbed a link');
  assert.deepEqual(await page.evaluate(() => window.pindrag.camera()), camera, 'a missed grab while playing orbited the camera');
  // paused, the same press 20 px away is empty space (it orbits)
  start = stub.received.length;
  await page.keyboard.press('Space');
  await waitForMessage((m) => m.type === 'pause', start, 'pause');
  await page.waitForFunction(() => window.pindrag.session?.playback?.playing === false);
  assert.equal(await pickedAt(20), null, 'at rest, a press 20 px from the handle grabbed it');
  assert.notDeepEqual(await page.evaluate(() => window.pindrag.camera()), camera, 'at rest, a press on empty space did not orbit');
  assert.deepEqual(problems, []);
  await context.close();
});

test('orbiting and panning never take the camera below the floor', async () => {
  const { page, context, problems } = await openPage(browser, stub.url);
  const box = await page.locator('canvas').first().boundingBox();
  const empty = { x: box.x + 30, y: box.y + 30 }; // a corner: no handle there
  // orbit hard from above to below, then pan down hard
  await dragMouse(page, empty, { x: empty.x, y: empty.y + box.height - 60 }, { steps: 20 });
  await dragMouse(page, { x: empty.x, y: empty.y + box.height - 60 }, { x: empty.x, y: empty.y }, { steps: 20, button: 'right' });
  await dragMouse(page, empty, { x: empty.x, y: empty.y + box.height - 60 }, { steps: 20, button: 'right' });
  const camera = await page.evaluate(() => window.pindrag.camera());
  assert.ok(camera.position[1] >= 0.05 - 1e-9, `the camera went below the floor: y = ${camera.position[1]}`);
  assert.ok(camera.target[1] >= -1e-9, `the orbit target went below the floor: y = ${camera.target[1]}`);
  assert.deepEqual(problems, []);
  await context.close();
});

test('a dropped connection reconnects and says hello again', async () => {
  const { page, context } = await openPage(browser, stub.url);
  const start = stub.received.length;
  stub.dropConnections();
  await waitForMessage((m) => m.type === 'hello', start, 'a new hello after the drop');
  await page.waitForFunction(() => window.pindrag.connection === 'open');
  await settle(page);
  await context.close();
});
