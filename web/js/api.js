// The HTTP side of docs/protocol.md: configuration, sessions (create, list, delete), clip upload
// and export downloads. Every request that reads or changes a session carries its token
// (X-Session-Token); creating and listing carry the server key when the server asks for one.

async function errorText(res) {
  return (await failure('', res)).message;
}

/** An Error "<what>: <status>: <message>" that keeps the server's machine-readable `code`. */
async function failure(what, res) {
  let text = `${res.status} ${res.statusText}`;
  let code = null;
  try {
    const body = await res.json();
    if (body && body.error) text = `${res.status}: ${body.error}`;
    if (body && body.code) code = body.code;
  } catch {
    /* not JSON */
  }
  const err = new Error(what ? `${what}: ${text}` : text);
  err.code = code;
  err.status = res.status;
  return err;
}

export function createApi() {
  const api = {
    sessionId: null,
    token: null,
    /** The server key (?key= of the printed URL) a server listening beyond loopback asks for. */
    serverKey: null,

    keyHeaders() {
      return api.serverKey ? { 'X-Server-Key': api.serverKey } : {};
    },

    async config() {
      const res = await fetch('/api/config', { cache: 'no-store' });
      if (!res.ok) throw new Error(`GET /api/config: ${await errorText(res)}`);
      return res.json();
    },

    async createSession(character = 'human48') {
      const res = await fetch('/api/sessions', {
        method: 'POST',
        headers: { 'Content-Type': 'application/json', ...api.keyHeaders() },
        body: JSON.stringify({ character }),
      });
      if (!res.ok) throw new Error(`POST /api/sessions: ${await errorText(res)}`);
      return res.json();
    },

    /** A new session on a character file (URDF, JSON, BVH, glTF/GLB, FBX, DAE): {id, token}.
     *  `units`: a BVH file's unit (auto, m, cm, mm, in, cmu); auto guesses it from the figure's size.
     *  `resources`: the files a .gltf references beside it (its .bin buffers, its images). */
    async createSessionFromFile(file, units = 'auto', resources = []) {
      const form = new FormData();
      form.append('character', file, file.name);
      for (const r of resources) form.append('resource', r, r.name);
      if (/\.bvh$/i.test(file.name) && units !== 'auto') form.append('units', units);
      const res = await fetch('/api/sessions', { method: 'POST', headers: api.keyHeaders(), body: form });
      if (!res.ok) throw await failure(`open ${file.name}`, res);
      return res.json();
    },

    /** The characters a session can be created on by name: [{name, description}]. */
    async listCharacters() {
      const res = await fetch('/api/characters', { cache: 'no-store' });
      if (!res.ok) throw new Error(`GET /api/characters: ${await errorText(res)}`);
      return res.json();
    },

    /** The saved sessions: [{id, character, modified (Unix s), bytes, live}], newest first. */
    async listSessions() {
      const res = await fetch('/api/sessions', { headers: api.keyHeaders(), cache: 'no-store' });
      if (!res.ok) throw new Error(`GET /api/sessions: ${await errorText(res)}`);
      return res.json();
    },

    /** Deletes a saved session (its token is the proof of ownership). */
    async deleteSession(id, token) {
      const res = await fetch(`/api/sessions/${encodeURIComponent(id)}`, {
        method: 'DELETE',
        headers: { 'X-Session-Token': token },
      });
      if (!res.ok) throw new Error(`delete session: ${await errorText(res)}`);
      return res.json();
    },

    headers() {
      return { 'X-Session-Token': api.token };
    },

    async snapshot() {
      const res = await fetch(`/api/sessions/${encodeURIComponent(api.sessionId)}`, {
        headers: api.headers(),
        cache: 'no-store',
      });
      if (!res.ok) throw new Error(`GET session: ${await errorText(res)}`);
      return res.json();
    },

    /** The session's skinned mesh as an ArrayBuffer (server/mesh_binary.hpp); the browser caches it. */
    async mesh() {
      const res = await fetch(`/api/sessions/${encodeURIComponent(api.sessionId)}/mesh`, { headers: api.headers() });
      if (!res.ok) throw await failure('mesh', res);
      return res.arrayBuffer();
    },

    /** The correspondence retargeting would guess for a clip file (POST .../clip/correspondence). */
    async clipCorrespondence(file, resources = []) {
      const form = new FormData();
      form.append('clip', file, file.name);
      for (const r of resources) form.append('resource', r, r.name);
      const res = await fetch(`/api/sessions/${encodeURIComponent(api.sessionId)}/clip/correspondence`, {
        method: 'POST',
        headers: api.headers(),
        body: form,
      });
      if (!res.ok) throw await failure('mapping', res);
      return res.json();
    },

    /** The measured markers of the trial the clip was fitted to (GET .../markers). */
    async markers() {
      const res = await fetch(`/api/sessions/${encodeURIComponent(api.sessionId)}/markers`, { headers: api.headers() });
      if (!res.ok) throw await failure('markers', res);
      return res.json();
    },

    /** Loads a clip onto the character; `retarget`: a clip of another skeleton is retargeted onto it,
     *  with `mapping` ({source joint: target link or null}) over the guessed correspondence;
     *  `resources`: the files a .gltf clip references beside it (its .bin buffers, its images). */
    async uploadClip(file, { retarget = false, mapping = null, resources = [] } = {}) {
      const form = new FormData();
      form.append('clip', file, file.name);
      for (const r of resources) form.append('resource', r, r.name);
      if (mapping) form.append('mapping', new Blob([JSON.stringify(mapping)], { type: 'application/json' }), 'mapping.json');
      const query = retarget ? '?retarget=1' : '';
      const res = await fetch(`/api/sessions/${encodeURIComponent(api.sessionId)}/clip${query}`, {
        method: 'POST',
        headers: api.headers(),
        body: form,
      });
      if (!res.ok) throw await failure('clip upload', res);
      return res.json();
    },

    /** Fetches an export and hands it to the browser as a download with the server's file name. */
    async exportDownload(format) {
      const res = await fetch(
        `/api/sessions/${encodeURIComponent(api.sessionId)}/export?format=${encodeURIComponent(format)}`,
        { headers: api.headers(), cache: 'no-store' },
      );
      if (!res.ok) throw new Error(`export ${format}: ${await errorText(res)}`);
      const blob = await res.blob();
      const disposition = res.headers.get('Content-Disposition') || '';
      const match = /filename\*?=(?:UTF-8'')?"?([^";]+)"?/i.exec(disposition);
      const name = match ? decodeURIComponent(match[1]) : `pindrag.${format}`;
      const url = URL.createObjectURL(blob);
      const a = document.createElement('a');
      a.href = url;
      a.download = name;
      document.body.appendChild(a);
      a.click();
      a.remove();
      setTimeout(() => URL.revokeObjectURL(url), 10000);
      return { name, bytes: blob.size };
    },
  };
  return api;
}
