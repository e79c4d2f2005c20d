// Physics effects (docs/simulation.md): one switch per effect, each with what it cost per frame
// (µs, from the pose frames' physics object), and two presets: "Pose" (all off: kinematic posing)
// and "Stand" (gravity, ground contact, friction and dynamic pins). A change is sent as
// set_effects with every flag; the switches show the session's scene as the server reports it.

import { h, panel, fmt } from './panel_util.js';
import { msg } from './protocol.js';

export const EFFECTS = [
  { name: 'gravity', label: 'Gravity', hint: 'the figure has weight' },
  { name: 'ground_contact', label: 'Ground contact', hint: 'soft contact with the ground (Yamane ch. 6)' },
  { name: 'friction', label: 'Friction', hint: 'static and sliding friction at the contacts' },
  { name: 'dynamic_pins', label: 'Dynamic pins', hint: 'pins and the drag act through the dynamics: dragging a hand shifts the pelvis (Yamane ch. 9)' },
  { name: 'hard_limits', label: 'Hard limits', hint: 'joint ranges as hard stops' },
  { name: 'self_collision', label: 'Self-collision', hint: 'soft contact between the links of the figure' },
];

export const PRESETS = {
  Pose: [],
  Stand: ['gravity', 'ground_contact', 'friction', 'dynamic_pins'],
};

/** The scene object set_effects carries: every effect named, on or off. */
export function sceneOf(onNames) {
  return Object.fromEntries(EFFECTS.map((e) => [e.name, onNames.includes(e.name)]));
}

export function createEffectsPanel(state, connection) {
  const { signals } = state;
  const { root, body } = panel('effects', 'Physics effects');
  let scene = sceneOf([]);
  const send = (next) => {
    scene = next;
    connection.send(msg.setEffects(next));
  };

  const presets = h(
    'div.effect-presets',
    {},
    Object.entries(PRESETS).map(([name, on]) =>
      h(`button.preset#preset-${name.toLowerCase()}`, { type: 'button', title: on.length ? `switch on: ${on.join(', ')}` : 'all effects off: kinematic posing', onclick: () => send(sceneOf(on)) }, name),
    ),
  );
  const rows = EFFECTS.map((e) => {
    const box = h(`input#effect-${e.name}`, { type: 'checkbox' });
    box.addEventListener('change', () => send({ ...scene, [e.name]: box.checked }));
    const cost = h('span.value', { dataset: { effect: e.name } }, '–');
    const row = h('div.effect', { title: e.hint }, box, h('label', { for: box.id }, e.label), cost, h('span.unit', {}, 'µs'));
    return { e, box, cost, row };
  });
  const total = h('span.value#effects-total', {}, '–');
  body.append(presets, ...rows.map((r) => r.row), h('div.effect.total', {}, h('span'), h('span.label', {}, 'All physics'), total, h('span.unit', {}, 'µs')));

  signals.sessionStateChanged.add((s) => {
    if (!s.scene) return;
    scene = sceneOf(EFFECTS.map((e) => e.name).filter((n) => s.scene[n]));
    for (const r of rows) r.box.checked = Boolean(scene[r.e.name]);
  });
  // per-frame costs arrive with every pose; the text is refreshed a few times a second
  let latest = null;
  signals.poseChanged.add((pose) => {
    latest = pose.physics;
  });
  setInterval(() => {
    for (const r of rows) {
      const us = latest?.stage_us?.[r.e.name];
      r.cost.textContent = latest && scene[r.e.name] ? fmt(us, 0) : '–';
    }
    total.textContent = latest ? fmt(latest.total_us, 0) : '–';
  }, 250);
  return root;
}
