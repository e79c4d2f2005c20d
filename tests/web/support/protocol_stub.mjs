// A stand-in for `pindrag serve` that speaks docs/protocol.md without solving anything: it serves
// the page and three.js, builds the snapshot of a character file at its rest pose, answers edits
// with `state`/`ack`, acknowledges drag samples in pose frames, and records every message the page
// sends. The page test uses it to check what the page puts on the wire, independent of the solver.

import fs from 'node:fs';
import http from 'node:http';
import path from 'node:path';
import { pathToFileURL } from 'node:url';
import { WEB_DIR, NODE_MODULES, SOURCE_DIR, importWebPackage } from './env.mjs';

const { encodePose } = await import(pathToFileURL(path.join(WEB_DIR, 'js/protocol.js')).href);

const MIME = { '.html': 'text/html', '.js': 'text/javascript', '.css': 'text/css', '.png': 'image/png', '.json': 'application/json' };

// --- rest-pose snapshot of a pindrag-character file -------------------------------------------
const qmul = (a, b) => [
  a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
  a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
  a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
  a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
];
const qrot = (q, v) => qmul(qmul(q, [0, ...v]), [q[0], -q[1], -q[2], -q[3]]).slice(1);

/** Rotation matrix (rows) -> unit quaternion [w, x, y, z]. */
function matrixToQuat(m) {
  const t = m[0][0] + m[1][1] + m[2][2];
  let q;
  if (t > 0) {
    const s = Math.sqrt(t + 1) * 2;
    q = [s / 4, (m[2][1] - m[1][2]) / s, (m[0][2] - m[2][0]) / s, (m[1][0] - m[0][1]) / s];
  } else if (m[0][0] > m[1][1] && m[0][0] > m[2][2]) {
    const s = Math.sqrt(1 + m[0][0] - m[1][1] - m[2][2]) * 2;
    q = [(m[2][1] - m[1][2]) / s, s / 4, (m[0][1] + m[1][0]) / s, (m[0][2] + m[2][0]) / s];
  } else if (m[1][1] > m[2][2]) {
    const s = Math.sqrt(1 + m[1][1] - m[0][0] - m[2][2]) * 2;
    q = [(m[0][2] - m[2][0]) / s, (m[0][1] + m[1][0]) / s, s / 4, (m[1][2] + m[2][1]) / s];
  } else {
    const s = Math.sqrt(1 + m[2][2] - m[0][0] - m[1][1]) * 2;
    q = [(m[1][0] - m[0][1]) / s, (m[0][2] + m[2][0]) / s, (m[1][2] + m[2][1]) / s, s / 4];
  }
  const n = Math.hypot(...q);
  return q.map((x) => x / n);
}
const originOf = (o = {}) => ({ p: o.xyz || [0, 0, 0], R: o.rotation ? matrixToQuat(o.rotation) : [1, 0, 0, 0] });

export function restSnapshot(file) {
  const doc = JSON.parse(fs.readFileSync(file, 'utf8'));
  const index = new Map(doc.links.map((l, i) => [l.name, i]));
  const links = doc.links.map((l) => {
    const j = l.joint || {};
    return {
      name: l.name,
      display_name: l.display_name || l.name,
      parent: l.parent === undefined ? -1 : index.get(l.parent),
      joint: j.name,
      joint_type: j.type,
      X_PJ: originOf(j.origin),
      axis: j.axis || null,
      limits: j.limits ? [j.limits.lower, j.limits.upper] : null,
      range: j.range || null,
      shapes: (l.visual || l.collision || []).map((s) => ({ ...s, ...originOf(s.origin), origin: undefined })),
    };
  });
  const world = [];
  links.forEach((l, i) => {
    const parent = l.parent < 0 ? { p: [0, 0, 0], R: [1, 0, 0, 0] } : world[l.parent];
    const dp = qrot(parent.R, l.X_PJ.p);
    world[i] = { name: l.name, p: parent.p.map((x, k) => x + dp[k]), R: qmul(parent.R, l.X_PJ.R) };
  });
  return { character: { name: doc.name, links, height: 1.75, skinned: false }, links: world };
}

// --- the server ---------------------------------------------------------------------------------
export async function startProtocolStub({ character = path.join(SOURCE_DIR, 'characters/human48.json') } = {}) {
  const { WebSocketServer } = await importWebPackage('ws', 'wrapper.mjs');
  const rest = restSnapshot(character);
  const received = []; // every JSON message from the page, in order
  const sessionId = 's1';
  const token = 't1';
  const session = {
    pins: [],
    keys: [],
    clip: null,
    layers: [],
    playback: { time: 0, playing: false, speed: 1, loop: true, loop_start: 0, loop_end: -1, duration: 0 },
    recording: false,
    settings: { damping: 0.03, iterations: 1, gains: { drag: 40, pin: 40, reference: 2, limit: 20, range: 20 } },
    scene: {},
    undo: { can_undo: false, can_redo: false, labels: [] },
  };
  const snapshot = () => ({ protocol: 1, session: sessionId, character: rest.character, q: [], links: rest.links, ...session });

  const server = http.createServer((req, res) => {
    const url = new URL(req.url, 'http://x');
    const json = (code, body) => {
      res.writeHead(code, { 'Content-Type': 'application/json' });
      res.end(JSON.stringify(body));
    };
    if (url.pathname === '/api/config') {
      return json(200, { protocol: 1, ws_url: `ws://127.0.0.1:${server.address().port}/ws`, limits: { upload_bytes: 67108864, ws_message_bytes: 1048576 } });
    }
    if (url.pathname === '/api/sessions' && req.method === 'POST') return json(201, { id: sessionId, token });
    if (url.pathname === `/api/sessions/${sessionId}`) return json(200, snapshot());
    let file;
    if (url.pathname.startsWith('/vendor/three/')) file = path.join(NODE_MODULES, 'three', url.pathname.slice('/vendor/three/'.length));
    else file = path.join(WEB_DIR, url.pathname === '/' ? 'index.html' : url.pathname.slice(1));
    if (!file.startsWith(WEB_DIR) || !fs.existsSync(file) || fs.statSync(file).isDirectory()) return json(404, { error: `no file ${url.pathname}` });
    res.writeHead(200, { 'Content-Type': MIME[path.extname(file)] || 'application/octet-stream' });
    fs.createReadStream(file).pipe(res);
  });
  const wss = new WebSocketServer({ server, path: '/ws' });
  let frame = 0;
  // failSaves: edits are answered as a server with a full disk would; physics: the physics object
  // every pose frame carries (null: none, as while posing is kinematic)
  const control = { failSaves: false, physics: null };
  const EDITS = new Set(['pin', 'unpin', 'key_insert', 'key_delete', 'undo', 'redo']);
  wss.on('connection', (ws) => {
    let ack = 0;
    const sendPose = () => ws.send(encodePose({ frame: ++frame, ack, time: session.playback.time, links: rest.links, physics: control.physics }));
    const sendState = () => ws.send(JSON.stringify({ type: 'state', ...session, links: rest.links }));
    ws.on('message', (data, isBinary) => {
      if (isBinary) return;
      const m = JSON.parse(String(data));
      received.push(m);
      if (control.failSaves && EDITS.has(m.type)) {
        // not saved, so not applied: an error on the edit's id and the unchanged state again
        const message = `${m.type}: not saved (No space left on device), so not applied`;
        ws.send(JSON.stringify({ type: 'error', id: m.id, code: 'not_saved', message }));
        sendState();
        return;
      }
      switch (m.type) {
        case 'hello':
          ws.send(JSON.stringify({ type: 'snapshot', ...snapshot() }));
          sendPose();
          break;
        case 'drag_move':
          ack = m.seq;
          sendPose();
          break;
        case 'pin':
          session.pins.push({ link: m.link, mode: m.mode, point: [0, 0, 0], target: rest.links.find((l) => l.name === m.link).p, rotation: [1, 0, 0, 0] });
          sendState();
          break;
        case 'unpin':
          session.pins = session.pins.filter((p) => p.link !== m.link);
          sendState();
          break;
        case 'play':
          session.playback.playing = true;
          sendState();
          break;
        case 'pause':
          session.playback.playing = false;
          sendState();
          break;
        case 'set_effects':
          session.scene = m.scene;
          sendState();
          sendPose();
          break;
        case 'key_insert':
          session.keys.push({ time: m.time ?? 0, interpolation: m.interpolation || 'smooth' });
          sendState();
          break;
        default:
          break;
      }
      if (m.id !== undefined) ws.send(JSON.stringify({ type: 'ack', id: m.id, request: m.type }));
    });
  });
  await new Promise((resolve) => server.listen(0, '127.0.0.1', resolve));
  return {
    url: `http://127.0.0.1:${server.address().port}/`,
    received,
    control,
    /** Sends a pose frame to every page (with control.physics). */
    sendPose: () => wss.clients.forEach((c) => c.send(encodePose({ frame: ++frame, time: session.playback.time, links: rest.links, physics: control.physics }))),
    /** Sends a JSON message to every page. */
    sendMessage: (m) => wss.clients.forEach((c) => c.send(JSON.stringify(m))),
    dropConnections: () => wss.clients.forEach((c) => c.terminate()),
    close: () => new Promise((resolve) => {
      wss.clients.forEach((c) => c.terminate());
      wss.close();
      server.close(resolve);
    }),
  };
}
