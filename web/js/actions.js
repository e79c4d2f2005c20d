// Commands shared by the keyboard, the context clicks and the panels. Each one turns an intent into
// protocol messages; nothing here changes the pose locally (the server answers with state and poses).

import { frameTimeOf, keyTime } from './frames.js';
import { msg } from './protocol.js';
import { pinOf, linkLabel } from './state.js';

export function createActions(state, connection) {
  const { signals } = state;
  const send = (m) => connection.send(m);
  const linkName = (i) => state.character?.links[i]?.name;
  const playback = () => state.session?.playback || { time: 0, playing: false, speed: 1, loop: true };
  const frameTime = () => frameTimeOf(state);

  const actions = {
    togglePin(link) {
      const name = linkName(link);
      if (!name) return;
      if (pinOf(state, link)) {
        send(msg.unpin(name));
        signals.notify.dispatch({ text: `unpinned ${linkLabel(state, link)}`, kind: 'info' });
      } else {
        send(msg.pin(name, state.pinMode));
        signals.notify.dispatch({ text: `pinned ${linkLabel(state, link)} (${state.pinMode})`, kind: 'info' });
      }
    },
    setPin(link, on) {
      const name = linkName(link);
      if (!name || !!pinOf(state, link) === !!on) return;
      send(on ? msg.pin(name, state.pinMode) : msg.unpin(name));
    },
    unpinAll() {
      for (const p of state.session?.pins || []) send(msg.unpin(p.link));
    },
    undo: () => send(msg.undo()),
    redo: () => send(msg.redo()),
    playPause() {
      send(playback().playing ? msg.pause() : msg.play());
    },
    /** Moves the playhead; the server shows the animation there (clamped to its end). */
    seek(t) {
      const time = Math.max(0, t);
      signals.timeCursorChanged.dispatch(time);
      connection.sendLatest('seek', msg.seek(time));
    },
    step(frames) {
      actions.seek(state.timeCursor + frames * frameTime());
    },
    first: () => actions.seek(0),
    last() {
      actions.seek(playback().duration ?? state.session?.clip?.duration ?? 0);
    },
    /** Keys the current pose at the playhead's frame (which may lie past the last key: that extends the
     * animation). */
    insertKey(interpolation) {
      send(msg.keyInsert(keyTime(state, state.timeCursor), interpolation || state.keyInterpolation || 'smooth'));
    },
    deleteKey() {
      if (state.selectedKey >= 0) {
        send(msg.keyDelete(state.selectedKey));
        signals.keySelectionChanged.dispatch(-1);
      }
    },
    toggleRecord() {
      send(msg.record(!state.session?.recording));
    },
    toggleLoop() {
      const pb = playback();
      send(msg.setLoop(!pb.loop, pb.loop_start ?? 0, pb.loop_end ?? -1));
    },
    setSpeed: (s) => send(msg.setSpeed(s)),
  };
  return actions;
}
