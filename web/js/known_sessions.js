// The sessions this browser created, with their tokens (localStorage), so the session list can
// open or delete them. A token never leaves the browser except as the X-Session-Token of its own
// session; the server's list carries none.

const STORAGE_KEY = 'pindrag.sessions';

function read() {
  try {
    const value = JSON.parse(localStorage.getItem(STORAGE_KEY) || '{}');
    return value && typeof value === 'object' ? value : {};
  } catch {
    return {};
  }
}

/** {id: token} of every session created in this browser and not forgotten. */
export function knownSessions() {
  return read();
}

export function rememberSession(id, token) {
  const all = read();
  all[id] = token;
  localStorage.setItem(STORAGE_KEY, JSON.stringify(all));
}

export function forgetSession(id) {
  const all = read();
  delete all[id];
  localStorage.setItem(STORAGE_KEY, JSON.stringify(all));
}
