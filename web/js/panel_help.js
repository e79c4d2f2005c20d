// The keyboard and mouse reference, shown with "?" and hidden with Esc or a click.

import { h } from './panel_util.js';

const ROWS = [
  ['Drag a joint or body part', 'pose it (the rest follows by IK)'],
  ['Right-click / P', 'pin or unpin the joint under the cursor / the selection'],
  ['Drag empty space', 'orbit · right-drag pans · wheel zooms'],
  ['W / E', 'pin gizmo: move / turn'],
  ['Space', 'play / pause'],
  ['← / →, Home / End', 'step one frame, first / last frame'],
  ['I / Delete', 'insert key / delete the selected key'],
  ['R', 'record on / off'],
  ['Ctrl+Z / Ctrl+Shift+Z', 'undo / redo'],
  ['F / Shift+F', 'focus the selection (nothing selected: frame the figure) / frame the figure'],
  ['H / L', 'show handles / joint ranges'],
  ['Esc', 'cancel the drag (restores the pose) · clear the selection'],
];

export function createHelpOverlay(state) {
  const root = h(
    'div.help-overlay#help-overlay',
    { hidden: true },
    h(
      'div.help-card',
      {},
      h('h2', {}, 'Pin and drag'),
      h('table', {}, ROWS.map(([k, v]) => h('tr', {}, h('th', {}, k), h('td', {}, v)))),
    ),
  );
  root.addEventListener('click', () => (root.hidden = true));
  state.signals.helpToggled.add((show) => {
    root.hidden = show === undefined ? !root.hidden : !show;
  });
  return root;
}
