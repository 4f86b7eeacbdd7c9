// HTTP side of the protocol (PROTOCOL.md). Every function throws an
// `ApiError` with a readable message; callers decide how to show it. A
// documented state (204 + X-Loupe-State, PROTOCOL.md "States": an output
// not captured yet, no tradeoff results yet) is thrown as an ApiError with
// `state` set, so a caller that wants data never reads an empty body.

import { encodePath } from './util.js';

export class ApiError extends Error {
  constructor(message, { status = 0, url = '', state = null } = {}) {
    super(message);
    this.name = 'ApiError';
    /** HTTP status, or 0 when the server could not be reached. */
    this.status = status;
    this.url = url;
    /** The server's X-Loupe-State for a 204, else null. */
    this.state = state;
  }
  /** The output exists but no frame has captured it yet. */
  get notCaptured() {
    return this.state === 'not-captured';
  }
  get notFound() {
    return this.status === 404;
  }
  get unreachable() {
    return this.status === 0;
  }
}

async function request(url, accept, init = {}) {
  let response;
  try {
    response = await fetch(url, { cache: 'no-store', ...init, headers: { Accept: accept, ...init.headers } });
  } catch (err) {
    // fetch rejects only when the server is unreachable (restarting).
    throw new ApiError(`${url}: server unreachable`, { url });
  }
  if (!response.ok) {
    // The server's error bodies are short text or {"error": ...}; show them.
    let detail = '';
    try {
      detail = (await response.text()).trim();
      const parsed = JSON.parse(detail);
      if (parsed && typeof parsed.error === 'string') detail = parsed.error;
      else if (parsed && parsed.error && typeof parsed.error.message === 'string') detail = parsed.error.message;
    } catch {
      // Not JSON: keep the text as it is.
    }
    if (detail.length > 200) detail = detail.slice(0, 200) + '…';
    const msg = `${url}: ${response.status} ${response.statusText}${detail ? ` — ${detail}` : ''}`;
    throw new ApiError(msg, { status: response.status, url });
  }
  if (response.status === 204) {
    const state = response.headers.get('X-Loupe-State') ?? 'no-content';
    throw new ApiError(`${url}: ${state}`, { status: 204, url, state });
  }
  return response;
}

export async function getJson(url) {
  const response = await request(url, 'application/json');
  try {
    return await response.json();
  } catch (err) {
    throw new ApiError(`${url}: invalid JSON (${err.message})`, { status: response.status, url });
  }
}

export async function getText(url) {
  const response = await request(url, 'text/plain');
  return response.text();
}

/** The body as an ArrayBuffer (raw `.f32` data). */
export async function getBytes(url) {
  const response = await request(url, 'application/octet-stream');
  return response.arrayBuffer();
}

export const status = () => getJson('/api/status');
export const passes = () => getJson('/api/passes').then(unwrap('passes'));
export const pipelines = () => getJson('/api/pipelines').then(unwrap('pipelines'));
export const diagnostics = () => getJson('/api/diagnostics').then(unwrap('diagnostics'));
export const captures = () => getJson('/api/captures').then(unwrap('captures'));
export const source = (path) => getText(`/api/sources/${encodePath(path)}`);
export const files = () => getJson('/api/files').then(unwrap('files'));

/** Writes image case `name`'s shown outputs as its references. */
export async function blessReference(name) {
  return (await request(`/api/references/${encodeURIComponent(name)}/bless`, 'application/json', { method: 'POST' })).json();
}

/** Writes `file`'s last good text back (`POST /api/files/revert`). */
export async function revertFile(file) {
  const init = { method: 'POST', headers: { 'Content-Type': 'application/json' }, body: JSON.stringify({ file }) };
  return (await request('/api/files/revert', 'application/json', init)).json();
}

/**
 * The newest tradeoff results: `{state, results}`, `state` being whose
 * they are (`current`, `stale` or `other-scene`, from X-Loupe-State).
 * None written yet throws an ApiError with `state` `not-written`.
 */
export async function tradeoffs() {
  const url = '/api/tradeoffs';
  const response = await request(url, 'application/json');
  const state = response.headers.get('X-Loupe-State') ?? 'current';
  try {
    return { state, results: await response.json() };
  } catch (err) {
    throw new ApiError(`${url}: invalid JSON (${err.message})`, { status: response.status, url });
  }
}

/** Lists may come bare or wrapped in an object (`{diagnostics: [...]}`). */
function unwrap(key) {
  return (value) => {
    if (Array.isArray(value)) return value;
    if (value && Array.isArray(value[key])) return value[key];
    throw new ApiError(`/api/${key}: expected a list`);
  };
}

export function captureUrl(pass, output, ext, lastGood = false) {
  const base = `/api/captures/${encodePath(pass)}/${encodeURIComponent(output)}.${ext}`;
  return lastGood ? `${base}?version=last_good` : base;
}

const LITTLE_ENDIAN = new Uint8Array(new Uint32Array([1]).buffer)[0] === 1;

/**
 * Fetches a capture as raw RGBA float32 (`.f32`: little-endian, top row
 * first). Size comes from the X-Loupe-Width/Height headers, or from
 * `fallback` ({width, height}) when the server omits them.
 */
export async function captureF32(pass, output, { lastGood = false, fallback = null } = {}) {
  const url = captureUrl(pass, output, 'f32', lastGood);
  const response = await request(url, 'application/octet-stream');
  const buffer = await response.arrayBuffer();
  const width = Number(response.headers.get('X-Loupe-Width') ?? fallback?.width);
  const height = Number(response.headers.get('X-Loupe-Height') ?? fallback?.height);
  const frameHeader = response.headers.get('X-Loupe-Frame');
  const expected = width * height * 16;
  if (!(width > 0 && height > 0)) {
    throw new ApiError(`${url}: no X-Loupe-Width/Height headers and no size known`, { status: 200, url });
  }
  if (buffer.byteLength !== expected) {
    throw new ApiError(
      `${url}: ${buffer.byteLength} bytes, expected ${expected} for ${width}×${height} RGBA f32`,
      { status: 200, url },
    );
  }
  let data;
  if (LITTLE_ENDIAN) {
    data = new Float32Array(buffer);
  } else {
    // Big-endian hosts are rare, but the format is defined as LE.
    const view = new DataView(buffer);
    data = new Float32Array(buffer.byteLength / 4);
    for (let i = 0; i < data.length; i++) data[i] = view.getFloat32(i * 4, true);
  }
  return {
    data,
    width,
    height,
    frame: frameHeader === null ? null : Number(frameHeader),
    format: response.headers.get('X-Loupe-Format'),
  };
}

/**
 * A pass's quad map (`overdraw` or `helpers`): one little-endian f32 a
 * pixel, its render targets one under another.
 */
export async function quadMap(pass, kind) {
  const url = `/api/quads/${encodePath(pass)}/${kind}.f32`;
  const response = await request(url, 'application/octet-stream');
  const buffer = await response.arrayBuffer();
  const width = Number(response.headers.get('X-Loupe-Width'));
  const height = Number(response.headers.get('X-Loupe-Height'));
  if (!(width > 0 && height > 0) || buffer.byteLength !== width * height * 4) {
    throw new ApiError(`${url}: ${buffer.byteLength} bytes for ${width}×${height} f32`, { status: 200, url });
  }
  const view = new DataView(buffer);
  const values = new Float32Array(width * height);
  for (let i = 0; i < values.length; i++) values[i] = view.getFloat32(i * 4, true);
  return { width, height, values };
}
