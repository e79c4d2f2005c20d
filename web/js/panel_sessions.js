// Saved sessions (GET /api/sessions), newest first: open one (this tab switches to it) or delete
// it with its files. Only sessions created in this browser can be opened or deleted, since only
// their tokens are here (known_sessions.js); the others are listed without actions. The list
// loads when the panel opens and after each change.

import { h, panel } from './panel_util.js';
import { knownSessions, forgetSession } from './known_sessions.js';

function size(bytes) {
  return bytes >= 1 << 20 ? `${(bytes / (1 << 20)).toFixed(1)} MB` : `${Math.ceil(bytes / 1024)} KB`;
}

export function createSessionsPanel(state, api, openSession) {
  const { root, body } = panel('sessions', 'Sessions', false);
  const list = h('ul.session-list');
  const note = h('span.session-note');
  const refreshButton = h('button', { type: 'button', onclick: () => refresh() }, 'Refresh');
  body.append(list, h('div.session-footer', {}, note, refreshButton));

  const notify = (text, kind = 'info') => state.signals.notify.dispatch({ text, kind });

  function deleteButton(row, token) {
    // two clicks: the first arms it for three seconds
    const button = h('button.danger', { type: 'button', title: 'delete this session and its files' }, 'Delete');
    let armed = false;
    button.addEventListener('click', async () => {
      if (!armed) {
        armed = true;
        button.textContent = 'Sure?';
        setTimeout(() => {
          armed = false;
          button.textContent = 'Delete';
        }, 3000);
        return;
      }
      try {
        await api.deleteSession(row.id, token);
        forgetSession(row.id);
        notify(`session of ${row.character || '?'} deleted`);
      } catch (err) {
        notify(err.message, 'error');
      }
      refresh();
    });
    return button;
  }

  function item(row, token) {
    const when = new Date(row.modified * 1000).toLocaleString();
    const li = h(
      'li',
      { dataset: { id: row.id } },
      h('span.session-name', { title: row.id }, row.character || '?'),
      h('span.session-meta', {}, `${when} · ${size(row.bytes)}`),
    );
    if (row.id === state.sessionId) {
      li.classList.add('current');
      li.append(h('span.session-tag', {}, 'this tab'));
    } else if (!token) {
      li.append(h('span.session-tag', { title: 'created in another browser: its token is not here' }, 'no token'));
    } else {
      li.append(h('button', { type: 'button', onclick: () => openSession(row.id, token) }, 'Open'), deleteButton(row, token));
    }
    return li;
  }

  async function refresh() {
    note.textContent = 'loading…';
    let rows;
    try {
      rows = await api.listSessions();
    } catch (err) {
      note.textContent = err.message;
      return;
    }
    const tokens = knownSessions();
    const stored = new Set(rows.map((r) => r.id));
    for (const id of Object.keys(tokens)) if (!stored.has(id)) forgetSession(id);
    list.replaceChildren(...rows.map((r) => item(r, tokens[r.id])));
    if (!rows.length) list.append(h('li.empty', {}, 'no saved sessions'));
    note.textContent = `${rows.length} saved`;
  }

  root.addEventListener('toggle', () => {
    if (root.open) refresh();
  });
  return root;
}
