// The renderer switch and what path tracing adds to the page: a raster /
// path traced switch (an override of `quality.renderer`; it shows the
// value however it was set: here, in the Scene panel or in the file), the
// samples accumulated so far, and how far the path-traced HDR image is from
// the raster one: a heat map of |path − raster| with its RMSE and mean
// relative difference.
//
// The raster reference lives in this page, not on the server: the path
// tracer culls the raster passes, so while the renderer is raster the page
// streams the raster HDR image (f32) and keeps the newest, to compare the
// path-traced one with once the renderer is path.
//
// Test hooks: #renderer-raster, #renderer-path (aria-pressed), #path-panel
// (shown while path tracing), #path-samples[data-samples][data-spp]
// [data-converged], #path-difference (the toggle), #path-difference-view,
// #path-difference-stats[data-rmse][data-relative][data-frame]
// [data-reference-frame], #path-difference-map, #path-difference-legend.

import { $, el } from './util.js';

const RENDERER = 'quality.renderer';
const SPP = 'quality.path_spp';
const SAMPLES = { pass: 'path_trace', output: 'samples' };
const TRACED = { pass: 'path_trace', output: 'color' };
/** The passes that make the raster HDR image: a control that affects one
 * changes what the raster reference shows. */
const RASTER = ['shadows', 'depth_prepass', 'gbuffer', 'ltc_tables', 'lighting', 'volume_shadows', 'volume_march', 'volumes'];
/** Added to the raster value under the relative difference, so that black
 * pixels do not divide by zero. */
export const RELATIVE_EPSILON = 0.01;
/** The heat map's top is this quantile of the differences, so that a few
 * fireflies do not leave the rest of the map black. */
const SCALE_QUANTILE = 0.99;
/** At most one difference this often: it goes through two float images. */
const DIFFERENCE_MS = 500;
/** The heat map's colours, from no difference to the scale and beyond. */
const RAMP = [
  [0, 0, 4],
  [87, 16, 110],
  [188, 55, 84],
  [249, 142, 9],
  [252, 255, 164],
];
/** Pixels non-finite in either image, as the inspector's NaN overlay. */
const NON_FINITE = [255, 0, 255];

/**
 * Compares two RGBA f32 images of one size over their RGB channels, among
 * the pixels finite in both: `heat` is |path − raster| per pixel (the mean
 * of the channels; NaN where either is not finite), `rmse` the root mean
 * square of path − raster, `relative` the mean of |path − raster| /
 * (|raster| + RELATIVE_EPSILON), `nonFinite` how many pixels were left out.
 */
export function difference(path, raster) {
  const n = path.length / 4;
  const heat = new Float32Array(n);
  let squares = 0;
  let relative = 0;
  let finite = 0;
  for (let i = 0; i < n; i++) {
    let sum = 0;
    let square = 0;
    let rel = 0;
    for (let c = 4 * i; c < 4 * i + 3; c++) {
      const d = Math.abs(path[c] - raster[c]);
      sum += d;
      square += d * d;
      rel += d / (Math.abs(raster[c]) + RELATIVE_EPSILON);
    }
    if (!Number.isFinite(square) || !Number.isFinite(rel)) {
      heat[i] = NaN;
      continue;
    }
    heat[i] = sum / 3;
    squares += square;
    relative += rel;
    finite++;
  }
  const channels = 3 * finite;
  return { heat, rmse: Math.sqrt(squares / channels), relative: relative / channels, nonFinite: n - finite };
}

/** The heat map's top: the SCALE_QUANTILE of the finite differences. */
export function scaleOf(heat) {
  const sorted = heat.filter((v) => !Number.isNaN(v)).sort();
  return sorted.length ? sorted[Math.min(sorted.length - 1, Math.floor(SCALE_QUANTILE * sorted.length))] : 0;
}

/** RGBA8 pixels of `heat` on the ramp, `scale` and above at its top. */
export function heatMap(heat, scale) {
  const rgba = new Uint8ClampedArray(heat.length * 4);
  const last = RAMP.length - 1;
  for (let i = 0; i < heat.length; i++) {
    const v = heat[i];
    let color = NON_FINITE;
    if (!Number.isNaN(v)) {
      const x = scale > 0 ? Math.min(v / scale, 1) * last : 0;
      const k = Math.min(Math.floor(x), last - 1);
      const f = x - k;
      color = RAMP[k].map((a, c) => a + f * (RAMP[k + 1][c] - a));
    }
    rgba.set(color, 4 * i);
    rgba[4 * i + 3] = 255;
  }
  return rgba;
}

/** A figure as the page shows it: three significant digits. */
export const fmt = (v) => Number(v).toPrecision(3);

/** A streamed capture's floats (copied: a Float32Array needs a 4-byte aligned start). */
const floats = (bytes) => new Float32Array(bytes.slice().buffer);

export class PathView {
  /**
   * @param {object} hooks
   * @param {(message: object) => void} hooks.send sends a WebSocket message
   * @param {(wanted: {pass: string, output: string, encoding: string}[]) => void}
   *   hooks.want sets the outputs streamed for this view
   * @param {() => void} hooks.refreshCaptures refetches the capture list
   *   (throttled): the sample count is in its statistics
   */
  constructor(hooks) {
    this.hooks = hooks;
    this.buttons = { raster: $('renderer-raster'), path: $('renderer-path') };
    this.samplesEl = $('path-samples');
    this.toggle = $('path-difference');
    this.panel = $('path-panel');
    this.view = $('path-difference-view');
    this.map = $('path-difference-map');
    this.legend = $('path-difference-legend');
    this.stats = $('path-difference-stats');

    this.renderer = null; // 'raster' | 'path', as the server renders now
    this.spp = null;
    this.controlsKey = null;
    this.values = new Map(); // path → JSON value, of the controls that change the raster image
    this.rasterKey = null; // {pass, output} of the raster HDR image
    this.reference = null; // newest raster HDR capture: {bytes, width, height, frame, values}
    this.traced = null; // newest path-traced HDR capture, while the difference is on
    this.shown = null; // [traced, reference] the difference on screen was made from
    this.frame = 0; // newest frame event
    this.since = 0; // sample counts from frames after this one are of the current accumulation
    this.samples = null;
    this.timer = null;
    this.lastDifference = -Infinity;

    for (const [value, button] of Object.entries(this.buttons)) {
      button.addEventListener('click', () => this.hooks.send({ type: 'set_override', path: RENDERER, value }));
    }
    this.toggle.addEventListener('change', () => {
      this.subscribe();
      this.show();
    });
    this.show();
  }

  /** A `ControlsReport`: the renderer, the samples per pixel, and the
   * values the raster reference was made with. */
  setControls(report) {
    if (!report || !Array.isArray(report.controls)) return;
    const key = JSON.stringify([report.controls.map((c) => [c.path, c.value]), report.overrides]);
    // Any change restarts the accumulation: counts captured before it (a
    // previous path-traced run's, kept by the server) are not this one's.
    if (this.controlsKey !== null && key !== this.controlsKey) this.since = this.frame;
    this.controlsKey = key;
    const value = (path) => report.controls.find((c) => c.path === path)?.value ?? null;
    this.renderer = value(RENDERER);
    this.spp = value(SPP);
    // A path-traced image from an earlier run is not compared with a newer raster one.
    if (this.renderer !== 'path') this.traced = null;
    const raster = report.controls.filter((c) => c.path !== RENDERER && c.affects?.some((p) => RASTER.includes(p)));
    this.values = new Map(raster.map((c) => [c.path, JSON.stringify(c.value)]));
    this.subscribe();
    this.show();
  }

  /** The pass list: which output is the raster HDR image. */
  setPasses(passes) {
    const live = (name) => passes.some((p) => p.name === name && (p.status === 'ok' || p.status === 'stale'));
    // With media the volume pass composites over the lit frame. While path
    // tracing both are culled, and the reference keeps its key.
    const pass = live('volumes') ? 'volumes' : live('lighting') ? 'lighting' : null;
    if (!pass || pass === this.rasterKey?.pass) return;
    this.rasterKey = { pass, output: 'color' };
    this.subscribe();
  }

  subscribe() {
    const wanted = [];
    if (this.renderer === 'raster' && this.rasterKey) wanted.push({ ...this.rasterKey, encoding: 'f32' });
    if (this.renderer === 'path') {
      // Captured for its statistics; as PNG it is the smallest stream.
      wanted.push({ ...SAMPLES, encoding: 'png' });
      if (this.toggle.checked) wanted.push({ ...TRACED, encoding: 'f32' });
    }
    this.hooks.want(wanted);
  }

  /** A `frame` event. */
  onFrame(frame) {
    this.frame = frame;
    if (this.renderer === 'path') this.hooks.refreshCaptures();
  }

  /** The capture list: the samples so far are its `path_trace/samples` minimum. */
  setCaptures(list) {
    const c = list.find((x) => x.pass === SAMPLES.pass && x.output === SAMPLES.output);
    this.samples = c && c.frame > this.since ? c.stats.min[0] : null;
    this.show();
  }

  /** A binary `capture` message. */
  onCapture(header, bytes) {
    if (header.encoding !== 'f32' || bytes.byteLength !== header.width * header.height * 16) return;
    const image = { bytes, width: header.width, height: header.height, frame: header.frame };
    if (header.pass === this.rasterKey?.pass && header.output === this.rasterKey.output) {
      this.reference = { ...image, values: this.values };
    } else if (this.renderer === 'path' && header.pass === TRACED.pass && header.output === TRACED.output) {
      this.traced = image;
      this.scheduleDifference();
    }
  }

  show() {
    for (const [value, button] of Object.entries(this.buttons)) {
      button.setAttribute('aria-pressed', String(this.renderer === value));
      button.disabled = this.renderer === null;
    }
    const tracing = this.renderer === 'path';
    this.panel.hidden = !tracing;
    this.view.hidden = !(tracing && this.toggle.checked);
    if (tracing) {
      const converged = this.samples !== null && this.samples >= this.spp;
      this.samplesEl.textContent = `${this.samples ?? '—'} / ${this.spp ?? '—'} samples${converged ? ' · converged' : ''}`;
      Object.assign(this.samplesEl.dataset, { samples: this.samples ?? '', spp: this.spp ?? '', converged: String(converged) });
    }
    if (!this.view.hidden) this.scheduleDifference();
  }

  scheduleDifference() {
    if (this.timer !== null) return;
    const wait = Math.max(0, this.lastDifference + DIFFERENCE_MS - performance.now());
    this.timer = setTimeout(() => {
      this.timer = null;
      this.lastDifference = performance.now();
      this.showDifference();
    }, wait);
  }

  /** Why the raster reference cannot be compared with, or null. */
  referenceProblem() {
    const r = this.reference;
    if (!r) return 'no raster image yet: switch to raster once to capture a reference';
    if ([...this.values].some(([path, v]) => r.values.has(path) && r.values.get(path) !== v)) {
      return 'the scene changed since the raster reference: switch to raster once to capture a new one';
    }
    const t = this.traced;
    if (t && (t.width !== r.width || t.height !== r.height)) {
      return `the raster reference is ${r.width}×${r.height}, the path-traced image ${t.width}×${t.height}: switch to raster once to capture a new one`;
    }
    return null;
  }

  showDifference() {
    if (this.view.hidden) return;
    const problem = this.referenceProblem() ?? (this.traced ? null : 'waiting for a path-traced frame…');
    this.map.hidden = problem !== null;
    this.legend.hidden = problem !== null;
    if (problem) {
      this.shown = null;
      this.stats.textContent = problem;
      for (const key of ['rmse', 'relative', 'frame', 'referenceFrame']) delete this.stats.dataset[key];
      return;
    }
    const [t, r] = [this.traced, this.reference];
    if (this.shown?.[0] === t && this.shown[1] === r) return;
    this.shown = [t, r];
    const d = difference(floats(t.bytes), floats(r.bytes));
    const scale = scaleOf(d.heat);
    this.map.width = t.width;
    this.map.height = t.height;
    this.map.getContext('2d').putImageData(new ImageData(heatMap(d.heat, scale), t.width, t.height), 0, 0);
    const stops = RAMP.map((c, i) => `rgb(${c.join(',')}) ${(100 * i) / (RAMP.length - 1)}%`).join(', ');
    this.legend.replaceChildren(
      el('span', { class: 'muted', text: '|path − raster|, mean of RGB:' }),
      el('span', { class: 'num', text: '0' }),
      el('i', { class: 'ramp', style: `background: linear-gradient(90deg, ${stops})` }),
      el('span', { class: 'num', text: fmt(scale) }),
      el('i', { class: 'swatch', style: `background: rgb(${NON_FINITE.join(',')})` }),
      el('span', { class: 'muted', text: 'not finite' }),
    );
    this.legend.title = `the top of the scale is the ${100 * SCALE_QUANTILE}th percentile; larger differences share its colour`;
    const left = d.nonFinite ? ` · ${d.nonFinite} non-finite pixel${d.nonFinite === 1 ? '' : 's'} left out` : '';
    this.stats.textContent = `RMSE ${fmt(d.rmse)} · mean relative ${fmt(100 * d.relative)} %${left} · path frame ${t.frame} vs raster frame ${r.frame}`;
    this.stats.title = `relative: |path − raster| / (|raster| + ${RELATIVE_EPSILON}), over RGB`;
    Object.assign(this.stats.dataset, { rmse: d.rmse, relative: d.relative, frame: t.frame, referenceFrame: r.frame });
  }

  /** For `window.loupe.state`. */
  snapshot() {
    const image = (i) => i && { frame: i.frame, width: i.width, height: i.height };
    return { renderer: this.renderer, spp: this.spp, samples: this.samples, since: this.since, rasterKey: this.rasterKey, reference: image(this.reference), traced: image(this.traced) };
  }
}
