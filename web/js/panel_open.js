// "Open…": the character and scene picker. It lists the bundled characters, takes a character
// file of the user's (URDF, pindrag JSON, BVH, glTF/GLB, FBX, DAE; a file with motion brings its
// clip) and the sessions saved from this browser. Opening makes a new session and this tab
// switches to it; the current session stays saved and is listed here and in the Sessions panel.
// It also asks what to do with a clip whose skeleton differs from the character's ("Load clip…"):
// open it as its own character, retarget it onto this one, or leave it.

import { h, uploadTooLarge } from './panel_util.js';
import { knownSessions, rememberSession } from './known_sessions.js';

const ACCEPTED_CHARACTERS = '.urdf,.json,.bvh,.glb,.gltf,.fbx,.dae';
const BVH_UNITS = [
  ['auto', 'guess from its height'],
  ['m', 'metres'],
  ['cm', 'centimetres'],
  ['mm', 'millimetres'],
  ['in', 'inches'],
  ['cmu', 'CMU units'],
];

export function createOpenDialog(state, api, switchSession) {
  const notify = (text, kind = 'info') => state.signals.notify.dispatch({ text, kind });

  const card = h('div.open-card', { role: 'dialog', 'aria-modal': 'true' });
  const overlay = h('div.open-overlay#open-dialog', { hidden: true }, card);
  overlay.addEventListener('click', (e) => {
    if (e.target === overlay) close();
  });
  overlay.addEventListener('keydown', (e) => {
    if (e.key === 'Escape') close();
    e.stopPropagation(); // the page's shortcuts stay off while the dialog is up
  });

  function close() {
    overlay.hidden = true;
    card.replaceChildren();
  }

  function show(...children) {
    card.replaceChildren(...children);
    overlay.hidden = false;
    card.querySelector('button')?.focus();
  }

  // the new session is remembered (its token) and this tab reloads on it
  async function openCreated(promise, what) {
    const status = card.querySelector('.open-status');
    if (status) status.textContent = `opening ${what}…`;
    card.querySelectorAll('button').forEach((b) => (b.disabled = true));
    try {
      const { id, token } = await promise;
      rememberSession(id, token);
      switchSession(id, token);
    } catch (err) {
      card.querySelectorAll('button').forEach((b) => (b.disabled = false));
      if (status) status.textContent = err.message;
      notify(err.message, 'error');
    }
  }

  function fileButton() {
    const input = h('input#open-character-file', { type: 'file', accept: ACCEPTED_CHARACTERS, hidden: true });
    input.addEventListener('change', () => {
      const file = input.files[0];
      input.value = '';
      if (!file) return;
      const tooLarge = uploadTooLarge(state, file);
      if (tooLarge) {
        notify(tooLarge, 'error');
        return;
      }
      openCreated(api.createSessionFromFile(file, units.value), file.name);
    });
    const button = h('button#open-file', { type: 'button', onclick: () => input.click() }, 'Character file…');
    const units = h(
      'select#open-units',
      { title: 'The unit a BVH file is read in (others carry theirs)' },
      ...BVH_UNITS.map(([value, label]) => h('option', { value }, label)),
    );
    return [button, input, h('label.open-meta', {}, 'BVH unit ', units)];
  }

  async function characterRows() {
    const list = h('ul.open-list.open-characters', {}, h('li.empty', {}, 'loading…'));
    try {
      const characters = await api.listCharacters();
      list.replaceChildren(
        ...characters.map((c) =>
          h(
            'li',
            { dataset: { name: c.name } },
            h('button', { type: 'button', onclick: () => openCreated(api.createSession(c.name), c.name) }, c.name),
            h('span.open-meta', {}, c.description || ''),
          ),
        ),
      );
    } catch (err) {
      list.replaceChildren(h('li.empty', {}, err.message));
    }
    return list;
  }

  async function sessionRows() {
    const list = h('ul.open-list.open-sessions');
    let rows = [];
    try {
      rows = await api.listSessions();
    } catch (err) {
      list.append(h('li.empty', {}, err.message));
      return list;
    }
    const tokens = knownSessions();
    for (const row of rows) {
      const token = tokens[row.id];
      if (!token || row.id === state.sessionId) continue;
      const when = new Date(row.modified * 1000).toLocaleString();
      list.append(
        h(
          'li',
          { dataset: { id: row.id } },
          h('button', { type: 'button', onclick: () => switchSession(row.id, token) }, row.character || '?'),
          h('span.open-meta', {}, when),
        ),
      );
    }
    if (!list.children.length) list.append(h('li.empty', {}, 'no other saved sessions'));
    return list;
  }

  /** Shows the picker: bundled characters, a file of one's own, saved sessions. */
  async function open() {
    const status = h('p.open-status');
    show(
      h('h2', {}, 'Open'),
      h('p.open-note', {}, 'A new session opens in this tab; this one stays saved (Sessions).'),
      h('h3', {}, 'A bundled character'),
      h('div.open-slot.characters'),
      h('h3', {}, 'Your own file'),
      h('p.open-note', {}, 'URDF, pindrag JSON, BVH, glTF/GLB, FBX or DAE; a file with motion brings its clip.'),
      state.character?.unit
        ? h('p.open-note#open-current-unit', {}, `This character's BVH file was read in ${state.character.unit}; to read it in another unit, open it again with the unit chosen here.`)
        : null,
      h('div.open-row', {}, ...fileButton()),
      h('h3', {}, 'A saved session'),
      h('div.open-slot.sessions'),
      status,
      h('div.open-actions', {}, h('button#open-close', { type: 'button', onclick: close }, 'Close')),
    );
    const [characters, sessions] = await Promise.all([characterRows(), sessionRows()]);
    card.querySelector('.open-slot.characters')?.replaceChildren(characters);
    card.querySelector('.open-slot.sessions')?.replaceChildren(sessions);
  }

  // the clip retargeted onto this character (animator/retarget.hpp): it becomes the clip here
  async function retargetHere(file) {
    const status = card.querySelector('.open-status');
    if (status) status.textContent = `retargeting ${file.name}…`;
    card.querySelectorAll('button').forEach((b) => (b.disabled = true));
    try {
      const r = await api.uploadClip(file, { retarget: true });
      notify(`${file.name} retargeted: ${r.frames} frames at ${(1 / r.frame_time).toFixed(1)} fps`);
      close();
    } catch (err) {
      card.querySelectorAll('button').forEach((b) => (b.disabled = false));
      if (status) status.textContent = err.message;
      notify(err.message, 'error');
    }
  }

  /** A clip of another skeleton was refused: offer to open the file as its own character, or to
   *  retarget it onto this one. */
  function offerOwnCharacter(file, message) {
    const character = state.character?.name || 'this character';
    show(
      h('h2', {}, 'Another skeleton'),
      h('p', {}, `${file.name} animates a skeleton that differs from ${character}'s.`),
      h('p.open-note', { title: message }, message),
      h('p.open-status'),
      h(
        'div.open-actions',
        {},
        h('button#open-as-own', { type: 'button', onclick: () => openCreated(api.createSessionFromFile(file), file.name) }, 'Open it as its own character'),
        h('button#retarget-clip', { type: 'button', onclick: () => retargetHere(file) }, `Retarget it onto ${character}`),
        h('button', { type: 'button', onclick: close }, 'Cancel'),
      ),
    );
  }

  const button = h('button#open-character', { type: 'button', title: 'Open a bundled character, a character file or a saved session', onclick: open }, 'Open…');
  return { button, overlay, open, offerOwnCharacter, close };
}
