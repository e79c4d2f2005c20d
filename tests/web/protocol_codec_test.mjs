// The page's pure modules in Node: the binary pose frame codec of docs/protocol.md (layout checked
// byte by byte against an independent DataView reading, and every malformed frame refused with a
// message), frame-id ordering across the u32 wrap, the message builders (against the
// CLIENT_MESSAGES table, which tests/server/protocol_test.cpp compares with the server), and the
// joint-range geometry (swing–twist decomposition recomposed, hinge angles, the range test of
// human48's lumbar).
// Usage: node tests/web/protocol_codec_test.mjs

import { test } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import { pathToFileURL } from 'node:url';
import { WEB_DIR, SOURCE_DIR } from './support/env.mjs';

const protocol = await import(pathToFileURL(path.join(WEB_DIR, 'js/protocol.js')).href);
const ranges = await import(pathToFileURL(path.join(WEB_DIR, 'js/joint_ranges.js')).href);
const { decodePose, encodePose, isNewerFrame, msg, POSE_MAGIC } = protocol;

function randomUnitQuat(rand) {
  const q = [rand() - 0.5, rand() - 0.5, rand() - 0.5, rand() - 0.5];
  const n = Math.hypot(...q);
  return q.map((x) => x / n);
}
function lcg(seed) {
  let s = seed >>> 0;
  return () => ((s = (Math.imul(s, 1664525) + 1013904223) >>> 0) / 2 ** 32);
}
const f32 = (x) => Math.fround(x);

test('a pose frame has the documented layout and decodes to what was encoded', () => {
  const rand = lcg(7);
  const links = Array.from({ length: 21 }, () => ({ p: [rand(), rand(), rand()], R: randomUnitQuat(rand), q: randomUnitQuat(rand) }));
  const buf = encodePose({ frame: 4000000000, ack: 77, time: 1.25, root: links[0].p, links });
  assert.equal(buf.byteLength, 36 + 44 * links.length);
  const v = new DataView(buf);
  assert.equal(v.getUint32(0, true), 0x46504450);
  assert.equal(String.fromCharCode(...new Uint8Array(buf, 0, 4)), 'PDPF');
  assert.equal(v.getUint16(4, true), 1);
  assert.equal(v.getUint16(6, true), links.length);
  assert.equal(v.getFloat32(36 + 44 * 3 + 4 * 3, true), f32(links[3].R[0])); // w of link 3's rotation
  const d = decodePose(buf);
  assert.equal(d.frame, 4000000000);
  assert.equal(d.ack, 77);
  assert.equal(d.time, 1.25);
  assert.equal(d.n, links.length);
  links.forEach((l, i) => {
    assert.deepEqual(d.links[i].p, l.p.map(f32));
    assert.deepEqual(d.links[i].R, l.R.map(f32));
    assert.deepEqual(d.links[i].q, l.q.map(f32));
  });
  // a view into a larger buffer (as a WebSocket library may hand over) decodes the same
  const padded = new Uint8Array(buf.byteLength + 8);
  padded.set(new Uint8Array(buf), 4);
  assert.deepEqual(decodePose(padded.subarray(4, 4 + buf.byteLength)), d);
});

test('malformed pose frames are refused with a message naming the problem', () => {
  const good = encodePose({ frame: 1, links: [{ p: [0, 0, 0], R: [1, 0, 0, 0] }] });
  assert.throws(() => decodePose(new ArrayBuffer(10)), /shorter than the 36-byte header/);
  const badMagic = good.slice(0);
  new DataView(badMagic).setUint32(0, POSE_MAGIC + 1, true);
  assert.throws(() => decodePose(badMagic), /bad magic/);
  const badVersion = good.slice(0);
  new DataView(badVersion).setUint16(4, 2, true);
  assert.throws(() => decodePose(badVersion), /protocol 2/);
  assert.throws(() => decodePose(good.slice(0, good.byteLength - 4)), /expected 80/);
  const tooMany = good.slice(0);
  new DataView(tooMany).setUint16(6, 2, true);
  assert.throws(() => decodePose(tooMany), /for 2 links/);
});

test('a pose frame carries the physics object after its links while physics runs', () => {
  const links = [{ p: [0, 1, 0], R: [1, 0, 0, 0] }];
  assert.equal(decodePose(encodePose({ frame: 1, links })).physics, null);
  const physics = {
    com: [0, 0.9, 0],
    cop: [0.01, 0, 0.02],
    support_polygon: [[0, 0, 0], [0.1, 0, 0], [0, 0, 0.2]],
    contacts: [{ point: [0, 0, 0], force: [0, 300, 0] }],
    balanced: true,
    stage_us: { gravity: 12.5, dynamic_pins: 800 },
  };
  const d = decodePose(encodePose({ frame: 2, links, physics }));
  assert.deepEqual(d.physics, physics);
  assert.equal(d.links.length, 1);
  const bad = new Uint8Array(encodePose({ frame: 3, links, physics }));
  bad[bad.length - 1] = 0x7b; // '{' where the closing brace was
  assert.throws(() => decodePose(bad), /physics object is not JSON/);
});

test('frame ids are ordered across the u32 wrap', () => {
  assert.equal(isNewerFrame(5, null), true);
  assert.equal(isNewerFrame(6, 5), true);
  assert.equal(isNewerFrame(5, 5), false);
  assert.equal(isNewerFrame(4, 5), false);
  assert.equal(isNewerFrame(2, 0xfffffffe), true);
  assert.equal(isNewerFrame(0xfffffffe, 2), false);
});

test('message builders follow the protocol tables', () => {
  assert.deepEqual(msg.hello(), { type: 'hello', protocol: 1 });
  assert.deepEqual(msg.dragMove(2 ** 32 + 3, ['1', 2, 3]), { type: 'drag_move', seq: 3, target: [1, 2, 3] });
  assert.deepEqual(msg.pin('l_foot', 'position'), { type: 'pin', link: 'l_foot', mode: 'position' });
  assert.throws(() => msg.pin('l_foot', 'glue'), /pin mode 'glue'/);
  assert.deepEqual(msg.seek(-1), { type: 'seek', time: 0 });
  assert.deepEqual(msg.keyInsert(undefined, 'step'), { type: 'key_insert', interpolation: 'step' });
  for (const m of Object.values(msg)) {
    const built = m.length === 0 ? m() : null;
    if (built) assert.equal(typeof built.type, 'string');
  }
});

test('the builders send exactly the message types and fields of CLIENT_MESSAGES', () => {
  const { CLIENT_MESSAGES } = protocol;
  // every builder, with all of its optional arguments
  const full = {
    hello: [],
    dragBegin: ['r_hand', [0, 1, 0], [0, 0, 0.1]],
    dragMove: [1, [0, 1, 0], [1, 0, 0, 0]],
    dragEnd: [],
    pin: ['l_foot', 'pose', [0, 0, 0.02]],
    unpin: ['l_foot'],
    movePin: ['l_foot', [0, 0.1, 0], [1, 0, 0, 0]],
    setSettings: [{ iterations: 3 }],
    setEffects: [{ gravity: false }],
    keyInsert: [0.5, 'step'],
    keyDelete: [0],
    keyMove: [0, 1],
    bakeKeys: [30],
    record: [true],
    play: [],
    pause: [],
    seek: [1],
    setLoop: [true, 0, 2],
    setSpeed: [1],
    layerMute: [0, true],
    layerWeight: [0, 0.5],
    layerRemove: [0],
    bakeLayers: [],
    setFalloff: [0.5],
    undo: [],
    redo: [],
  };
  assert.deepEqual(Object.keys(full).sort(), Object.keys(msg).sort(), 'a builder without arguments here');
  const sent = {};
  for (const [name, args] of Object.entries(full)) {
    const m = msg[name](...args);
    assert.ok(Object.hasOwn(CLIENT_MESSAGES, m.type), `msg.${name} sends type '${m.type}', not in CLIENT_MESSAGES`);
    sent[m.type] ??= new Set();
    for (const key of Object.keys(m)) if (key !== 'type') sent[m.type].add(key);
  }
  for (const [type, fields] of Object.entries(CLIENT_MESSAGES)) {
    assert.deepEqual([...(sent[type] ?? [])].sort(), [...fields].sort(), `fields of ${type}`);
  }
  // the table is JSON, as the C++ side reads it from the source text
  const source = fs.readFileSync(path.join(WEB_DIR, 'js/protocol.js'), 'utf8');
  const start = source.indexOf('export const CLIENT_MESSAGES = ') + 'export const CLIENT_MESSAGES = '.length;
  const end = source.indexOf('\n};', start) + 2;
  assert.deepEqual(JSON.parse(source.slice(start, end)), CLIENT_MESSAGES);
});

test('swing–twist decomposition recomposes to the rotation', () => {
  const rand = lcg(11);
  for (let k = 0; k < 200; k++) {
    const q = randomUnitQuat(rand);
    if (q[0] < 0) q.forEach((x, i) => (q[i] = -x));
    const st = ranges.swingTwist(q);
    const swing = ranges.swingQuat(st.ay, st.az);
    const twist = [Math.cos(st.twist / 2), Math.sin(st.twist / 2), 0, 0];
    const back = ranges.qmul(swing, twist);
    const sameRotation = Math.abs(back.reduce((s, x, i) => s + x * q[i], 0)); // |<q, back>| = 1
    assert.ok(Math.abs(sameRotation - 1) < 1e-9, `q ${q} recomposed to ${back}`);
  }
});

test('hinge angles and the spherical range test of human48', () => {
  for (const angle of [-2.5, -0.3, 0, 0.7, 3]) {
    const axis = [0, 0.6, 0.8];
    const q = [Math.cos(angle / 2), ...axis.map((a) => a * Math.sin(angle / 2))];
    assert.ok(Math.abs(ranges.hingeAngle(q, axis) - angle) < 1e-12);
  }
  const human = JSON.parse(fs.readFileSync(path.join(SOURCE_DIR, 'characters/human48.json'), 'utf8'));
  const lumbar = human.links.find((l) => l.joint?.name === 'lumbar').joint.range;
  const link = { joint_type: 'spherical', range: lumbar };
  const F = lumbar.frame;
  // a rotation given in the range frame, expressed in the joint frame: F q F⁻¹
  const inJointFrame = (qr) => ranges.qmul(ranges.qmul(F, qr), ranges.qconj(F));
  assert.equal(ranges.jointLimitStatus(link, [1, 0, 0, 0]).inside, true);
  // swing halfway towards range vertex 1 stays inside; twice as far as the vertex is outside
  const [ay, az] = lumbar.vertices[1];
  assert.equal(ranges.jointLimitStatus(link, inJointFrame(ranges.swingQuat(ay / 2, az / 2))).inside, true);
  const far = ranges.jointLimitStatus(link, inJointFrame(ranges.swingQuat(0, Math.min(0.99, az * 2))));
  assert.equal(far.inside, false);
  assert.ok(far.violation > 0.1);
  // twist beyond the vertex's upper twist limit is outside, by the excess
  const hi = lumbar.vertices[0][3];
  const twisted = ranges.jointLimitStatus(link, inJointFrame([Math.cos((hi + 0.2) / 2), Math.sin((hi + 0.2) / 2), 0, 0]));
  assert.equal(twisted.inside, false);
  assert.ok(Math.abs(twisted.violation - 0.2) < 1e-9, `violation ${twisted.violation}`);
});
