// Edit layers (docs/protocol.md, "layer" and "bake_layers"): one row per layer that editing in
// motion made (one gesture, one layer), with its name, the frames it edits, its weight, a mute
// switch and a delete button; "Bake" applies every unmuted layer to the clip. The rows show the
// session's layers as the server reports them; a change is sent and shown when the state returns.

import { h, panel, fmt } from './panel_util.js';
import { msg } from './protocol.js';

const MAX_WEIGHT = 2;

export function createLayersPanel(state, connection) {
  const { signals } = state;
  const { root, body } = panel('layers', 'Edit layers');
  const list = h('ol.layer-list#layer-list');
  const empty = h('div.hint#layers-empty', {}, 'Drag a link while a clip plays: each gesture becomes a layer here.');
  const bake = h('button#layers-bake', { type: 'button', title: 'Apply every unmuted layer to the clip and remove the layers', onclick: () => connection.send(msg.bakeLayers()) }, 'Bake');
  body.append(empty, list, h('div.layer-actions', {}, bake));

  function row(layer, index) {
    const mute = h('input.layer-mute', { type: 'checkbox', checked: !layer.muted, title: 'Use this layer (unchecked: muted)' });
    mute.addEventListener('change', () => connection.send(msg.layerMute(index, !mute.checked)));
    const weight = h('input.layer-weight', { type: 'range', min: 0, max: MAX_WEIGHT, step: 0.05, value: String(layer.weight), title: 'How much of the edit is applied' });
    const weightText = h('span.value', {}, fmt(layer.weight, 2));
    weight.addEventListener('input', () => (weightText.textContent = fmt(Number(weight.value), 2)));
    weight.addEventListener('change', () => connection.send(msg.layerWeight(index, Number(weight.value))));
    const remove = h('button.small.layer-remove', { type: 'button', title: 'Delete this layer', onclick: () => connection.send(msg.layerRemove(index)) }, '✕');
    const frames = h('span.layer-frames', {}, `frames ${layer.first_frame}–${layer.last_frame}`);
    const li = h('li.layer', { dataset: { index: String(index) } }, mute, h('span.layer-name', {}, layer.name), frames, remove, weight, weightText);
    li.classList.toggle('muted', !!layer.muted);
    return li;
  }

  signals.sessionStateChanged.add((s) => {
    const layers = s.layers || [];
    list.replaceChildren(...layers.map(row));
    empty.hidden = layers.length > 0;
    bake.disabled = layers.length === 0;
    root.dataset.count = String(layers.length);
  });
  return root;
}
