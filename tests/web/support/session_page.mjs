// Helpers the browser tests share for reading the session a page works on: link positions from a
// server snapshot, the snapshot of the page's session, polling the server until a condition
// holds, and where a link's handle is on screen.

import assert from 'node:assert/strict';

/** World position [x, y, z] of a link in a snapshot. */
export function linkP(snapshot, name) {
  const l = snapshot.links.find((x) => x.name === name);
  assert.ok(l, `the snapshot has no link '${name}'`);
  return l.p;
}

export const dist = (a, b) => Math.hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);

/** The server's snapshot (GET /api/sessions/{id}) of the session the page has open. */
export async function serverSnapshot(server, page) {
  const { id, token } = await page.evaluate(() => ({ id: window.pindrag.sessionId, token: window.pindrag.token }));
  return server.snapshot(id, token);
}

/** Polls the server's snapshot until `ok(snapshot)` holds; returns it, or fails with `what`. */
export async function waitForServer(server, page, ok, what, timeoutMs = 8000) {
  const deadline = Date.now() + timeoutMs;
  while (Date.now() < deadline) {
    const s = await serverSnapshot(server, page);
    if (ok(s)) return s;
    await new Promise((r) => setTimeout(r, 100));
  }
  assert.fail(`${what} (waited ${timeoutMs} ms)`);
}

/** Client (CSS pixel) coordinates of a link's handle as drawn now; fails when it is off screen. */
export async function handle(page, name) {
  const p = await page.evaluate((n) => window.pindrag.project(n), name);
  assert.ok(p && p.visible, `the handle of ${name} is not on screen`);
  return p;
}
