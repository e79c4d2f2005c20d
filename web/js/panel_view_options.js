// A small bar over the 3D view: show or hide the joint handles, the selected joint's range and the
// floor grid, snap keys to frames or not, and put the camera back home.

import { h } from './panel_util.js';

export function createViewOptions(state, viewport) {
  const { signals } = state;
  const toggles = {};
  const toggle = (key, label, title) => {
    const input = h('input', { type: 'checkbox', checked: state.view[key] });
    input.addEventListener('change', () => {
      state.view[key] = input.checked;
      signals.viewOptionsChanged.dispatch({ ...state.view });
    });
    toggles[key] = input;
    return h('label.toggle', { title }, input, label);
  };
  signals.viewOptionsChanged.add((v) => {
    for (const [key, input] of Object.entries(toggles)) input.checked = !!v[key];
  });
  return h(
    'div.view-options#view-options',
    {},
    toggle('handles', 'handles', 'Show joint handles (H)'),
    toggle('limits', 'ranges', 'Show the selected joint’s range (L)'),
    toggle('grid', 'grid', 'Show the floor grid'),
    toggle('snapKeys', 'snap keys', 'Keys land on frames at the clip’s rate'),
    h('button.small', { type: 'button', title: 'Reset the view (Shift+F)', onclick: () => viewport.home() }, 'Home view'),
  );
}
