// Boots the page: reads /api/config, opens (or resumes) a session, builds the views and panels and
// connects the WebSocket. Also exposes `window.pindrag`, a small read-only handle that the browser
// tests (and curious users in the console) use to find the session and where links are on screen.

import * as THREE from 'three';
import { createState, linkLabel } from './state.js';
import { createApi } from './api.js';
import { createConnection } from './connection.js';
import { createActions } from './actions.js';
import { createViewport } from './viewport.js';
import { createSkeletonView } from './skeleton_view.js';
import { createLimitsView } from './limits_view.js';
import { createPinsView } from './pins_view.js';
import { createDragControls } from './drag_controls.js';
import { createToolbar } from './panel_toolbar.js';
import { createTimelinePanel } from './panel_timeline.js';
import { createSelectionPanel } from './panel_selection.js';
import { createSettingsPanel } from './panel_settings.js';
import { createEffectsPanel } from './panel_effects.js';
import { createLayersPanel } from './panel_layers.js';
import { createPhysicsView } from './physics_view.js';
import { createStatusPanel } from './panel_status.js';
import { createToasts } from './panel_toasts.js';
import { createHelpOverlay } from './panel_help.js';
import { createSessionsPanel } from './panel_sessions.js';
import { rememberSession } from './known_sessions.js';
import { createViewOptions } from './panel_view_options.js';
import { createCameraFollow } from './camera_follow.js';
import { bindKeyboard } from './keyboard.js';
import { createOpenDialog } from './panel_open.js';
import { createSkinnedView } from './skinned_view.js';
import { createMarkersView } from './markers_view.js';

const SESSION_STORAGE_KEY = 'pindrag.session';
const SERVER_KEY_STORAGE_KEY = 'pindrag.key';

/** Resumes the session of this tab (after a reload) or creates a new one. */
async function openSession(api, character) {
  const saved = JSON.parse(sessionStorage.getItem(SESSION_STORAGE_KEY) || 'null');
  if (saved && saved.id && saved.token && !character) {
    api.sessionId = saved.id;
    api.token = saved.token;
    try {
      await api.snapshot();
      return saved;
    } catch {
      /* gone (server data dir wiped) or token refused: start afresh */
    }
  }
  const created = await api.createSession(character || 'human48');
  api.sessionId = created.id;
  api.token = created.token;
  sessionStorage.setItem(SESSION_STORAGE_KEY, JSON.stringify({ id: created.id, token: created.token }));
  rememberSession(created.id, created.token);
  return created;
}

/** Switches this tab to another saved session: the page reloads on it (without ?character=). */
function switchSession(id, token) {
  sessionStorage.setItem(SESSION_STORAGE_KEY, JSON.stringify({ id, token }));
  const url = new URL(location.href);
  url.searchParams.delete('character');
  location.assign(url.toString());
}

function showFatal(message) {
  const box = document.createElement('div');
  box.className = 'fatal';
  box.textContent = message;
  document.body.appendChild(box);
}

async function main() {
  const state = createState();
  const api = createApi();
  const params = new URLSearchParams(location.search);
  // a server reachable from other machines prints its URL with ?key=: keep it for this tab
  if (params.get('key')) sessionStorage.setItem(SERVER_KEY_STORAGE_KEY, params.get('key'));
  api.serverKey = sessionStorage.getItem(SERVER_KEY_STORAGE_KEY);

  let config;
  try {
    config = await api.config();
    const session = await openSession(api, params.get('character'));
    state.sessionId = session.id;
    state.token = session.token;
  } catch (err) {
    showFatal(`Could not start a session: ${err.message}`);
    throw err;
  }
  state.config = config;

  const connection = createConnection(state, config.ws_url);
  const actions = createActions(state, connection);

  const viewport = createViewport(state);
  document.getElementById('stage').appendChild(viewport.element);
  const skeleton = createSkeletonView(state, viewport);
  createLimitsView(state, viewport, skeleton);
  const pins = createPinsView(state, viewport, skeleton, connection);
  const drag = createDragControls(state, viewport, skeleton, connection, actions, pins);
  const skinned = createSkinnedView(state, viewport, skeleton, api);
  const markers = createMarkersView(state, viewport, skeleton, api);
  createCameraFollow(state, viewport, skeleton);
  frameEachNewCharacter(state, viewport, skeleton, skinned);
  createPhysicsView(state, viewport, document.getElementById('stage'));

  const openDialog = createOpenDialog(state, api, switchSession);
  document.getElementById('toolbar').appendChild(createToolbar(state, api, connection, actions, openDialog));
  document.getElementById('timeline').appendChild(createTimelinePanel(state, connection, actions));
  const sidebar = document.getElementById('sidebar');
  sidebar.append(
    createSelectionPanel(state, actions, skeleton),
    createSettingsPanel(state, connection),
    createLayersPanel(state, connection),
    createEffectsPanel(state, connection),
    createStatusPanel(state, connection),
    createSessionsPanel(state, api, switchSession),
  );
  document.getElementById('stage').append(createViewOptions(state, viewport), markers.legend, createToasts(state), createHelpOverlay(state));
  document.body.append(openDialog.overlay);
  bindKeyboard(state, actions, drag, viewport, skeleton);

  showCharacterInTitle(state);
  viewport.resize();
  connection.start();

  // The test and console handle. Everything here reads; changes go through the UI or the protocol.
  let poseFrames = 0;
  state.signals.poseChanged.add(() => poseFrames++);
  window.pindrag = {
    get sessionId() {
      return state.sessionId;
    },
    get token() {
      return state.token;
    },
    get connection() {
      return state.connection;
    },
    get session() {
      return state.session;
    },
    get poseFrames() {
      return poseFrames;
    },
    get lastPose() {
      return state.pose ? { frame: state.pose.frame, ack: state.pose.ack, time: state.pose.time, physics: state.pose.physics } : null;
    },
    get timeCursor() {
      return state.timeCursor;
    },
    get renders() {
      return viewport.stats.renders;
    },
    linkNames: () => (state.character ? state.character.links.map((l) => l.name) : []),
    /** Client (CSS pixel) coordinates of a link's pivot as drawn now. */
    project(name) {
      const i = state.linkIndex.get(name);
      const w = i === undefined ? null : skeleton.linkWorld(i);
      if (!w) return null;
      const s = viewport.toClient(w.position);
      return { x: s.x, y: s.y, visible: s.visible };
    },
    /** Client (CSS pixel) coordinates of a world point. */
    projectPoint(p) {
      const s = viewport.toClient({ x: p[0], y: p[1], z: p[2] });
      return { x: s.x, y: s.y, visible: s.visible };
    },
    /** World position of a link's pin marker as drawn now (null: not pinned). */
    pinMarker: (name) => pins.markerPosition(name),
    /** World position of a link's pivot as drawn now. */
    linkPosition(name) {
      const i = state.linkIndex.get(name);
      const w = i === undefined ? null : skeleton.linkWorld(i);
      return w ? w.position.toArray() : null;
    },
    /** World pose of a link as drawn now: {p: [x,y,z], q: [x,y,z,w]} (null: no such link). */
    linkPose(name) {
      const i = state.linkIndex.get(name);
      const w = i === undefined ? null : skeleton.linkWorld(i);
      return w ? { p: w.position.toArray(), q: w.quaternion.toArray() } : null;
    },
    camera: () => ({
      position: viewport.camera.position.toArray(),
      target: viewport.controls.target.toArray(),
      quaternion: viewport.camera.quaternion.toArray(),
    }),
    contextLost: () => viewport.renderer.getContext().isContextLost(),
    /** The fitted trial's markers drawn now (markers_view.js): frame, counts, residuals in metres. */
    markers: () => markers.stats(),
    /** The skinned mesh drawn now: {vertices, visible, parts, textured (parts drawn with an image)} (null: none). */
    mesh() {
      const m = skinned.object();
      if (!m) return null;
      const textured = m.material.filter((material) => material.map && material.map.image).length;
      return { vertices: m.geometry.attributes.position.count, visible: m.visible, parts: m.material.length, textured };
    },
    /** World position of skinned vertex i as drawn now (linear blend skinning by three.js). */
    skinnedVertex(i) {
      const m = skinned.object();
      if (!m) return null;
      return m.getVertexPosition(i, new THREE.Vector3()).applyMatrix4(m.matrixWorld).toArray();
    },
    /** The vertex weighted most to a link's bone: {index, weight} (null: the link has no bone). */
    vertexOfLink(name) {
      const m = skinned.object();
      const link = state.linkIndex.get(name);
      if (!m || link === undefined) return null;
      const bone = m.skeleton.bones.findIndex((b) => b.userData.link === link);
      if (bone < 0) return null;
      const idx = m.geometry.attributes.skinIndex;
      const w = m.geometry.attributes.skinWeight;
      let best = { index: -1, weight: 0 };
      for (let v = 0; v < idx.count; v++) {
        for (let k = 0; k < 4; k++) {
          if (idx.getComponent(v, k) === bone && w.getComponent(v, k) > best.weight) best = { index: v, weight: w.getComponent(v, k) };
        }
      }
      return best;
    },
    /** The colour [r, g, b] (0-255) drawn at a client point, from a fresh render. */
    pixelAt(x, y) {
      const r = viewport.renderer;
      r.render(viewport.scene, viewport.camera);
      const rect = r.domElement.getBoundingClientRect();
      const ratio = r.getPixelRatio();
      const px = Math.round((x - rect.left) * ratio);
      const py = Math.round(r.domElement.height - (y - rect.top) * ratio);
      const out = new Uint8Array(4);
      const gl = r.getContext();
      gl.readPixels(px, py, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, out);
      return [out[0], out[1], out[2]];
    },
    label: (i) => linkLabel(state, i),
  };
}

/** Home view frames the figure and its mesh; a newly loaded character is framed once its first
 *  pose is drawn, and again when its mesh arrives. */
function frameEachNewCharacter(state, viewport, skeleton, skinned) {
  viewport.subjectBounds = () => skinned.expandBounds(skeleton.bounds());
  let pending = false;
  state.signals.characterLoaded.add(() => (pending = true));
  state.signals.poseChanged.add(() => {
    if (!pending) return;
    pending = false;
    viewport.home();
  });
  state.signals.meshLoaded.add(() => {
    if (!pending) viewport.home();
  });
}

function showCharacterInTitle(state) {
  state.signals.characterLoaded.add((c) => {
    document.title = `pindrag · ${c.name}`;
  });
}

main();
