// The tensor view: one captured buffer (a histogram, an adaptation state,
// later a network's activations) read as the tensor its layout describes.
// It shows the shape, element type and per-channel statistics, and plots
// the values as bars (one per element) when there are few enough to see;
// hovering a bar reads its index and exact value. An image-shaped tensor
// ([y, x, channel]) is shown as images instead (tensor_image.js), and a
// denoiser tensor with the list of all of the denoiser's (tensor_list.js).
//
// Test hooks: #tensor-panel[data-key], #tensor-shape, #tensor-stats (a
// constant channel's row: tr.constant[data-constant]),
// #tensor-plot (canvas, data-bars = bars drawn), #tensor-readout.

import * as api from './api.js';
import { $, el, encodePath } from './util.js';
import { TensorImage, isImage } from './tensor_image.js';
import { TensorList } from './tensor_list.js';

/** Above this many elements the plot would be a smear: stats only. */
const MAX_BARS = 4096;
const REFRESH_MS = 250;

export class TensorView {
  /** `subscribe(wanted)` asks the server to capture these outputs each frame;
   * `subscribeList` the same for the denoiser's list. */
  constructor(subscribe, subscribeList) {
    this.subscribe = subscribe;
    this.image = new TensorImage();
    this.list = new TensorList(subscribeList, (pass, output) => this.show(pass, output));
    this.root = $('tensor-panel');
    this.title = $('tensor-title');
    this.shape = $('tensor-shape');
    this.stats = $('tensor-stats');
    this.canvas = $('tensor-plot');
    this.readout = $('tensor-readout');
    this.target = null;
    this.data = null;
    this.last = 0;
    this.timer = null;
    this.canvas.addEventListener('mousemove', (e) => this.hover(e));
    this.canvas.addEventListener('mouseleave', () => (this.readout.textContent = ''));
    new ResizeObserver(() => this.draw()).observe(this.canvas);
  }

  get active() {
    return this.target !== null;
  }

  show(pass, output) {
    this.target = { pass, output };
    this.root.hidden = false;
    this.root.dataset.key = `${pass}/${output}`;
    this.title.textContent = `${pass}/${output}`;
    this.data = null;
    this.subscribe([{ pass, output }]);
    this.list.follow(pass, output);
    this.refresh();
  }

  /** The newest pass list (the denoiser's tensors to list). */
  setPasses(passes) {
    this.list.setPasses(passes);
  }

  hide() {
    this.target = null;
    this.root.hidden = true;
    delete this.root.dataset.key;
    this.image.hide();
    this.list.follow(null);
  }

  /** A frame was rendered: fetch the new values, at most every REFRESH_MS
   * (a frame inside that window is fetched when it ends). */
  onFrame() {
    if (this.active) this.schedule();
  }

  schedule() {
    if (this.timer) return;
    const wait = Math.max(0, REFRESH_MS - (performance.now() - this.last));
    this.timer = setTimeout(() => {
      this.timer = null;
      this.refresh();
    }, wait);
  }

  async refresh() {
    const target = this.target;
    if (!target) return;
    this.last = performance.now();
    const base = `/api/tensors/${encodePath(target.pass)}/${encodeURIComponent(target.output)}`;
    try {
      const meta = await api.getJson(base);
      const bytes = await api.getBytes(`${base}.f32`);
      if (this.target !== target) return; // switched meanwhile
      this.meta = meta;
      this.data = new Float32Array(bytes);
      this.render();
      await this.list.refresh();
    } catch (err) {
      if (err instanceof api.ApiError && err.notCaptured) {
        // Not captured yet: the subscription makes the next frame capture
        // it; look again shortly.
        this.shape.textContent = 'waiting for a frame that captures it…';
        if (this.target === target) this.schedule();
      } else {
        this.shape.textContent = err.message;
      }
    }
  }

  render() {
    const { layout, stats, frame } = this.meta;
    const dims = layout.dims.map(([name, n]) => `${name} ${n}`).join(' × ');
    this.shape.textContent = `[${dims}] ${layout.element} · frame ${frame}`;
    // A channel whose min is its max holds one value: said, not left for
    // the reader to spot among the figures.
    const channels = stats.min.map((min, c) => {
      const constant = min === stats.max[c];
      const name = layout.dims.length > 1 ? `c${c}` : 'all';
      return el(
        'tr',
        constant ? { class: 'constant', dataset: { constant: String(min) } } : {},
        el('td', { text: constant ? `${name} constant` : name }),
        ...[min, stats.max[c], stats.mean[c]].map((v) => el('td', { class: 'num', text: fmt(v) })),
      );
    });
    this.stats.replaceChildren(
      el('table', {}, el('tr', {}, el('th', { text: '' }), el('th', { text: 'min' }), el('th', { text: 'max' }), el('th', { text: 'mean' })), ...channels),
      el('div', { class: 'tensor-counts', text: `NaN ${stats.nan} · Inf ${stats.inf} · negative ${stats.negative}` }),
    );
    const image = isImage(layout);
    this.canvas.hidden = image;
    if (image) this.image.show(layout, this.data);
    else this.image.hide();
    this.draw();
  }

  draw() {
    const c = this.canvas;
    const ctx = c.getContext('2d');
    const dpr = window.devicePixelRatio || 1;
    c.width = Math.max(1, Math.round(c.clientWidth * dpr));
    c.height = Math.max(1, Math.round(c.clientHeight * dpr));
    ctx.clearRect(0, 0, c.width, c.height);
    const data = this.data;
    if (!data || data.length === 0 || data.length > MAX_BARS) {
      c.dataset.bars = '0';
      return;
    }
    let max = 0;
    for (const v of data) if (Number.isFinite(v)) max = Math.max(max, Math.abs(v));
    const w = c.width / data.length;
    ctx.fillStyle = getComputedStyle(c).color || '#8cf';
    for (let i = 0; i < data.length; i++) {
      const v = data[i];
      if (!Number.isFinite(v)) {
        ctx.fillStyle = '#f0f';
        ctx.fillRect(i * w, 0, Math.max(1, w), c.height);
        ctx.fillStyle = getComputedStyle(c).color || '#8cf';
        continue;
      }
      const h = max > 0 ? (Math.abs(v) / max) * (c.height - 2) : 0;
      ctx.fillRect(i * w, c.height - h, Math.max(1, w - (w > 3 ? 1 : 0)), h);
    }
    c.dataset.bars = String(data.length);
  }

  hover(e) {
    if (!this.data || this.data.length > MAX_BARS) return;
    const rect = this.canvas.getBoundingClientRect();
    const i = Math.floor(((e.clientX - rect.left) / rect.width) * this.data.length);
    if (i < 0 || i >= this.data.length) return;
    this.readout.textContent = `[${i}] = ${this.data[i]}`;
  }
}

function fmt(v) {
  return Number.isInteger(v) ? String(v) : v.toPrecision(6);
}
