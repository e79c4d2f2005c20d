// The top bar: the character, Open…, undo/redo, pin mode, gizmo mode, clip upload, export buttons
// and the connection badge.

import { h, uploadTooLarge, GLTF_RESOURCES, hasExtension } from './panel_util.js';
import { PIN_MODES, EXPORT_FORMATS } from './protocol.js';

// a marker trial (.c3d) is fitted onto the character by the server (docs/marker-fitting.md)
const ACCEPTED_CLIPS = '.bvh,.glb,.gltf,.fbx,.dae,.c3d';

function segmented(name, options, current, onPick) {
  const buttons = options.map(([value, label, title]) =>
    h('button.seg', { type: 'button', title, dataset: { value }, onclick: () => onPick(value) }, label),
  );
  const root = h(`div.segmented.${name}`, { role: 'group' }, buttons);
  const select = (value) => buttons.forEach((b) => b.classList.toggle('active', b.dataset.value === value));
  select(current);
  return { root, select };
}

export function createToolbar(state, api, connection, actions, openDialog) {
  const { signals } = state;

  const characterName = h('span.character-name', {}, '…');
  const brand = h('div.brand', {}, h('span.logo', { 'aria-hidden': 'true' }, '◉'), h('span.name', {}, 'pindrag'), characterName);

  const undo = h('button.icon#undo', { type: 'button', title: 'Undo (Ctrl+Z)', disabled: true, onclick: actions.undo }, '↶');
  const redo = h('button.icon#redo', { type: 'button', title: 'Redo (Ctrl+Shift+Z)', disabled: true, onclick: actions.redo }, '↷');

  const pinMode = segmented(
    'pin-mode',
    PIN_MODES.map((m) => [m, m, `new pins hold the link's ${m === 'pose' ? 'position and orientation' : m}`]),
    state.pinMode,
    (m) => signals.pinModeChanged.dispatch(m),
  );
  signals.pinModeChanged.add(pinMode.select);

  const gizmoMode = segmented(
    'gizmo-mode',
    [
      ['translate', 'move', 'pin gizmo moves the target (W)'],
      ['rotate', 'turn', 'pin gizmo turns the target (E)'],
    ],
    state.gizmoMode,
    (m) => signals.gizmoModeChanged.dispatch(m),
  );
  signals.gizmoModeChanged.add(gizmoMode.select);

  // clip upload
  const fileInput = h('input#clip-file', { type: 'file', accept: `${ACCEPTED_CLIPS},${GLTF_RESOURCES}`, multiple: true, hidden: true });
  const uploadButton = h('button#upload-clip', { type: 'button', title: 'Load a clip (BVH, glTF, FBX) or fit a marker trial (C3D) onto this character', onclick: () => fileInput.click() }, 'Load clip…');
  fileInput.addEventListener('change', async () => {
    const files = [...fileInput.files];
    fileInput.value = '';
    if (!files.length) return;
    // one clip file; the rest are the files a .gltf references (a "glTF Separate" export)
    const file = files.find((f) => hasExtension(f.name, ACCEPTED_CLIPS));
    if (!file) {
      signals.notify.dispatch({ text: `choose a clip file (${ACCEPTED_CLIPS}); a .gltf's buffers and images go with it`, kind: 'error' });
      return;
    }
    const resources = files.filter((f) => f !== file);
    const tooLarge = uploadTooLarge(state, file);
    if (tooLarge) {
      signals.notify.dispatch({ text: tooLarge, kind: 'error' });
      return;
    }
    uploadButton.disabled = true;
    try {
      const r = await api.uploadClip(file, { resources });
      signals.notify.dispatch({ text: `${file.name}: ${r.frames} frames at ${(1 / r.frame_time).toFixed(1)} fps`, kind: 'info' });
    } catch (err) {
      if (err.code === 'skeleton_differs') openDialog.offerOwnCharacter(file, err.message, resources);
      else signals.notify.dispatch({ text: err.message, kind: 'error' });
    } finally {
      uploadButton.disabled = false;
    }
  });

  // exports
  const exportButtons = EXPORT_FORMATS.map((format) =>
    h(
      `button.export#export-${format}`,
      {
        type: 'button',
        title: `Download the animation as ${format.toUpperCase()}`,
        onclick: async (e) => {
          const b = e.currentTarget;
          b.disabled = true;
          try {
            const r = await api.exportDownload(format);
            signals.notify.dispatch({ text: `exported ${r.name} (${(r.bytes / 1024).toFixed(1)} KiB)`, kind: 'info' });
          } catch (err) {
            signals.notify.dispatch({ text: err.message, kind: 'error' });
          } finally {
            b.disabled = false;
          }
        },
      },
      format.toUpperCase(),
    ),
  );

  const badge = h('span.conn-badge#connection', { title: '' }, h('span.dot'), h('span.text', {}, 'connecting'));
  signals.connectionChanged.add((c) => {
    badge.className = `conn-badge conn-${c.status}`;
    const text =
      c.status === 'open' ? 'live' : c.status === 'reconnecting' && c.retryIn ? `reconnecting (${(c.retryIn / 1000).toFixed(1)} s)` : c.status;
    badge.querySelector('.text').textContent = text;
    badge.title = c.message || '';
  });
  // stays until an edit is saved again: the server could not write the last one and undid it
  const notSaved = h('span.save-badge#not-saved', { hidden: true }, 'not saved');
  signals.savingChanged.add(({ saved, message }) => {
    notSaved.hidden = saved;
    notSaved.title = saved ? '' : `${message || 'the server could not save'}; the edit is undone`;
  });
  const help = h('button.icon#help', { type: 'button', title: 'Keyboard and mouse (?)', onclick: () => signals.helpToggled.dispatch() }, '?');

  signals.characterLoaded.add((c) => {
    characterName.textContent = c.name;
    characterName.title = c.unit ? `read from BVH in ${c.unit}` : '';
  });
  signals.sessionStateChanged.add((s) => {
    const u = s.undo || {};
    const labels = u.labels || [];
    undo.disabled = !u.can_undo;
    redo.disabled = !u.can_redo;
    undo.title = u.can_undo && labels.length ? `Undo ${labels[labels.length - 1]} (Ctrl+Z)` : 'Undo (Ctrl+Z)';
  });

  return h(
    'div.toolbar-inner',
    {},
    brand,
    h('div.group', {}, undo, redo),
    h('div.group', {}, h('span.group-label', {}, 'Pin'), pinMode.root),
    h('div.group', {}, h('span.group-label', {}, 'Gizmo'), gizmoMode.root),
    h('div.spacer'),
    h('div.group', {}, openDialog.button, uploadButton, fileInput),
    h('div.group', {}, h('span.group-label', {}, 'Export'), exportButtons),
    notSaved,
    badge,
    help,
  );
}
