// The selected material's preview: a sphere wearing it under the scene's
// sky and directional lights, raster and path traced side by side
// (`GET /api/materials/{index}/preview`). Previews start when the user
// asks, by selecting a material or by the "preview" button, not on page
// load: a page that never looks at materials costs the daemon nothing.
// From then on they render again when the selection or the materials
// report changes (a material file saved, an override set). Each image has at most one request in flight and one
// waiting (the newest), so dragging a slider never floods the daemon; a
// failed render keeps the last image and says why in its caption.
//
// Test hooks: #material-preview-start (the button), #material-preview
// figure[data-renderer] with data-state
// (rendering, ready, error), data-index (the material its image shows)
// and data-renders (renders landed so far); its img and figcaption.

import { el } from './util.js';

const RENDERERS = [
  ['raster', 'raster'],
  ['path', 'path traced'],
];

export class MaterialPreview {
  constructor(root) {
    this.images = RENDERERS.map(([renderer, label]) => {
      const img = el('img', { alt: `the material on a sphere, ${label}`, width: 128, height: 128 });
      const caption = el('figcaption', {}, label);
      const figure = el('figure', { 'data-renderer': renderer, 'data-state': 'idle', 'data-renders': '0' }, img, caption);
      return { renderer, label, figure, img, caption, busy: false, waiting: null, url: null, renders: 0 };
    });
    this.index = 0;
    this.on = false;
    this.button = el('button', { type: 'button', class: 'tool', id: 'material-preview-start', onclick: () => this.start(this.index) }, 'preview');
    for (const i of this.images) i.figure.hidden = true;
    root.replaceChildren(this.button, ...this.images.map((i) => i.figure));
  }

  /** Turns previews on and renders material `index`. */
  start(index) {
    this.on = true;
    this.button.hidden = true;
    for (const i of this.images) i.figure.hidden = false;
    this.show(index);
  }

  /** Renders material `index`, raster and path traced, once previews are on. */
  show(index) {
    this.index = index;
    if (!this.on) return;
    for (const image of this.images) this.request(image, index);
  }

  async request(image, index) {
    if (image.busy) {
      image.waiting = index;
      return;
    }
    image.busy = true;
    image.figure.dataset.state = 'rendering';
    image.caption.textContent = `${image.label}: rendering…`;
    try {
      const r = await fetch(`/api/materials/${index}/preview?renderer=${image.renderer}`);
      if (!r.ok) throw new Error(await failure(r));
      const url = URL.createObjectURL(await r.blob());
      image.img.src = url;
      if (image.url) URL.revokeObjectURL(image.url);
      image.url = url;
      const samples = r.headers.get('x-loupe-samples');
      image.caption.textContent = image.renderer === 'path' ? `${image.label} · ${samples} spp` : image.label;
      image.figure.dataset.index = String(index);
      image.figure.dataset.renders = String(++image.renders);
      image.figure.dataset.state = 'ready';
    } catch (err) {
      image.caption.textContent = `${image.label}: ${err.message}`;
      image.figure.dataset.state = 'error';
    } finally {
      image.busy = false;
      if (image.waiting !== null) {
        const next = image.waiting;
        image.waiting = null;
        this.request(image, next);
      }
    }
  }
}

/** What a refused preview says: its first diagnostic at file:line:col,
 * or its error. */
async function failure(r) {
  const body = await r.json().catch(() => ({}));
  const d = body.diagnostics?.[0];
  if (d) return d.location ? `${d.location.file}:${d.location.line}:${d.location.column}: ${d.message}` : d.message;
  return body.error ?? `HTTP ${r.status}`;
}
