// Starts `pindrag serve` on free loopback ports with a temporary data directory, waits for
// /api/health, and stops it again. Its output goes to serve.log in the test's output directory.

import { spawn } from 'node:child_process';
import fs from 'node:fs';
import net from 'node:net';
import path from 'node:path';
import { tempDir } from './env.mjs';

function listenOn(port) {
  return new Promise((resolve) => {
    const s = net.createServer();
    s.once('error', () => resolve(null));
    s.listen(port, '127.0.0.1', () => resolve(s));
  });
}

/** A port P such that P and P + 1 are both free now. */
async function freePortPair() {
  for (let attempt = 0; attempt < 50; attempt++) {
    const a = await listenOn(0);
    const port = a.address().port;
    const b = port < 65535 ? await listenOn(port + 1) : null;
    await new Promise((r) => a.close(r));
    if (b) {
      await new Promise((r) => b.close(r));
      return port;
    }
  }
  throw new Error('no two consecutive free ports on 127.0.0.1');
}

export async function startPindragServer(binary, logDir, { character = 'human48', timeoutMs = 20000 } = {}) {
  const port = await freePortPair();
  const dataDir = tempDir('pindrag-web-test-');
  const log = fs.openSync(path.join(logDir, 'serve.log'), 'a');
  const args = ['serve', '--host', '127.0.0.1', '--port', String(port), '--ws-port', String(port + 1), '--character', character, '--data-dir', dataDir];
  const child = spawn(binary, args, { stdio: ['ignore', log, log] });
  let exited = null;
  child.on('exit', (code, signal) => (exited = { code, signal }));
  const url = `http://127.0.0.1:${port}/`;
  const deadline = Date.now() + timeoutMs;
  for (;;) {
    if (exited) throw new Error(`pindrag ${args.join(' ')} exited (${exited.code ?? exited.signal}); see ${path.join(logDir, 'serve.log')}`);
    try {
      const res = await fetch(`${url}api/health`);
      if (res.ok) break;
    } catch {
      /* not listening yet */
    }
    if (Date.now() > deadline) {
      child.kill('SIGTERM');
      throw new Error(`pindrag serve did not answer /api/health within ${timeoutMs} ms`);
    }
    await new Promise((r) => setTimeout(r, 100));
  }
  return {
    url,
    port,
    dataDir,
    /** GET /api/sessions/{id} with the session's token. */
    async snapshot(id, token) {
      const res = await fetch(`${url}api/sessions/${encodeURIComponent(id)}`, { headers: { 'X-Session-Token': token } });
      if (!res.ok) throw new Error(`GET /api/sessions/${id}: ${res.status} ${await res.text()}`);
      return res.json();
    },
    async stop() {
      if (exited) return;
      const done = new Promise((r) => child.once('exit', r));
      child.kill('SIGTERM');
      const timer = setTimeout(() => child.kill('SIGKILL'), 5000);
      await done;
      clearTimeout(timer);
      fs.rmSync(dataDir, { recursive: true, force: true });
    },
  };
}

/** Whether the binary lists the serve command in its help (it may be built without the server). */
export function hasServeCommand(binary) {
  return new Promise((resolve) => {
    let help = '';
    const child = spawn(binary, ['--help'], { stdio: ['ignore', 'pipe', 'ignore'] });
    child.stdout.on('data', (d) => (help += d));
    child.on('close', () => resolve(/^\s+serve\s/m.test(help)));
    child.on('error', () => resolve(false));
  });
}
