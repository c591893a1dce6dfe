// The hub's HTTP API (DESIGN §3 and the agreed contract): JSON in and out, the session
// cookie plus X-CSRF-Token on every changing request.
export const session = { name: null, role: 'anonymous', csrf: null };

export class ApiError extends Error {
  constructor(status, body) {
    super((body && body.error) || `HTTP ${status}`);
    this.status = status;
    this.where = (body && body.where) || null;
  }
}

export async function api(method, path, body) {
  const headers = { Accept: 'application/json' };
  if (method !== 'GET' && session.csrf) headers['X-CSRF-Token'] = session.csrf;
  let payload;
  if (body instanceof FormData) payload = body;
  else if (body !== undefined) { headers['Content-Type'] = 'application/json'; payload = JSON.stringify(body); }
  const res = await fetch(path, { method, headers, body: payload, credentials: 'same-origin' });
  const text = await res.text();
  let data = null;
  try { data = text ? JSON.parse(text) : null; } catch { data = { error: text.slice(0, 300) }; }
  if (!res.ok) throw new ApiError(res.status, data);
  return data;
}

// Reads the current session; anonymous when the hub says 401 (or has no accounts yet).
export async function loadSession() {
  try {
    Object.assign(session, await api('GET', '/api/session'));
  } catch {
    Object.assign(session, { name: null, role: 'anonymous', csrf: null });
  }
  return session;
}

export function loggedIn() { return session.role !== 'anonymous'; }
export function isCurator() { return session.role === 'curator' || session.role === 'admin'; }

// Uploads with XMLHttpRequest so the browser reports upload progress (fetch does not).
export function postWithProgress(path, form, onProgress) {
  return new Promise((resolve, reject) => {
    const xhr = new XMLHttpRequest();
    xhr.open('POST', path);
    if (session.csrf) xhr.setRequestHeader('X-CSRF-Token', session.csrf);
    xhr.upload.onprogress = (e) => { if (e.lengthComputable) onProgress(e.loaded, e.total); };
    xhr.onload = () => {
      let data = null;
      try { data = JSON.parse(xhr.responseText); } catch { data = { error: xhr.responseText.slice(0, 300) }; }
      if (xhr.status >= 200 && xhr.status < 300) resolve(data);
      else reject(new ApiError(xhr.status, data));
    };
    xhr.onerror = () => reject(new ApiError(0, { error: 'the connection to the hub failed during the upload' }));
    xhr.send(form);
  });
}
