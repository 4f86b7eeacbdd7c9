// Views of an image-shaped tensor, [y, x, channel] (the denoiser's
// activations): three channels as RGB, every channel as a grid of small
// images, one channel through a colour map, or a histogram per channel.
// Activations have no natural range, so each shown channel is mapped from
// its own range (min/max, or the 1st–99th percentiles, which ignore the
// few extreme values that would flatten the rest) to 0…255. A channel
// whose every value is the same (a dead ReLU channel, all zero) has no
// range: the grid and the histograms label it "constant = v" rather than
// show a flat grey that reads like data.
//
// Test hooks: #tensor-image[data-view], #tensor-view, #tensor-fit,
// #tensor-r/#tensor-g/#tensor-b, #tensor-cmap-channel,
// #tensor-rgb (canvas, data-ranges = JSON [[lo, hi] per R, G, B]),
// #tensor-cmap (canvas, data-range), #tensor-grid canvas[data-channel],
// #tensor-histograms canvas[data-channel][data-bins], and in both
// figure[data-constant] (the value) with its figcaption for a constant channel,
// #tensor-pixel[data-x][data-y][data-values = JSON, one per channel].

import { viridis } from './presets.js';
import { $, el } from './util.js';

const BINS = 64;
/** Percentiles are taken over at most this many values per channel (an
 * even stride through the image): sorting every value of every channel of
 * a full-size activation would stall the page. */
const PERCENTILE_SAMPLES = 1 << 16;

/**
 * The value every pixel of channel `ch` holds in `data` ([y, x, channel]
 * with `channels` channels), or null when two differ or one is not finite.
 */
export function constantValue(data, channels, ch) {
  const first = data[ch];
  if (!Number.isFinite(first)) return null;
  for (let i = ch + channels; i < data.length; i += channels) if (data[i] !== first) return null;
  return first;
}

/** A channel's caption: its name, and its value when it is constant (or null). */
export function channelCaption(ch, constant) {
  return constant === null ? `c${ch}` : `c${ch} constant = ${fmt(constant)}`;
}

/** Whether a layout is an image: [y, x, channel]. */
export function isImage(layout) {
  const names = layout.dims.map(([name]) => name);
  return names.length === 3 && names[0] === 'y' && names[1] === 'x' && names[2] === 'channel';
}

export class TensorImage {
  constructor() {
    this.root = $('tensor-image');
    this.view = $('tensor-view');
    this.fitMode = $('tensor-fit');
    this.pickers = ['tensor-r', 'tensor-g', 'tensor-b'].map($);
    this.cmapChannel = $('tensor-cmap-channel');
    this.rgb = $('tensor-rgb');
    this.cmap = $('tensor-cmap');
    this.grid = $('tensor-grid');
    this.histograms = $('tensor-histograms');
    this.pixel = $('tensor-pixel');
    this.data = null;
    for (const control of [this.view, this.fitMode, this.cmapChannel, ...this.pickers]) control.addEventListener('change', () => this.draw());
    for (const canvas of [this.rgb, this.cmap]) canvas.addEventListener('mousemove', (e) => this.hover(e, canvas));
    this.grid.addEventListener('mousemove', (e) => e.target instanceof HTMLCanvasElement && this.hover(e, e.target));
  }

  /** Shows `data` (f32, layout order) of an image-shaped `layout`. */
  show(layout, data) {
    const [[, h], [, w], [, c]] = layout.dims;
    const changed = !this.data || this.w !== w || this.h !== h || this.c !== c;
    Object.assign(this, { w, h, c, data });
    if (changed) this.setChannels();
    this.root.hidden = false;
    this.draw();
    if (this.pixel.dataset.x !== undefined) this.readout(Number(this.pixel.dataset.x), Number(this.pixel.dataset.y));
  }

  hide() {
    this.root.hidden = true;
    this.data = null;
  }

  /** New channel count: pickers offer every channel, starting at 0, 1, 2. */
  setChannels() {
    const options = () => Array.from({ length: this.c }, (_, i) => el('option', { value: i, text: `c${i}` }));
    this.pickers.forEach((p, i) => {
      p.replaceChildren(...options());
      p.value = String(Math.min(i, this.c - 1));
    });
    this.cmapChannel.replaceChildren(...options());
    this.cmapChannel.value = '0';
    delete this.pixel.dataset.x;
    this.pixel.textContent = '';
  }

  /** The range channel `ch` is mapped from, as the fit mode says. */
  range(ch) {
    const { w, h, c, data } = this;
    const n = w * h;
    const percentile = this.fitMode.value === 'percentile';
    const stride = percentile ? Math.max(1, Math.floor(n / PERCENTILE_SAMPLES)) : 1;
    const values = [];
    let lo = Infinity;
    let hi = -Infinity;
    for (let i = 0; i < n; i += stride) {
      const v = data[i * c + ch];
      if (!Number.isFinite(v)) continue;
      if (percentile) values.push(v);
      lo = Math.min(lo, v);
      hi = Math.max(hi, v);
    }
    if (percentile && values.length) {
      values.sort((a, b) => a - b);
      const at = (p) => values[Math.round(p * (values.length - 1))];
      [lo, hi] = [at(0.01), at(0.99)];
    }
    return Number.isFinite(lo) ? [lo, hi] : [0, 0];
  }

  draw() {
    if (!this.data) return;
    const view = this.view.value;
    this.root.dataset.view = view;
    for (const [name, node] of [['rgb', this.rgb], ['colormap', this.cmap], ['grid', this.grid], ['histograms', this.histograms]]) node.hidden = view !== name;
    for (const p of this.pickers) p.parentElement.hidden = view !== 'rgb';
    this.cmapChannel.parentElement.hidden = view !== 'colormap';
    if (view === 'rgb') this.drawRgb();
    else if (view === 'colormap') this.drawColormap();
    else if (view === 'grid') this.drawGrid();
    else this.drawHistograms();
  }

  drawRgb() {
    const channels = this.pickers.map((p) => Number(p.value));
    const ranges = channels.map((ch) => this.range(ch));
    this.rgb.dataset.ranges = JSON.stringify(ranges);
    this.paint(this.rgb, (i, out) => {
      for (let k = 0; k < 3; k++) out[k] = toByte(this.data[i * this.c + channels[k]], ranges[k]);
    });
  }

  drawColormap() {
    const ch = Number(this.cmapChannel.value);
    const range = this.range(ch);
    this.cmap.dataset.range = JSON.stringify(range);
    this.paint(this.cmap, (i, out) => viridis(toByte(this.data[i * this.c + ch], range) / 255, out));
  }

  drawGrid() {
    const cells = Array.from({ length: this.c }, (_, ch) => {
      const canvas = el('canvas', { dataset: { channel: ch }, title: `c${ch}` });
      const range = this.range(ch);
      canvas.dataset.range = JSON.stringify(range);
      this.paint(canvas, (i, out) => out.fill(toByte(this.data[i * this.c + ch], range), 0, 3));
      return this.figure(ch, canvas, null);
    });
    this.grid.replaceChildren(...cells);
  }

  drawHistograms() {
    const cells = Array.from({ length: this.c }, (_, ch) => {
      const [lo, hi] = this.range(ch);
      const counts = new Array(BINS).fill(0);
      for (let i = 0; i < this.w * this.h; i++) {
        const v = this.data[i * this.c + ch];
        if (!Number.isFinite(v) || v < lo || v > hi) continue;
        counts[hi > lo ? Math.min(BINS - 1, Math.floor(((v - lo) / (hi - lo)) * BINS)) : 0]++;
      }
      const canvas = el('canvas', { width: BINS * 2, height: 40, dataset: { channel: ch, bins: JSON.stringify(counts) } });
      const g = canvas.getContext('2d');
      const top = Math.max(1, ...counts);
      g.fillStyle = '#7fb8ff';
      counts.forEach((n, b) => g.fillRect(b * 2, 40 - (n / top) * 40, 2, (n / top) * 40));
      return this.figure(ch, canvas, `${fmt(lo)} … ${fmt(hi)}`);
    });
    this.histograms.replaceChildren(...cells);
  }

  /** A grid or histogram cell: `canvas` captioned with channel `ch`, and `range` unless it is constant. */
  figure(ch, canvas, range) {
    const constant = constantValue(this.data, this.c, ch);
    const caption = constant === null && range ? `${channelCaption(ch, null)} ${range}` : channelCaption(ch, constant);
    const dataset = constant === null ? {} : { constant: String(constant) };
    return el('figure', { dataset, class: constant === null ? '' : 'constant' }, canvas, el('figcaption', { text: caption }));
  }

  /** Fills `canvas` (one canvas pixel per tensor pixel) with `pixel(i, rgba)`. */
  paint(canvas, pixel) {
    canvas.width = this.w;
    canvas.height = this.h;
    const g = canvas.getContext('2d');
    const image = g.createImageData(this.w, this.h);
    const out = new Uint8ClampedArray(4);
    for (let i = 0; i < this.w * this.h; i++) {
      out[3] = 255;
      pixel(i, out);
      image.data.set(out, i * 4);
    }
    g.putImageData(image, 0, 0);
  }

  hover(e, canvas) {
    const r = canvas.getBoundingClientRect();
    const x = Math.floor(((e.clientX - r.left) / r.width) * this.w);
    const y = Math.floor(((e.clientY - r.top) / r.height) * this.h);
    if (x >= 0 && y >= 0 && x < this.w && y < this.h) this.readout(x, y);
  }

  /** Every channel's value at tensor pixel (x, y). */
  readout(x, y) {
    if (!this.data) return;
    const values = Array.from(this.data.subarray((y * this.w + x) * this.c, (y * this.w + x + 1) * this.c));
    Object.assign(this.pixel.dataset, { x, y, values: JSON.stringify(values.map(String)) });
    this.pixel.textContent = `(${x}, ${y}) ` + values.map((v, ch) => `c${ch} ${fmt(v)}`).join(' · ');
  }
}

/** `v` mapped from `[lo, hi]` to 0…255, clamped (percentiles leave values
 * outside); a flat channel is mid-grey; NaN/Inf at full intensity, to stand out. */
function toByte(v, [lo, hi]) {
  if (!Number.isFinite(v)) return 255;
  if (!(hi > lo)) return 128;
  return Math.min(255, Math.max(0, Math.round(((v - lo) / (hi - lo)) * 255)));
}

function fmt(v) {
  return Number.isInteger(v) ? String(v) : v.toPrecision(4);
}
