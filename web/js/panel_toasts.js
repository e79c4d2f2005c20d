// Short messages for the user (what was pinned, exported, refused), fading after a few seconds.

import { h } from './panel_util.js';

const SHOW_MS = { info: 2500, error: 6000 };
const MAX_SHOWN = 4;

export function createToasts(state) {
  const root = h('div.toasts#toasts', { 'aria-live': 'polite' });
  state.signals.notify.add(({ text, kind = 'info' }) => {
    const toast = h(`div.toast.${kind}`, {}, text);
    root.appendChild(toast);
    while (root.children.length > MAX_SHOWN) root.firstChild.remove();
    setTimeout(() => toast.classList.add('leaving'), SHOW_MS[kind] || SHOW_MS.info);
    setTimeout(() => toast.remove(), (SHOW_MS[kind] || SHOW_MS.info) + 400);
  });
  return root;
}
