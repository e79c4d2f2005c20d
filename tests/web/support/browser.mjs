// Chromium through playwright-core, set up as reference/platform.md §4 says: Debian's binary,
// headless, WebGL on SwiftShader. One browser per test file; one fresh page (context) per test.

import { importWebPackage, requireChromium } from './env.mjs';

const IGNORED_CONSOLE = [/GPU stall due to ReadPixels/, /favicon/, /Automatic fallback to software WebGL/];

export async function launchBrowser() {
  const executablePath = requireChromium();
  const { chromium } = await importWebPackage('playwright-core', 'index.mjs');
  return chromium.launch({
    executablePath,
    headless: true,
    args: ['--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--disable-background-networking', '--disable-component-update', '--no-first-run'],
  });
}

/**
 * Opens the page in a fresh context and waits until it is connected and has drawn a pose.
 * Returns {page, context, problems}: problems collects page errors and console errors.
 */
export async function openPage(browser, url, { width = 1280, height = 800, sessionStorage: stored = null } = {}) {
  const context = await browser.newContext({ viewport: { width, height }, acceptDownloads: true });
  // entries the page finds in its tab's sessionStorage (e.g. the session to resume)
  if (stored) await context.addInitScript((entries) => Object.entries(entries).forEach(([k, v]) => sessionStorage.setItem(k, v)), stored);
  const page = await context.newPage();
  const problems = [];
  page.on('pageerror', (e) => problems.push(`page error: ${e.message}`));
  page.on('console', (m) => {
    if (m.type() === 'error' && !IGNORED_CONSOLE.some((r) => r.test(m.text()))) problems.push(`console: ${m.text()}`);
  });
  await page.goto(url);
  await page.waitForFunction(() => window.pindrag && window.pindrag.connection === 'open' && window.pindrag.poseFrames > 0, null, { timeout: 20000 });
  await settle(page);
  return { page, context, problems };
}

/** Waits until the page has rendered a couple of frames with nothing new to draw. */
export async function settle(page) {
  await page.evaluate(() => new Promise((resolve) => requestAnimationFrame(() => requestAnimationFrame(() => resolve()))));
}

/** Presses at `from`, moves to `to` in `steps` pointer moves (one per animation frame), releases
 * (skipPressRelease: the caller presses and releases). */
export async function dragMouse(page, from, to, { steps = 10, button = 'left', skipPressRelease = false } = {}) {
  if (!skipPressRelease) {
    await page.mouse.move(from.x, from.y);
    await page.mouse.down({ button });
  }
  for (let k = 1; k <= steps; k++) {
    const t = k / steps;
    await page.mouse.move(from.x + (to.x - from.x) * t, from.y + (to.y - from.y) * t);
    await settle(page);
  }
  if (!skipPressRelease) await page.mouse.up({ button });
}

/** Pixel statistics of the 3D canvas: how many distinct colours, and the luminance spread. */
export async function canvasStats(page) {
  return page.evaluate(() => {
    const src = document.querySelector('canvas.viewport-canvas');
    const c = document.createElement('canvas');
    c.width = 256;
    c.height = Math.max(1, Math.round((256 * src.height) / src.width));
    const ctx = c.getContext('2d');
    ctx.drawImage(src, 0, 0, c.width, c.height);
    const d = ctx.getImageData(0, 0, c.width, c.height).data;
    const colours = new Set();
    let sum = 0;
    let sum2 = 0;
    const n = d.length / 4;
    for (let i = 0; i < d.length; i += 4) {
      colours.add((d[i] << 16) | (d[i + 1] << 8) | d[i + 2]);
      const y = 0.2126 * d[i] + 0.7152 * d[i + 1] + 0.0722 * d[i + 2];
      sum += y;
      sum2 += y * y;
    }
    const mean = sum / n;
    return { colours: colours.size, luminanceStd: Math.sqrt(Math.max(0, sum2 / n - mean * mean)) };
  });
}
