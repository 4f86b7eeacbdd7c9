// One material preview image (`GET /api/materials/{index}/preview?…`) in a
// figure with its caption: at most one request in flight and the newest
// waiting, so a slider dragged never floods the daemon (whose preview
// queue is bounded); a failed render keeps the last image and says why.
// A preview refused because the queue is full (503) is asked again after
// a pause, a few times, unless a newer request is waiting: the budget
// comparison alone asks for four at once, and the queue holds four.
// Used by preview.js (as the scene renders) and budget_preview.js (full
// against a budget).
//
// Test hooks: the figure's data-state (idle, rendering, ready, error),
// data-index (the material its image shows), data-bytes (the adaptive
// G-buffer's bytes per pixel of what it wore) and data-renders (renders
// landed so far).

import { el } from './util.js';

/** Pauses before asking again for a preview the full queue refused. */
export const BUSY_RETRIES_MS = [250, 500, 1000, 2000, 4000];

/** One preview image: `query` (a URL's query string) of a material, at most
 * one request in flight and the newest waiting. `landed(image)` runs after
 * each image that arrives. */
export class PreviewImage {
  constructor(label, attrs, landed = () => {}) {
    this.label = label;
    this.landed = landed;
    this.img = el('img', { alt: `the material on a sphere, ${label}`, width: 128, height: 128 });
    this.caption = el('figcaption', {}, label);
    this.figure = el('figure', { ...attrs, 'data-state': 'idle', 'data-renders': '0' }, this.img, this.caption);
    this.busy = false;
    this.waiting = null;
    this.url = null;
    this.renders = 0;
    /** The request the shown image answered: `{ index, query }`. */
    this.shown = null;
  }

  async request(index, query) {
    if (this.busy) {
      this.waiting = { index, query };
      return;
    }
    this.busy = true;
    this.figure.dataset.state = 'rendering';
    this.caption.textContent = `${this.label}: rendering…`;
    try {
      const r = await fetchPreview(`/api/materials/${index}/preview?${query}`, () => this.waiting !== null);
      if (!r.ok) throw new Error(await failure(r));
      const blob = await r.blob();
      const url = URL.createObjectURL(blob);
      this.img.src = url;
      if (this.url) URL.revokeObjectURL(this.url);
      this.url = url;
      this.blob = blob;
      const samples = Number(r.headers.get('x-loupe-samples'));
      const bytes = r.headers.get('x-loupe-material-bytes');
      this.caption.textContent = [this.label, samples > 1 ? `${samples} spp` : null, bytes ? `${bytes} B/px` : null].filter(Boolean).join(' · ');
      this.shown = { index, query };
      this.figure.dataset.index = String(index);
      this.figure.dataset.bytes = bytes ?? '';
      this.figure.dataset.renders = String(++this.renders);
      this.figure.dataset.state = 'ready';
      this.landed(this);
    } catch (err) {
      this.caption.textContent = `${this.label}: ${err.message}`;
      this.figure.dataset.state = 'error';
    } finally {
      this.busy = false;
      if (this.waiting !== null) {
        const next = this.waiting;
        this.waiting = null;
        this.request(next.index, next.query);
      }
    }
  }
}

/** `fetch(url)`, asked again after each pause of BUSY_RETRIES_MS while
 * the answer is 503 (the preview queue full) and `superseded()` is false. */
export async function fetchPreview(url, superseded, pause = (ms) => new Promise((done) => setTimeout(done, ms))) {
  let r = await fetch(url);
  for (const ms of BUSY_RETRIES_MS) {
    if (r.status !== 503 || superseded()) break;
    await pause(ms);
    r = await fetch(url);
  }
  return r;
}

/** What a refused preview says: its first diagnostic at file:line:col,
 * or its error. */
async function failure(r) {
  const body = await r.json().catch(() => ({}));
  const d = body.diagnostics?.[0];
  if (d) return d.location ? `${d.location.file}:${d.location.line}:${d.location.column}: ${d.message}` : d.message;
  return body.error ?? `HTTP ${r.status}`;
}
