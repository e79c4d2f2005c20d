// Where the browser tests find their tools: the page's npm install (playwright-core, ws, three),
// Debian's chromium, and a directory for screenshots and downloads outside the source tree.
// A missing tool is a skip, not a failure: skip() exits with SKIP_CODE, which ctest maps to SKIPPED.

import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';

export const SKIP_CODE = 77;
export const SOURCE_DIR = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../../..');
export const WEB_DIR = path.join(SOURCE_DIR, 'web');
export const NODE_MODULES = path.join(WEB_DIR, 'node_modules');
export const CHROMIUM = process.env.PINDRAG_CHROMIUM || '/usr/bin/chromium';

export function skip(reason) {
  console.log(`SKIP: ${reason}`);
  process.exit(SKIP_CODE);
}

/** Imports a package from web/node_modules, or skips when it is not installed. */
export async function importWebPackage(name, entry) {
  const file = path.join(NODE_MODULES, name, entry);
  if (!fs.existsSync(file)) skip(`${file} is missing: run 'npm ci' in web/`);
  return import(pathToFileURL(file).href);
}

export function requireChromium() {
  if (!fs.existsSync(CHROMIUM)) skip(`${CHROMIUM} is missing: apt-get install chromium`);
  return CHROMIUM;
}

/** The pindrag binary: argv[2] or PINDRAG_BIN. */
export function pindragBinary() {
  const bin = process.argv[2] || process.env.PINDRAG_BIN;
  if (!bin) skip('no pindrag binary: pass its path as the first argument or in PINDRAG_BIN');
  if (!fs.existsSync(bin)) throw new Error(`pindrag binary ${bin} does not exist`);
  return path.resolve(bin);
}

/** Where screenshots and downloads go: PINDRAG_WEB_TEST_OUT, else ./web-test-output (ctest runs in the build dir). */
export function outputDir(testName) {
  const base = process.env.PINDRAG_WEB_TEST_OUT || path.join(process.cwd(), 'web-test-output');
  const dir = path.join(base, testName);
  if (path.resolve(dir).startsWith(SOURCE_DIR + path.sep) && !path.resolve(dir).includes(`${path.sep}build`)) {
    throw new Error(`refusing to write test output into the source tree (${dir}); run from the build directory`);
  }
  fs.mkdirSync(dir, { recursive: true });
  return dir;
}

export function tempDir(prefix) {
  return fs.mkdtempSync(path.join(os.tmpdir(), prefix));
}
