// The timeline: transport (first, step, play/pause, last), record, the time readout, a scrub track
// with the keys as diamonds (click selects, drag moves) and the loop range, loop and speed.

import { frameTimeOf, keyTime } from './frames.js';
import { h, fmt } from './panel_util.js';
import { INTERPOLATIONS, msg } from './protocol.js';

const SPEEDS = [0.25, 0.5, 1, 1.5, 2];
const MIN_SPAN_S = 2;

export function createTimelinePanel(state, connection, actions) {
  const { signals } = state;
  const button = (id, label, title, onclick) => h(`button.transport#${id}`, { type: 'button', title, onclick }, label);

  const first = button('tl-first', '«', 'First frame (Home)', actions.first);
  const back = button('tl-back', '‹', 'Previous frame (←)', () => actions.step(-1));
  const play = button('tl-play', '▶', 'Play / pause (Space)', actions.playPause);
  const fwd = button('tl-fwd', '›', 'Next frame (→)', () => actions.step(1));
  const last = button('tl-last', '»', 'Last frame (End)', actions.last);
  const record = button('tl-record', '●', 'Record the posed figure at 30 fps (R); stopping makes it the clip', actions.toggleRecord);
  record.classList.add('record');

  const timeText = h('span.time#tl-time', {}, '0.00 s');
  const frameText = h('span.frame#tl-frame', {}, 'frame 0');

  const loopInput = h('input#tl-loop', { type: 'checkbox' });
  loopInput.addEventListener('change', actions.toggleLoop);
  const speedSelect = h(
    'select#tl-speed',
    { title: 'Playback speed' },
    SPEEDS.map((s) => h('option', { value: String(s) }, `${s}×`)),
  );
  speedSelect.value = '1';
  speedSelect.addEventListener('change', () => actions.setSpeed(Number(speedSelect.value)));

  const interpSelect = h(
    'select#tl-interp',
    { title: 'Interpolation of new keys' },
    INTERPOLATIONS.map((m) => h('option', { value: m }, m)),
  );
  interpSelect.value = 'smooth';
  state.keyInterpolation = 'smooth';
  interpSelect.addEventListener('change', () => (state.keyInterpolation = interpSelect.value));
  const addKey = h('button#tl-key-insert', { type: 'button', title: 'Key the current pose (I)', onclick: () => actions.insertKey() }, '◆ Key');
  const delKey = h('button#tl-key-delete', { type: 'button', title: 'Delete the selected key (Delete)', disabled: true, onclick: actions.deleteKey }, 'Delete key');

  // the track
  const loopBand = h('div.loop-band');
  const keysLayer = h('div.keys');
  const ticks = h('div.ticks');
  const playhead = h('div.playhead', {}, h('div.playhead-knob'));
  const track = h('div.track#tl-track', { title: 'Scrub' }, ticks, loopBand, keysLayer, playhead);
  const info = h('span.clip-info#tl-clip', {}, 'no clip');

  let span = MIN_SPAN_S;
  const timeAt = (clientX) => {
    const r = track.getBoundingClientRect();
    return Math.max(0, Math.min(1, (clientX - r.left) / r.width)) * span;
  };
  const xOf = (t) => `${(100 * Math.max(0, Math.min(span, t))) / span}%`;

  let scrubbing = false;
  track.addEventListener('pointerdown', (e) => {
    if (e.button !== 0 || e.target.closest('.key')) return;
    scrubbing = true;
    track.setPointerCapture(e.pointerId);
    actions.seek(timeAt(e.clientX));
  });
  track.addEventListener('pointermove', (e) => {
    if (scrubbing) actions.seek(timeAt(e.clientX));
  });
  const stopScrub = () => (scrubbing = false);
  track.addEventListener('pointerup', stopScrub);
  track.addEventListener('pointercancel', stopScrub);

  function frameTime() {
    return frameTimeOf(state);
  }

  function showTime(t) {
    timeText.textContent = `${fmt(t, 2)} s`;
    frameText.textContent = `frame ${Math.round(t / frameTime())}`;
    playhead.style.left = xOf(t);
  }

  function renderKeys(keys) {
    keysLayer.replaceChildren();
    keys.forEach((k, index) => {
      const d = h('div.key', {
        title: `key ${index + 1}: ${fmt(k.time, 2)} s, ${k.interpolation}`,
        dataset: { index: String(index), interpolation: k.interpolation || 'smooth' },
      });
      d.style.left = xOf(k.time);
      d.classList.toggle('selected', state.selectedKey === index);
      let moved = false;
      d.addEventListener('pointerdown', (e) => {
        if (e.button !== 0) return;
        e.stopPropagation();
        moved = false;
        d.setPointerCapture(e.pointerId);
        signals.keySelectionChanged.dispatch(index);
      });
      d.addEventListener('pointermove', (e) => {
        if (!d.hasPointerCapture(e.pointerId)) return;
        moved = true;
        d.style.left = xOf(timeAt(e.clientX));
      });
      d.addEventListener('pointerup', (e) => {
        if (!d.hasPointerCapture(e.pointerId)) return;
        d.releasePointerCapture(e.pointerId);
        if (moved) connection.send(msg.keyMove(index, keyTime(state, timeAt(e.clientX))));
        else actions.seek(k.time);
      });
      keysLayer.appendChild(d);
    });
  }

  function renderTicks() {
    ticks.replaceChildren();
    const step = span <= 3 ? 0.5 : span <= 10 ? 1 : span <= 30 ? 5 : 10;
    for (let t = 0; t <= span + 1e-9; t += step) {
      const tick = h('div.tick', {}, h('span', {}, `${Number(t.toFixed(2))}s`));
      tick.style.left = xOf(t);
      ticks.appendChild(tick);
    }
  }

  signals.sessionStateChanged.add((s) => {
    const pb = s.playback || {};
    const keys = s.keys || [];
    const duration = pb.duration ?? s.clip?.duration ?? 0;
    const lastKey = keys.length ? Math.max(...keys.map((k) => k.time)) : 0;
    const newSpan = Math.max(MIN_SPAN_S, duration, lastKey + 0.5);
    if (newSpan !== span) {
      span = newSpan;
    }
    renderTicks();
    renderKeys(keys);
    play.textContent = pb.playing ? '❚❚' : '▶';
    play.classList.toggle('active', !!pb.playing);
    record.classList.toggle('active', !!s.recording);
    loopInput.checked = pb.loop !== false;
    if (pb.speed !== undefined) speedSelect.value = String(SPEEDS.includes(pb.speed) ? pb.speed : 1);
    const lo = pb.loop_start ?? 0;
    const hi = pb.loop_end === undefined || pb.loop_end < 0 ? duration || span : pb.loop_end;
    loopBand.style.left = xOf(lo);
    loopBand.style.width = `${(100 * Math.max(0, Math.min(span, hi) - lo)) / span}%`;
    loopBand.hidden = !loopInput.checked || !duration;
    info.textContent = s.clip
      ? `${s.clip.frames} frames · ${fmt(1 / s.clip.frame_time, 0)} fps · ${fmt(s.clip.duration, 2)} s`
      : keys.length
        ? `${keys.length} key${keys.length === 1 ? '' : 's'}, no clip`
        : 'no clip';
    if (!pb.playing && !state.pose) signals.timeCursorChanged.dispatch(pb.time || 0);
    else showTime(state.timeCursor);
    delKey.disabled = state.selectedKey < 0 || state.selectedKey >= keys.length;
  });
  signals.keySelectionChanged.add((i) => {
    for (const d of keysLayer.children) d.classList.toggle('selected', Number(d.dataset.index) === i);
    delKey.disabled = i < 0;
  });
  // while playing, the playhead follows the poses; otherwise it stays where it was put
  signals.poseChanged.add((pose) => {
    if (!scrubbing && state.session?.playback?.playing && pose.time !== state.timeCursor) {
      signals.timeCursorChanged.dispatch(pose.time);
    }
  });
  signals.timeCursorChanged.add(showTime);

  return h(
    'div.timeline',
    {},
    h('div.transport-row', {}, first, back, play, fwd, last, record),
    h('div.readout-time', {}, timeText, frameText),
    h('div.track-wrap', {}, track, info),
    h(
      'div.timeline-options',
      {},
      h('label.toggle', { title: 'Loop playback (the loop range is shaded)' }, loopInput, 'loop'),
      h('label.inline', {}, 'speed', speedSelect),
      h('span.divider'),
      interpSelect,
      addKey,
      delKey,
    ),
  );
}
