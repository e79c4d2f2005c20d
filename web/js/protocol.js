// The wire protocol of docs/protocol.md, version 1: builders of the client's JSON messages and
// the binary pose frame codec. This file has no imports so Node (the tests, the fake server) can
// use the same code as the page.

export const PROTOCOL_VERSION = 1;
export const POSE_MAGIC = 0x46504450; // "PDPF" little-endian
export const POSE_HEADER_BYTES = 36;
export const POSE_LINK_FLOATS = 11;
export const POSE_LINK_BYTES = POSE_LINK_FLOATS * 4;

export const PIN_MODES = ['position', 'orientation', 'pose'];
export const INTERPOLATIONS = ['step', 'linear', 'smooth'];
export const EXPORT_FORMATS = ['bvh', 'gltf', 'glb'];

/**
 * Every client → server message type and its fields besides `type` and `id` (docs/protocol.md),
 * in the order of the protocol table. Data only, written as JSON: tests/server/protocol_test.cpp
 * reads it from this file and compares it with the server's message structs, and
 * tests/web/protocol_codec_test.mjs checks that the builders in `msg` send exactly these.
 */
export const CLIENT_MESSAGES = {
  "hello": ["protocol"],
  "drag_begin": ["link", "target", "point"],
  "drag_move": ["seq", "target", "rotation"],
  "drag_end": [],
  "pin": ["link", "mode", "point"],
  "unpin": ["link"],
  "move_pin": ["link", "target", "rotation"],
  "set_settings": ["settings"],
  "set_effects": ["scene"],
  "key_insert": ["time", "interpolation"],
  "key_delete": ["index"],
  "key_move": ["index", "time"],
  "bake_keys": ["rate"],
  "record": ["on"],
  "play": [],
  "pause": [],
  "seek": ["time"],
  "set_loop": ["loop", "start", "end"],
  "set_speed": ["speed"],
  "layer": ["index", "muted", "weight", "remove"],
  "bake_layers": [],
  "set_falloff": ["seconds"],
  "undo": [],
  "redo": []
};

const vec3 = (v) => [Number(v[0]), Number(v[1]), Number(v[2])];
const quat = (q) => [Number(q[0]), Number(q[1]), Number(q[2]), Number(q[3])];

/** Client → server messages. Positions [x, y, z] (world, metres), rotations [w, x, y, z]. */
export const msg = {
  hello: () => ({ type: 'hello', protocol: PROTOCOL_VERSION }),
  dragBegin: (link, target, point) => {
    const m = { type: 'drag_begin', link, target: vec3(target) };
    if (point) m.point = vec3(point);
    return m;
  },
  dragMove: (seq, target, rotation) => {
    const m = { type: 'drag_move', seq: seq >>> 0, target: vec3(target) };
    if (rotation) m.rotation = quat(rotation);
    return m;
  },
  dragEnd: () => ({ type: 'drag_end' }),
  pin: (link, mode = 'pose', point) => {
    if (!PIN_MODES.includes(mode)) throw new Error(`pin mode '${mode}' is not one of ${PIN_MODES}`);
    const m = { type: 'pin', link, mode };
    if (point) m.point = vec3(point);
    return m;
  },
  unpin: (link) => ({ type: 'unpin', link }),
  movePin: (link, target, rotation) => {
    const m = { type: 'move_pin', link, target: vec3(target) };
    if (rotation) m.rotation = quat(rotation);
    return m;
  },
  setSettings: (settings) => ({ type: 'set_settings', settings }),
  setEffects: (scene) => ({ type: 'set_effects', scene }),
  keyInsert: (time, interpolation) => {
    const m = { type: 'key_insert' };
    if (time !== undefined && time !== null) m.time = Number(time);
    if (interpolation) m.interpolation = interpolation;
    return m;
  },
  keyDelete: (index) => ({ type: 'key_delete', index }),
  keyMove: (index, time) => ({ type: 'key_move', index, time: Number(time) }),
  bakeKeys: (rate) => (rate ? { type: 'bake_keys', rate: Number(rate) } : { type: 'bake_keys' }),
  record: (on) => ({ type: 'record', on: !!on }),
  play: () => ({ type: 'play' }),
  pause: () => ({ type: 'pause' }),
  seek: (time) => ({ type: 'seek', time: Math.max(0, Number(time)) }),
  setLoop: (loop, start, end) => {
    const m = { type: 'set_loop', loop: !!loop };
    if (start !== undefined) m.start = Number(start);
    if (end !== undefined) m.end = Number(end);
    return m;
  },
  setSpeed: (speed) => ({ type: 'set_speed', speed: Number(speed) }),
  layerMute: (index, muted) => ({ type: 'layer', index, muted: !!muted }),
  layerWeight: (index, weight) => ({ type: 'layer', index, weight: Number(weight) }),
  layerRemove: (index) => ({ type: 'layer', index, remove: true }),
  bakeLayers: () => ({ type: 'bake_layers' }),
  setFalloff: (seconds) => ({ type: 'set_falloff', seconds: Number(seconds) }),
  undo: () => ({ type: 'undo' }),
  redo: () => ({ type: 'redo' }),
};

/**
 * Decodes a binary pose frame. Returns
 * {frame, ack, time, root: Float32Array(3), n, links: [{p: [x,y,z], R: [w,x,y,z], q: [w,x,y,z]}]}
 * or throws an Error naming what is wrong.
 */
export function decodePose(buffer) {
  const bytes = buffer instanceof ArrayBuffer ? new Uint8Array(buffer) : buffer;
  const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  if (view.byteLength < POSE_HEADER_BYTES) {
    throw new Error(`pose frame: ${view.byteLength} bytes, shorter than the ${POSE_HEADER_BYTES}-byte header`);
  }
  const magic = view.getUint32(0, true);
  if (magic !== POSE_MAGIC) throw new Error(`pose frame: bad magic 0x${magic.toString(16)}`);
  const version = view.getUint16(4, true);
  if (version !== PROTOCOL_VERSION) throw new Error(`pose frame: protocol ${version}, expected ${PROTOCOL_VERSION}`);
  const n = view.getUint16(6, true);
  const expected = POSE_HEADER_BYTES + n * POSE_LINK_BYTES;
  if (view.byteLength < expected) {
    throw new Error(`pose frame: ${view.byteLength} bytes for ${n} links, expected ${expected}`);
  }
  const frame = view.getUint32(8, true);
  const ack = view.getUint32(12, true);
  const time = view.getFloat64(16, true);
  const root = [view.getFloat32(24, true), view.getFloat32(28, true), view.getFloat32(32, true)];
  const links = new Array(n);
  let o = POSE_HEADER_BYTES;
  for (let i = 0; i < n; i++) {
    const f = (k) => view.getFloat32(o + 4 * k, true);
    links[i] = { p: [f(0), f(1), f(2)], R: [f(3), f(4), f(5), f(6)], q: [f(7), f(8), f(9), f(10)] };
    o += POSE_LINK_BYTES;
  }
  // while physics runs, a JSON object {"physics": ...} follows the links
  const physics = view.byteLength > expected ? decodeTrailer(bytes.subarray(expected)).physics ?? null : null;
  return { frame, ack, time, root, n, links, physics };
}

function decodeTrailer(bytes) {
  try {
    return JSON.parse(new TextDecoder().decode(bytes));
  } catch (err) {
    throw new Error(`pose frame: the physics object is not JSON (${err.message})`);
  }
}

/** Encodes a pose frame (the server's job; here for the fake server and the codec test). */
export function encodePose({ frame, ack = 0, time = 0, root, links, physics = null }) {
  const n = links.length;
  const trailer = physics ? new TextEncoder().encode(JSON.stringify({ physics })) : new Uint8Array(0);
  const buf = new ArrayBuffer(POSE_HEADER_BYTES + n * POSE_LINK_BYTES + trailer.byteLength);
  const view = new DataView(buf);
  view.setUint32(0, POSE_MAGIC, true);
  view.setUint16(4, PROTOCOL_VERSION, true);
  view.setUint16(6, n, true);
  view.setUint32(8, frame >>> 0, true);
  view.setUint32(12, ack >>> 0, true);
  view.setFloat64(16, time, true);
  const r = root || links[0]?.p || [0, 0, 0];
  for (let k = 0; k < 3; k++) view.setFloat32(24 + 4 * k, r[k], true);
  let o = POSE_HEADER_BYTES;
  for (const l of links) {
    const vals = [...l.p, ...l.R, ...(l.q || [1, 0, 0, 0])];
    for (let k = 0; k < POSE_LINK_FLOATS; k++) view.setFloat32(o + 4 * k, vals[k], true);
    o += POSE_LINK_BYTES;
  }
  new Uint8Array(buf, o).set(trailer);
  return buf;
}

/** Newer-frame test with u32 wrap-around (frame ids increase per session). */
export function isNewerFrame(frame, than) {
  if (than === null || than === undefined) return true;
  const d = (frame - than) >>> 0;
  return d !== 0 && d < 0x80000000;
}

/** The session fields of a snapshot or state message (everything but type and character). */
export function sessionFields(m) {
  const out = {};
  for (const [k, v] of Object.entries(m)) if (k !== 'type' && k !== 'character') out[k] = v;
  return out;
}
