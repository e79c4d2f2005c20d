// A small bar over the 3D view: show or hide the joint handles, the selected joint's range, the
// floor grid, a skinned character's mesh and a fitted trial's markers, snap keys to frames or not, let the camera follow the figure, choose what a playing
// clip does while a link is held, and put the camera back home.

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
  const whileDragging = h(
    'select#while-dragging',
    { title: 'What a playing clip does while you hold a link' },
    h('option', { value: 'play' }, 'play on'),
    h('option', { value: 'slow' }, 'slow (¼×)'),
    h('option', { value: 'pause' }, 'pause'),
  );
  whileDragging.value = state.view.whileDragging;
  whileDragging.addEventListener('change', () => {
    state.view.whileDragging = whileDragging.value;
    signals.viewOptionsChanged.dispatch({ ...state.view });
  });
  signals.viewOptionsChanged.add((v) => {
    for (const [key, input] of Object.entries(toggles)) input.checked = !!v[key];
    whileDragging.value = v.whileDragging;
  });
  return h(
    'div.view-options#view-options',
    {},
    toggle('handles', 'handles', 'Show joint handles (H)'),
    toggle('limits', 'ranges', 'Show the selected joint’s range (L)'),
    toggle('grid', 'grid', 'Show the floor grid'),
    toggle('mesh', 'mesh', 'Draw a skinned character’s mesh (off: its capsules)'),
    toggle('markers', 'markers', 'Draw a fitted marker trial’s markers, with lines to the figure’s markers coloured by distance'),
    toggle('snapKeys', 'snap keys', 'Keys land on frames at the clip’s rate'),
    toggle('follow', 'follow', 'The camera travels with the figure'),
    h('label.toggle', { title: 'What a playing clip does while you hold a link' }, 'while dragging ', whileDragging),
    h('button.small', { type: 'button', title: 'Reset the view (Shift+F)', onclick: () => viewport.home() }, 'Home view'),
  );
}
