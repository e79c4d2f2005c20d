// The fixture of a browser test file against the real server: skips the file when the binary has
// no serve command, starts `pindrag serve` and Chromium once for the file's tests (the first
// `start()`), and stops both after them.

import { after } from 'node:test';
import { outputDir, pindragBinary, skip } from './env.mjs';
import { launchBrowser } from './browser.mjs';
import { startPindragServer, hasServeCommand } from './pindrag_server.mjs';

/** Returns {out, start}: the output folder, and start() → Promise<{server, browser}>. */
export async function serverAndBrowser(name) {
  const binary = pindragBinary();
  if (!(await hasServeCommand(binary))) skip(`${binary} has no 'serve' command`);
  const out = outputDir(name);
  let running = null;
  const start = () =>
    (running ??= (async () => {
      const server = await startPindragServer(binary, out);
      const browser = await launchBrowser();
      return { server, browser };
    })());
  after(async () => {
    if (!running) return;
    const { server, browser } = await running;
    await browser?.close();
    await server?.stop();
  });
  return { out, start };
}
