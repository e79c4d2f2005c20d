// Small DOM helpers shared by the panels.

/** h('div.cls#id', {attr: v, onclick: f}, ...children) */
export function h(tag, props = {}, ...children) {
  const [name, ...rest] = tag.split(/(?=[.#])/);
  const el = document.createElement(name || 'div');
  for (const r of rest) {
    if (r[0] === '.') el.classList.add(r.slice(1));
    else if (r[0] === '#') el.id = r.slice(1);
  }
  for (const [k, v] of Object.entries(props || {})) {
    if (v === undefined || v === null || v === false) continue;
    if (k.startsWith('on') && typeof v === 'function') el.addEventListener(k.slice(2), v);
    else if (k === 'dataset') Object.assign(el.dataset, v);
    else if (k === 'text') el.textContent = v;
    else if (k in el && typeof v !== 'string') el[k] = v;
    else el.setAttribute(k, v === true ? '' : v);
  }
  for (const c of children.flat()) {
    if (c === null || c === undefined || c === false) continue;
    el.append(c instanceof Node ? c : document.createTextNode(String(c)));
  }
  return el;
}

/** A collapsible sidebar panel: returns {root, body}. */
export function panel(className, title, open = true) {
  const body = h('div.panel-body');
  const root = h(`details.panel.${className}`, { open }, h('summary', {}, title), body);
  return { root, body };
}

export function fmt(x, digits = 1) {
  return Number.isFinite(x) ? x.toFixed(digits) : '–';
}

/** What a .gltf may reference beside it (its buffers and images): chosen together with it, these
 *  are sent as its "resource" files (the file pickers' `accept` lists them). */
export const GLTF_RESOURCES = '.bin,.png,.jpg,.jpeg,.webp,.ktx2';

/** Whether a file name ends in one of the extensions of an `accept` list ('.bvh,.glb'). */
export function hasExtension(name, accept) {
  const lower = name.toLowerCase();
  return accept.split(',').some((ext) => lower.endsWith(ext));
}

/** Why `file` cannot be uploaded to this server (over its largest upload cap), or null. */
export function uploadTooLarge(state, file) {
  const limit = state.config?.limits?.upload_bytes;
  if (!limit || file.size <= limit) return null;
  return `${file.name}: ${(file.size / 2 ** 20).toFixed(1)} MiB, over the ${(limit / 2 ** 20).toFixed(0)} MiB upload limit`;
}
