// The selected link (its joint, range status and pin) and the list of pins, with "unpin all".

import { h, panel, fmt } from './panel_util.js';
import { pinOf, linkLabel } from './state.js';

const deg = (r) => (r * 180) / Math.PI;

export function createSelectionPanel(state, actions, skeleton) {
  const { signals } = state;
  const { root, body } = panel('selection', 'Selection and pins');

  const title = h('div.sel-title#sel-name', {}, 'Nothing selected');
  const joint = h('div.sel-joint', {}, 'Click a joint handle or a body part; drag to pose it.');
  const range = h('div.sel-range#sel-range');
  const pinBox = h('input#sel-pin', { type: 'checkbox', disabled: true });
  pinBox.addEventListener('change', () => actions.setPin(state.selected, pinBox.checked));
  const focus = h('button.small#sel-focus', { type: 'button', title: 'Centre the view on it (F)', disabled: true, onclick: () => signals.focusRequested.dispatch(state.selected) }, 'Focus');
  const list = h('ul.pin-list#pin-list');
  const unpinAll = h('button.small#unpin-all', { type: 'button', disabled: true, onclick: actions.unpinAll }, 'Unpin all');

  body.append(
    title,
    joint,
    range,
    h('div.sel-actions', {}, h('label.toggle', { title: 'Pin the selected link (right-click or P)' }, pinBox, 'pinned'), focus),
    h('div.sub-heading', {}, h('span', {}, 'Pins'), unpinAll),
    list,
  );

  function renderSelection() {
    const i = state.selected;
    const link = i >= 0 ? state.character?.links[i] : null;
    pinBox.disabled = !link;
    focus.disabled = !link;
    if (!link) {
      title.textContent = 'Nothing selected';
      joint.textContent = 'Click a joint handle or a body part; drag to pose it.';
      range.textContent = '';
      pinBox.checked = false;
      return;
    }
    title.textContent = linkLabel(state, i);
    joint.textContent = `${link.name} · joint ${link.joint} (${link.joint_type})`;
    const pin = pinOf(state, i);
    pinBox.checked = !!pin;
    renderRange();
  }

  function renderRange() {
    const i = state.selected;
    if (i < 0 || !state.character) return;
    const link = state.character.links[i];
    let text = '';
    let bad = false;
    if (link.joint_type === 'revolute' && link.limits) {
      text = `range ${fmt(deg(link.limits[0]), 0)}° … ${fmt(deg(link.limits[1]), 0)}°`;
    } else if (link.joint_type === 'spherical' && link.range) {
      text = 'swing–twist range';
    } else {
      text = 'no range';
    }
    const status = skeleton.limitStatus(i);
    if (status && status.kind === 'hinge') text += ` · now ${fmt(deg(status.angle), 1)}°`;
    if (status && status.kind === 'spherical') text += ` · twist ${fmt(deg(status.swing.twist), 0)}°`;
    if (status && !status.inside) {
      text += ` · outside by ${fmt(deg(status.violation), 1)}°`;
      bad = true;
    }
    range.textContent = text;
    range.classList.toggle('bad', bad);
  }

  function renderPins() {
    const pins = state.session?.pins || [];
    unpinAll.disabled = !pins.length;
    list.replaceChildren(
      ...(pins.length
        ? pins.map((p) => {
            const i = state.linkIndex.get(p.link);
            return h(
              'li',
              { dataset: { link: p.link }, onclick: () => i !== undefined && signals.selectionChanged.dispatch(i) },
              h('span.pin-icon', {}, '●'),
              h('span.pin-name', {}, i !== undefined ? linkLabel(state, i) : p.link),
              h('span.pin-mode', {}, p.mode),
              h('button.tiny', { type: 'button', title: `Unpin ${p.link}`, onclick: (e) => { e.stopPropagation(); actions.setPin(i, false); } }, '✕'),
            );
          })
        : [h('li.empty', {}, 'No pins. Right-click a joint or press P.')]),
    );
    if (state.selected >= 0) pinBox.checked = !!pinOf(state, state.selected);
  }

  signals.selectionChanged.add(renderSelection);
  signals.characterLoaded.add(renderSelection);
  signals.sessionStateChanged.add(renderPins);
  let last = 0;
  signals.poseChanged.add(() => {
    const now = performance.now();
    if (now - last > 200) {
      last = now;
      renderRange();
    }
  });
  return root;
}
