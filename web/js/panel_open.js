// "Open…": the character and scene picker. It lists the bundled characters, takes a character
// file of the user's (URDF, pindrag JSON, BVH, glTF/GLB, FBX, DAE; a file with motion brings its
// clip) and the sessions saved from this browser. Opening makes a new session and this tab
// switches to it; the current session stays saved and is listed here and in the Sessions panel.
// It also asks what to do with a clip whose skeleton differs from the character's ("Load clip…"):
// open it as its own character, retarget it onto this one (as guessed, or with a mapping the user
// edits, saves and loads: which of the clip's joints drives which of the character's links), or
// leave it.

import { h, uploadTooLarge, GLTF_RESOURCES, hasExtension } from './panel_util.js';
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
    const input = h('input#open-character-file', {
      type: 'file',
      accept: `${ACCEPTED_CHARACTERS},${GLTF_RESOURCES}`,
      multiple: true,
      hidden: true,
    });
    input.addEventListener('change', () => {
      const files = [...input.files];
      input.value = '';
      if (!files.length) return;
      // one character file; the rest are the files a .gltf references (a "glTF Separate" export)
      const file = files.find((f) => hasExtension(f.name, ACCEPTED_CHARACTERS));
      if (!file) {
        notify(`choose a character file (${ACCEPTED_CHARACTERS}); a .gltf's buffers and images go with it`, 'error');
        return;
      }
      const tooLarge = uploadTooLarge(state, file);
      if (tooLarge) {
        notify(tooLarge, 'error');
        return;
      }
      const resources = files.filter((f) => f !== file);
      openCreated(api.createSessionFromFile(file, units.value, resources), file.name);
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
  async function retargetHere(file, mapping = null, resources = []) {
    const status = card.querySelector('.open-status');
    if (status) status.textContent = `retargeting ${file.name}…`;
    card.querySelectorAll('button, select').forEach((b) => (b.disabled = true));
    try {
      const r = await api.uploadClip(file, { retarget: true, mapping, resources });
      notify(`${file.name} retargeted: ${r.frames} frames at ${(1 / r.frame_time).toFixed(1)} fps`);
      close();
    } catch (err) {
      card.querySelectorAll('button, select').forEach((b) => (b.disabled = false));
      if (status) status.textContent = err.message;
      notify(err.message, 'error');
    }
  }

  /** The mapping editor: one row per moving joint of the clip, with the character's link it
   *  drives (the server's guess first); saved and loaded as the mapping file of
   *  docs/retargeting.md ({"source joint": "target link" or null}). */
  async function editMapping(file, message, resources = []) {
    const setStatus = (text) => {
      const status = card.querySelector('.open-status');
      if (status) status.textContent = text;
    };
    setStatus(`reading ${file.name}…`);
    let guess;
    try {
      guess = await api.clipCorrespondence(file, resources);
    } catch (err) {
      setStatus(err.message);
      notify(err.message, 'error');
      return;
    }
    const selects = new Map(); // source joint -> <select>
    const rows = guess.joints.map(({ source, target }) => {
      const select = h('select.mapping-target', { 'data-source': source, title: `the link ${source} drives` }, h('option', { value: '' }, '(none)'), ...guess.links.map((l) => h('option', { value: l }, l)));
      select.value = target ?? '';
      selects.set(source, select);
      return h('tr', {}, h('td', {}, source), h('td', {}, select));
    });
    const current = () => Object.fromEntries([...selects].map(([source, select]) => [source, select.value || null]));
    const save = () => {
      const url = URL.createObjectURL(new Blob([`${JSON.stringify(current(), null, 2)}\n`], { type: 'application/json' }));
      const a = h('a', { href: url, download: `${file.name.replace(/\.[^.]+$/, '')}-mapping.json` });
      document.body.appendChild(a);
      a.click();
      a.remove();
      setTimeout(() => URL.revokeObjectURL(url), 1000);
    };
    const loadInput = h('input#mapping-file', { type: 'file', accept: '.json', hidden: true });
    loadInput.addEventListener('change', async () => {
      const chosen = loadInput.files[0];
      loadInput.value = '';
      if (!chosen) return;
      try {
        const doc = JSON.parse(await chosen.text());
        if (!doc || typeof doc !== 'object' || Array.isArray(doc)) throw new Error('expected an object of source joint name → target link name or null');
        const unknown = [];
        for (const [source, target] of Object.entries(doc)) {
          const select = selects.get(source);
          if (!select) unknown.push(source);
          else if (target === null || guess.links.includes(target)) select.value = target ?? '';
          else unknown.push(`${source} → ${target}`);
        }
        const text = unknown.length ? `${chosen.name}: not in this clip or character, left as they were: ${unknown.join(', ')}` : `${chosen.name}: loaded`;
        setStatus(text);
        notify(text, unknown.length ? 'error' : 'info');
      } catch (err) {
        const text = `${chosen.name}: ${err.message}`;
        setStatus(text);
        notify(text, 'error');
      }
    });
    const conventions = [guess.source_convention, guess.target_convention].map((c) => c || 'unrecognised').join(' → ');
    show(
      h('h2', {}, 'Retarget with a mapping'),
      h('p', {}, `Which link of ${state.character?.name || 'the character'} each joint of ${file.name} drives (names read as ${conventions}). “(none)”: the joint drives nothing.`),
      h('div.mapping-table', {}, h('table#mapping-table', {}, h('tbody', {}, ...rows))),
      h('p.open-status'),
      loadInput,
      h(
        'div.open-actions',
        {},
        h('button#retarget-mapped', { type: 'button', onclick: () => retargetHere(file, current(), resources) }, 'Retarget with this mapping'),
        h('button#mapping-save', { type: 'button', title: 'Download the mapping as JSON (pindrag retarget --mapping reads it too)', onclick: save }, 'Save mapping…'),
        h('button#mapping-load', { type: 'button', title: 'Set the rows from a mapping file', onclick: () => loadInput.click() }, 'Load mapping…'),
        h('button', { type: 'button', onclick: () => offerOwnCharacter(file, message, resources) }, 'Back'),
      ),
    );
  }

  /** A clip of another skeleton was refused: offer to open the file as its own character, or to
   *  retarget it onto this one. `resources`: the files a .gltf clip references, chosen with it. */
  function offerOwnCharacter(file, message, resources = []) {
    const character = state.character?.name || 'this character';
    show(
      h('h2', {}, 'Another skeleton'),
      h('p', {}, `${file.name} animates a skeleton that differs from ${character}'s.`),
      h('p.open-note', { title: message }, message),
      h('p.open-status'),
      h(
        'div.open-actions',
        {},
        h('button#open-as-own', { type: 'button', onclick: () => openCreated(api.createSessionFromFile(file, 'auto', resources), file.name) }, 'Open it as its own character'),
        h('button#retarget-clip', { type: 'button', onclick: () => retargetHere(file, null, resources) }, `Retarget it onto ${character}`),
        h('button#edit-mapping', { type: 'button', title: 'See and change which joint drives which link before retargeting', onclick: () => editMapping(file, message, resources) }, 'Edit the mapping…'),
        h('button', { type: 'button', onclick: close }, 'Cancel'),
      ),
    );
  }

  const button = h('button#open-character', { type: 'button', title: 'Open a bundled character, a character file or a saved session', onclick: open }, 'Open…');
  return { button, overlay, open, offerOwnCharacter, close };
}
