// The page's session list against `pindrag serve` in headless Chromium: two tabs of one browser
// create two sessions; the list shows both, marks this tab's, opens the other one in place and
// deletes a session (two clicks) that no tab has open, after which the server has its files no
// more; deleting a session open in another tab is refused and says why.
// Usage: node tests/web/session_list_test.mjs PINDRAG_BINARY   (or PINDRAG_BIN=...)

import { test, before } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import { settle } from './support/browser.mjs';
import { serverAndBrowser } from './support/fixture.mjs';

const fixture = await serverAndBrowser('session_list');
const out = fixture.out;

let browser;
let server;
before(async () => ({ server, browser } = await fixture.start()));

async function openTab(context, url) {
  const page = await context.newPage();
  const problems = [];
  page.on('pageerror', (e) => problems.push(`page error: ${e.message}`));
  await page.goto(url);
  await page.waitForFunction(() => window.pindrag && window.pindrag.connection === 'open' && window.pindrag.poseFrames > 0, null, {
    timeout: 20000,
  });
  await settle(page);
  return { page, problems };
}

/** The rows of the page's session list once it shows `count` of them. */
async function rows(page, count) {
  await page.waitForFunction((n) => document.querySelectorAll('.session-list li[data-id]').length === n, count, { timeout: 10000 });
  return page.$$eval('.session-list li[data-id]', (lis) =>
    lis.map((li) => ({ id: li.dataset.id, text: li.textContent, buttons: [...li.querySelectorAll('button')].map((b) => b.textContent) })),
  );
}

const storedIds = async () => (await (await fetch(`${server.url}api/sessions`)).json()).map((r) => r.id);
const filesOf = (id) => fs.readdirSync(path.join(server.dataDir, 'sessions')).filter((f) => f.startsWith(`${id}.`));

test('the session list opens and deletes sessions of this browser', async () => {
  const context = await browser.newContext({ viewport: { width: 1280, height: 800 } });
  const first = await openTab(context, server.url);
  const second = await openTab(context, `${server.url}?character=human48`);
  const idA = await first.page.evaluate(() => window.pindrag.sessionId);
  const idB = await second.page.evaluate(() => window.pindrag.sessionId);
  assert.notEqual(idA, idB);

  // the second tab lists both: its own marked, the other with Open and Delete
  const page = second.page;
  await page.click('details.sessions > summary');
  let list = await rows(page, 2);
  const own = list.find((r) => r.id === idB);
  const other = list.find((r) => r.id === idA);
  assert.match(own.text, /this tab/);
  assert.deepEqual(other.buttons, ['Open', 'Delete']);
  assert.match(other.text, /human48/);
  await page.locator('details.sessions').screenshot({ path: path.join(out, 'session_list.png') });

  // A is open in the first tab: deleting it is refused, and the reason shows
  const deleteA = `.session-list li[data-id="${idA}"] button.danger`;
  await page.click(deleteA);
  await page.click(deleteA);
  await page.waitForFunction(() => /open in a page/.test(document.body.textContent), null, { timeout: 10000 });
  assert.ok((await storedIds()).includes(idA));

  // the first tab goes away; then A can be deleted, files and all
  await first.page.close();
  let deleted = false;
  for (let attempt = 0; attempt < 20 && !deleted; attempt++) {
    await page.click(deleteA);
    await page.click(deleteA);
    await new Promise((r) => setTimeout(r, 300));
    deleted = !(await storedIds()).includes(idA);
  }
  assert.ok(deleted, 'the session was not deleted');
  assert.deepEqual(filesOf(idA), []);
  list = await rows(page, 1);
  assert.equal(list[0].id, idB);

  // a third session (new tab), then the second tab opens it in place
  const third = await openTab(context, `${server.url}?character=human48`);
  const idC = await third.page.evaluate(() => window.pindrag.sessionId);
  await third.page.close();
  await page.click('details.sessions > summary'); // close and reopen: the list reloads
  await page.click('details.sessions > summary');
  await rows(page, 2);
  await page.click(`.session-list li[data-id="${idC}"] button:not(.danger)`);
  await page.waitForFunction((id) => window.pindrag && window.pindrag.sessionId === id && window.pindrag.connection === 'open', idC, {
    timeout: 20000,
  });
  assert.deepEqual(second.problems, []);
  await context.close();
});
