// Solver settings (docs/ik.md): damping, iterations per frame and the task gains. Values come from
// the session's settings; a change is sent as set_settings (only the field that changed).

import { h, panel } from './panel_util.js';
import { msg } from './protocol.js';

const FIELDS = [
  { path: ['damping'], label: 'Damping k', min: 0.001, max: 0.3, step: 0.001, log: true, hint: 'SR-inverse damping: higher is smoother near singular poses, lower reaches further' },
  { path: ['iterations'], label: 'Iterations', min: 1, max: 10, step: 1, hint: 'solve steps per frame' },
  { path: ['gains', 'drag'], label: 'Drag gain', min: 1, max: 200, step: 1, unit: '1/s', hint: 'how fast the grabbed point follows the cursor' },
  { path: ['gains', 'pin'], label: 'Pin gain', min: 1, max: 200, step: 1, unit: '1/s', hint: 'how hard pins pull back' },
  { path: ['gains', 'reference'], label: 'Rest gain', min: 0, max: 20, step: 0.1, unit: '1/s', hint: 'while dragging, pull towards the posture the drag began in' },
  { path: ['gains', 'limit'], label: 'Limit gain', min: 0, max: 100, step: 1, unit: '1/s', hint: 'push back into joint ranges' },
];

const getPath = (o, path) => path.reduce((v, k) => (v == null ? undefined : v[k]), o);

function settingsPatch(path, value) {
  return path.length === 1 ? { [path[0]]: value } : { [path[0]]: { [path[1]]: value } };
}

export function createSettingsPanel(state, connection) {
  const { signals } = state;
  const { root, body } = panel('settings', 'Solver settings');
  const controls = FIELDS.map((f) => {
    const id = `set-${f.path.join('-')}`;
    const slider = h('input', { type: 'range', min: f.log ? Math.log10(f.min) : f.min, max: f.log ? Math.log10(f.max) : f.max, step: f.log ? 0.01 : f.step });
    const number = h(`input.num#${id}`, { type: 'number', min: f.min, max: f.max, step: f.step });
    const toSlider = (v) => (f.log ? Math.log10(Math.max(f.min, v)) : v);
    const fromSlider = (v) => (f.log ? Number((10 ** v).toPrecision(3)) : Number(v));
    let editing = false;
    const commit = (value) => {
      if (!Number.isFinite(value)) return;
      const v = Math.min(f.max, Math.max(f.min, f.step >= 1 ? Math.round(value) : value));
      number.value = String(v);
      slider.value = String(toSlider(v));
      connection.send(msg.setSettings(settingsPatch(f.path, v)));
    };
    slider.addEventListener('input', () => {
      editing = true;
      number.value = String(fromSlider(Number(slider.value)));
    });
    slider.addEventListener('change', () => {
      editing = false;
      commit(fromSlider(Number(slider.value)));
    });
    number.addEventListener('change', () => commit(Number(number.value)));
    const row = h('div.setting', { title: f.hint }, h('label', { for: id }, f.label), slider, number, h('span.unit', {}, f.unit || ''));
    return {
      row,
      show(settings) {
        const v = getPath(settings, f.path);
        row.classList.toggle('unknown', v === undefined);
        if (v === undefined || editing || document.activeElement === number) return;
        number.value = String(Number(Number(v).toPrecision(4)));
        slider.value = String(toSlider(Number(v)));
      },
    };
  });
  // hard pins rank above the drag and the ranges and are held every frame; soft pins sit below
  // an exact drag and give way (docs/ik.md, "Pin strength")
  const hardPins = h('input#set-hard_pins', { type: 'checkbox' });
  hardPins.addEventListener('change', () => connection.send(msg.setSettings({ hard_pins: hardPins.checked })));
  const hardRow = h(
    'div.setting',
    { title: 'hard: pins hold and a drag they forbid stops short; soft: the drag goes exactly where the pointer is and pins give way' },
    h('label', { for: 'set-hard_pins' }, 'Hard pins'),
    hardPins,
  );
  // the floor: posing keeps the figure above y = 0 and its resting links where they stand
  const floor = h('input#set-floor', { type: 'checkbox' });
  floor.addEventListener('change', () => connection.send(msg.setSettings({ floor: floor.checked })));
  const floorRow = h(
    'div.setting',
    { title: 'on: no link goes below the floor and links resting on it stay where they stand unless dragged' },
    h('label', { for: 'set-floor' }, 'Floor'),
    floor,
  );
  body.append(...controls.map((c) => c.row), hardRow, floorRow);
  signals.sessionStateChanged.add((s) => {
    if (s.settings) for (const c of controls) c.show(s.settings);
    if (s.settings && typeof s.settings.hard_pins === 'boolean') hardPins.checked = s.settings.hard_pins;
    if (s.settings && typeof s.settings.floor === 'boolean') floor.checked = s.settings.floor;
  });
  return root;
}
