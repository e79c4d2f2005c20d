// The page's shared state and its event bus. Panels and views talk only through these signals
// (STYLE.md §9): a module that changes something dispatches a signal, the modules that show it
// listen. Nothing here touches the DOM or the network.

/** A minimal signal: add(listener) returns a function that removes it. */
export class Signal {
  constructor() {
    this.listeners = [];
  }
  add(listener) {
    this.listeners.push(listener);
    return () => this.remove(listener);
  }
  remove(listener) {
    const i = this.listeners.indexOf(listener);
    if (i >= 0) this.listeners.splice(i, 1);
  }
  dispatch(...args) {
    for (const listener of this.listeners.slice()) {
      try {
        listener(...args);
      } catch (err) {
        console.error('signal listener failed:', err);
      }
    }
  }
}

/** Every signal of the page, with what it carries. */
export const SIGNAL_NAMES = [
  'connectionChanged', // {status: 'connecting'|'open'|'reconnecting'|'closed', retryIn?, message?}
  'characterLoaded', // the snapshot's character (links, shapes, ranges) — a new figure to build
  'meshLoaded', // the character's skinned mesh is drawn (it arrives after the character)
  'sessionStateChanged', // the snapshot/state fields: pins, keys, clip, layers, playback, undo, ...
  'poseChanged', // a decoded pose frame (the newest one)
  'reportReceived', // the solver's live report
  'serverError', // {message, request}
  'ackReceived', // {id, request}
  'savingChanged', // {saved: bool, message?} — whether the server could save the last edit
  'hoverChanged', // link index or -1
  'selectionChanged', // link index or -1
  'dragChanged', // {active, link, target (THREE.Vector3) | null}
  'dragTargetAcked', // true when the newest drag sample is in the pose the page shows
  'keySelectionChanged', // key index or -1
  'timeCursorChanged', // seconds: where the playhead is (and where a new key goes)
  'pinModeChanged', // 'position' | 'orientation' | 'pose'
  'gizmoModeChanged', // 'translate' | 'rotate'
  'viewOptionsChanged', // {limits, handles, grid, snapKeys, follow, whileDragging}
  'focusRequested', // a link index to centre the camera on
  'helpToggled', // bool (show) or undefined (toggle)
  'notify', // {text, kind: 'info'|'error'} — a short message for the user
  'renderRequested', // something in the 3D view changed
];

export function createState() {
  const signals = {};
  for (const name of SIGNAL_NAMES) signals[name] = new Signal();
  const state = {
    signals,
    // session
    sessionId: null,
    token: null,
    config: null,
    // what the server told us last
    character: null, // snapshot.character
    linkIndex: new Map(), // link name -> index in character.links
    session: null, // the latest snapshot/state (without character)
    pose: null, // the newest decoded pose frame
    report: null,
    connection: 'connecting',
    // local UI state
    hover: -1,
    selected: -1,
    selectedKey: -1,
    timeCursor: 0, // the playhead; may lie past the end of the animation (the next key goes there)
    dragging: null, // {link, target}
    pinMode: 'pose',
    gizmoMode: 'translate',
    // whileDragging: what a playing clip does while a link is held: 'play' | 'slow' | 'pause'
    view: { limits: true, handles: true, grid: true, snapKeys: true, follow: false, mesh: true, markers: true, whileDragging: 'play' },
  };
  signals.hoverChanged.add((i) => (state.hover = i));
  signals.selectionChanged.add((i) => (state.selected = i));
  signals.keySelectionChanged.add((i) => (state.selectedKey = i));
  signals.timeCursorChanged.add((t) => (state.timeCursor = t));
  signals.pinModeChanged.add((m) => (state.pinMode = m));
  signals.gizmoModeChanged.add((m) => (state.gizmoMode = m));
  signals.connectionChanged.add((c) => (state.connection = c.status));
  return state;
}

/** The pin of a link (by index), or null. */
export function pinOf(state, link) {
  if (!state.session || !state.character || link < 0) return null;
  const name = state.character.links[link]?.name;
  return (state.session.pins || []).find((p) => p.link === name) || null;
}

/** Whether pins move with the motion: over a clip they follow their links' trajectories
 *  (editing in motion, Yamane eq. 8.30) instead of holding a fixed target. */
export function pinsMove(state) {
  return !!state.session?.clip;
}

/** Display name of a link. */
export function linkLabel(state, link) {
  const l = state.character?.links[link];
  if (!l) return '';
  return l.display_name || l.name;
}
