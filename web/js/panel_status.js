// Live readouts: connection, whether the last edit was saved, solver time per step, drag error, pin drift, limit violation, the
// pose stream rate and the drag round trip (drag_move sent -> pose that acknowledges it).

import { h, panel, fmt } from './panel_util.js';

export function createStatusPanel(state, connection) {
  const { root, body } = panel('status', 'Solver status');
  const rows = {};
  const row = (key, label, unit) => {
    const value = h('span.value', { dataset: { key } }, '–');
    rows[key] = value;
    return h('div.readout', {}, h('span.label', {}, label), value, h('span.unit', {}, unit || ''));
  };
  body.append(
    row('connection', 'Connection'),
    row('saving', 'Last edit'),
    row('microseconds', 'Solver step', 'µs'),
    row('drag_error', 'Drag error', 'mm'),
    row('pin_position_error', 'Pin drift', 'mm'),
    row('pin_orientation_error', 'Pin twist', '°'),
    row('limit_violation', 'Limit excess', '°'),
    row('top_rank', 'Drag rank'),
    row('poses', 'Pose stream', '/s'),
    row('rtt', 'Drag round trip', 'ms'),
  );

  state.signals.connectionChanged.add((c) => {
    const text =
      c.status === 'reconnecting' && c.retryIn ? `reconnecting in ${(c.retryIn / 1000).toFixed(1)} s` : c.status;
    rows.connection.textContent = text;
    rows.connection.className = `value conn-${c.status}`;
    rows.connection.title = c.message || '';
  });
  state.signals.savingChanged.add(({ saved, message }) => {
    rows.saving.textContent = saved ? 'saved' : 'not saved';
    rows.saving.classList.toggle('bad', !saved);
    rows.saving.title = saved ? '' : message || '';
  });
  // the drag readouts describe a drag in progress: nothing is shown while none is
  let dragging = false;
  const clearDragReadouts = () => {
    rows.drag_error.textContent = '–';
    rows.drag_error.classList.remove('warn');
    rows.top_rank.textContent = '–';
  };
  state.signals.dragChanged.add((d) => {
    dragging = d.active;
    if (!dragging) clearDragReadouts();
  });
  state.signals.reportReceived.add((r) => {
    rows.microseconds.textContent = fmt(r.microseconds, 0);
    rows.drag_error.textContent = fmt(r.drag_error * 1000, 2);
    rows.pin_position_error.textContent = fmt(r.pin_position_error * 1000, 2);
    rows.pin_orientation_error.textContent = fmt((r.pin_orientation_error * 180) / Math.PI, 2);
    rows.limit_violation.textContent = fmt((r.limit_violation * 180) / Math.PI, 2);
    rows.top_rank.textContent = r.top_rank ?? '–';
    rows.drag_error.classList.toggle('warn', r.drag_error > 0.01);
    rows.pin_position_error.classList.toggle('warn', r.pin_position_error > 0.005);
    if (!dragging) clearDragReadouts();
  });
  setInterval(() => {
    rows.poses.textContent = fmt(connection.stats.posesPerSecond, 0);
    rows.rtt.textContent = connection.stats.rttMs === null ? '–' : fmt(connection.stats.rttMs, 1);
  }, 500);
  return root;
}
