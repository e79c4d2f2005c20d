// The WebSocket to the session (docs/protocol.md): hello, one handle_message switch, auto-reconnect
// with back-off, and the latest-wins senders. Drag targets are absolute, so only the newest one
// matters: the page sends at most one drag_move per animation frame, and none while the socket
// still has more than BUFFERED_LIMIT bytes queued (the next frame sends the newest target anyway).

import { msg, decodePose, isNewerFrame, sessionFields, PROTOCOL_VERSION } from './protocol.js';

const BUFFERED_LIMIT = 64 * 1024;
const BACKOFF_FIRST_MS = 250;
const BACKOFF_MAX_MS = 5000;

export function createConnection(state, wsUrl) {
  const { signals } = state;
  let ws = null;
  let backoff = BACKOFF_FIRST_MS;
  let retryTimer = null;
  let closedByUs = false;
  let nextId = 1;

  // per-connection drag state
  let seq = 0;
  let dragActive = false;
  let pendingTarget = null; // newest drag target not sent yet
  let endRequested = false;
  let afterEnd = []; // messages that must follow drag_end (Esc: undo)
  const sentAt = new Map(); // seq -> performance.now() for the round trip readout
  let lastFrame = null;

  // latest-wins senders of other absolute samples, keyed (move_pin per link, seek)
  const pendingLatest = new Map();

  const stats = { rttMs: null, posesPerSecond: 0, lastAckSeq: 0, sentSeq: 0, dropped: 0 };
  let poseCount = 0;
  let poseWindowStart = performance.now();

  function status(s, extra = {}) {
    signals.connectionChanged.dispatch({ status: s, ...extra });
  }

  // Every edit carries an id, so the server answers it: `ack` once it is saved, `error` when it
  // was refused or could not be saved (then it was taken back). Drag samples need no answer.
  function rawSend(m) {
    if (!ws || ws.readyState !== WebSocket.OPEN) return false;
    if (m.id === undefined && m.type !== 'hello' && m.type !== 'drag_move') m = { ...m, id: nextId++ };
    ws.send(JSON.stringify(m));
    return true;
  }

  /** Sends an edit (reliable, in order). With want_ack, the server answers ack/error. */
  function send(m, { wantAck = false } = {}) {
    if (wantAck) m = { ...m, id: nextId++ };
    if (!rawSend(m)) {
      signals.notify.dispatch({ text: `not connected: '${m.type}' not sent`, kind: 'error' });
      return null;
    }
    return m.id ?? true;
  }

  function connect() {
    clearTimeout(retryTimer);
    const url = new URL(wsUrl);
    url.searchParams.set('session', state.sessionId);
    url.searchParams.set('token', state.token);
    status(ws ? 'reconnecting' : 'connecting');
    const socket = new WebSocket(url.toString());
    socket.binaryType = 'arraybuffer';
    ws = socket;
    seq = 0;
    lastFrame = null;
    sentAt.clear();
    stats.sentSeq = 0;
    stats.lastAckSeq = 0;
    socket.onopen = () => {
      backoff = BACKOFF_FIRST_MS;
      socket.send(JSON.stringify(msg.hello()));
      status('open');
    };
    socket.onmessage = (ev) => {
      if (socket !== ws) return;
      handle_message(ev.data);
    };
    socket.onclose = (ev) => {
      if (socket !== ws) return;
      if (dragActive) {
        dragActive = false;
        pendingTarget = null;
        endRequested = false;
        signals.dragChanged.dispatch({ active: false, link: -1, target: null, cancelled: true });
      }
      if (closedByUs) {
        status('closed');
        return;
      }
      if (ev.code === 1002 || ev.code === 1008) {
        status('closed', { message: `server closed the connection (${ev.code} ${ev.reason || ''})` });
        return;
      }
      const wait = backoff;
      backoff = Math.min(BACKOFF_MAX_MS, backoff * 2);
      status('reconnecting', { retryIn: wait, message: ev.reason || `closed (${ev.code})` });
      retryTimer = setTimeout(connect, wait);
    };
    socket.onerror = () => {
      /* onclose follows and schedules the retry */
    };
  }

  function handlePose(buffer) {
    let pose;
    try {
      pose = decodePose(buffer);
    } catch (err) {
      console.warn(err.message);
      return;
    }
    // render only the highest frame id
    if (!isNewerFrame(pose.frame, lastFrame)) {
      stats.dropped++;
      return;
    }
    lastFrame = pose.frame;
    poseCount++;
    const now = performance.now();
    if (now - poseWindowStart >= 1000) {
      stats.posesPerSecond = (poseCount * 1000) / (now - poseWindowStart);
      poseCount = 0;
      poseWindowStart = now;
    }
    if (pose.ack > stats.lastAckSeq || pose.ack === 0) {
      const t = sentAt.get(pose.ack);
      if (t !== undefined) stats.rttMs = now - t;
      for (const k of sentAt.keys()) if (k <= pose.ack) sentAt.delete(k);
      stats.lastAckSeq = pose.ack;
    }
    state.pose = pose;
    signals.poseChanged.dispatch(pose);
    signals.dragTargetAcked.dispatch(pose.ack >= stats.sentSeq && pendingTarget === null);
  }

  // The one switch over everything the server says.
  function handle_message(data) {
    if (typeof data !== 'string') {
      handlePose(data);
      return;
    }
    let m;
    try {
      m = JSON.parse(data);
    } catch {
      console.warn('server sent text that is not JSON');
      return;
    }
    switch (m.type) {
      case 'snapshot': {
        if (m.protocol !== undefined && m.protocol !== PROTOCOL_VERSION) {
          status('closed', { message: `server speaks protocol ${m.protocol}, the page ${PROTOCOL_VERSION}` });
          closedByUs = true;
          ws.close();
          return;
        }
        const sameFigure =
          state.character &&
          m.character &&
          state.character.name === m.character.name &&
          state.character.links.length === m.character.links.length;
        if (m.character && !sameFigure) {
          state.character = m.character;
          state.linkIndex = new Map(m.character.links.map((l, i) => [l.name, i]));
          signals.characterLoaded.dispatch(m.character);
        }
        state.session = sessionFields(m);
        signals.sessionStateChanged.dispatch(state.session);
        break;
      }
      case 'state':
        state.session = { ...(state.session || {}), ...sessionFields(m) };
        signals.sessionStateChanged.dispatch(state.session);
        break;
      case 'ack':
        signals.ackReceived.dispatch({ id: m.id, request: m.request });
        signals.savingChanged.dispatch({ saved: true });
        break;
      case 'error':
        signals.serverError.dispatch({ id: m.id, message: m.message || 'error' });
        if (m.code === 'not_saved') {
          // the server took the edit back and sends the state it kept
          signals.savingChanged.dispatch({ saved: false, message: m.message });
          signals.notify.dispatch({ text: m.message, kind: 'error' });
        } else {
          signals.notify.dispatch({ text: m.message || 'the server refused a request', kind: 'error' });
        }
        break;
      case 'report':
        state.report = m;
        signals.reportReceived.dispatch(m);
        break;
      default:
        console.warn(`unknown message type '${m.type}'`);
    }
  }

  // One animation-frame pump for every latest-wins sender.
  function pump() {
    requestAnimationFrame(pump);
    if (!ws || ws.readyState !== WebSocket.OPEN) return;
    if (ws.bufferedAmount > BUFFERED_LIMIT) return; // the newest sample goes next frame
    if (pendingTarget) {
      seq = (seq + 1) >>> 0;
      rawSend(msg.dragMove(seq, pendingTarget));
      sentAt.set(seq, performance.now());
      stats.sentSeq = seq;
      pendingTarget = null;
    }
    if (endRequested) {
      rawSend(msg.dragEnd());
      endRequested = false;
      for (const m of afterEnd) rawSend(m);
      afterEnd = [];
    }
    for (const m of pendingLatest.values()) rawSend(m);
    pendingLatest.clear();
  }
  requestAnimationFrame(pump);

  return {
    send,
    stats,
    get socket() {
      return ws;
    },
    start() {
      closedByUs = false;
      connect();
    },
    close() {
      closedByUs = true;
      clearTimeout(retryTimer);
      if (ws) ws.close();
    },
    /** Starts a drag gesture: reliable, sent now. */
    dragBegin(link, target, point) {
      if (!rawSend(msg.dragBegin(link, target, point))) return false;
      dragActive = true;
      endRequested = false;
      pendingTarget = null;
      return true;
    },
    /** Sets the newest drag target; the next animation frame sends it. */
    dragTo(target) {
      if (!dragActive) return;
      pendingTarget = [target[0], target[1], target[2]];
    },
    /** Ends the gesture after the last target is sent (same frame, in order); `then` follows. */
    dragEnd(then = []) {
      if (!dragActive) return;
      dragActive = false;
      endRequested = true;
      afterEnd = then;
    },
    get dragging() {
      return dragActive;
    },
    /** A latest-wins message: only the newest per key is sent, once per animation frame. */
    sendLatest(key, m) {
      pendingLatest.set(key, m);
    },
  };
}
