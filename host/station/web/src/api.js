// The station's API as the page uses it: every request carries this tab's
// client id and the station's token (taken from the address the station
// printed, then kept for the tab), and a refusal becomes an ApiError with the
// station's own message.

const TOKEN_KEY = 'lightstage-token';
const CLIENT_KEY = 'lightstage-client';

const params = new URLSearchParams(location.search);
if (params.get('token')) {
  sessionStorage.setItem(TOKEN_KEY, params.get('token'));
  // Out of the address bar (and of screenshots, history and shared links).
  history.replaceState(null, '', location.pathname);
}
const token = sessionStorage.getItem(TOKEN_KEY) ?? '';

function newClientId() {
  // getRandomValues works on plain http too (randomUUID needs a secure context).
  const bytes = crypto.getRandomValues(new Uint8Array(16));
  return Array.from(bytes, (b) => b.toString(16).padStart(2, '0')).join('');
}
let client = sessionStorage.getItem(CLIENT_KEY);
if (!client) {
  client = newClientId();
  sessionStorage.setItem(CLIENT_KEY, client);
}

export class ApiError extends Error {
  constructor(message, status) {
    super(message);
    this.status = status;
  }
}

function headers() {
  const h = { 'X-Lightstage-Client': client };
  if (token) h.Authorization = `Bearer ${token}`;
  return h;
}

async function answer(response) {
  const text = await response.text();
  let body = null;
  try {
    body = text ? JSON.parse(text) : null;
  } catch {
    throw new ApiError(`the station answered ${response.status} with something that is not JSON`, response.status);
  }
  if (!response.ok) throw new ApiError(body?.error ?? `HTTP ${response.status}`, response.status);
  return body;
}

export async function get(path) {
  return answer(await fetch(path, { headers: headers(), cache: 'no-store' }));
}

export async function post(path, body = {}) {
  return answer(await fetch(path, {
    method: 'POST',
    headers: { ...headers(), 'Content-Type': 'application/json' },
    body: JSON.stringify(body),
  }));
}

// A file of the data folder (stacks/, calibrations/, results/, surfaces/, exports/) for a link or an image.
export function fileUrl(path, fresh = false) {
  const query = new URLSearchParams();
  if (token) query.set('token', token);
  if (fresh) query.set('t', String(Date.now()));
  const q = query.toString();
  return `/files/${path.split('/').map(encodeURIComponent).join('/')}${q ? `?${q}` : ''}`;
}

// An image the API makes (the preview, a stack's sphere picture), never from the cache.
export function apiImageUrl(path) {
  const query = new URLSearchParams({ t: String(Date.now()) });
  if (token) query.set('token', token);
  return `${path}?${query}`;
}
