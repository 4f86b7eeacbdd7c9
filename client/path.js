// The renderer switch and what path tracing adds to the page: a raster /
// path traced switch (an override of `quality.renderer`; it shows the
// value however it was set: here, in the Scene panel or in the file), the
// samples accumulated so far with the samples per second and the time to
// `quality.path_spp`, and how far the path-traced HDR image is from the
// raster one: its statistics (difference.js) and an action that opens
// |path − raster| in the inspector, where the raster reference is a B.
//
// The raster reference lives in this page, not on the server: the path
// tracer culls the raster passes, so while the renderer is raster the page
// streams the raster HDR image (f32) and the G-buffer's normal (its w says
// where geometry was drawn: the background mask) and keeps the newest, to
// compare the path-traced one with once the renderer is path. While the
// difference is on it streams the path-traced colour and albedo (whose
// alpha marks the pixels that see an emitter: the emitter mask).
//
// Test hooks: #renderer-raster, #renderer-path (aria-pressed), #path-panel
// (shown while path tracing), #path-samples[data-samples][data-spp]
// [data-converged], #path-rate[data-rate][data-seconds], #path-difference
// (the toggle), #path-difference-view, #path-difference-open,
// #path-difference-stats[data-median][data-p95][data-relative][data-rmse]
// [data-pixels][data-masked][data-frame][data-reference-frame].

import { backgroundMask, compareStats, emitterMask, fmt, formatDuration, SampleRate, statsText, statsTitle, unionMask } from './difference.js';
import { $ } from './util.js';

const RENDERER = 'quality.renderer';
const SPP = 'quality.path_spp';
const SAMPLES = { pass: 'path_trace', output: 'samples' };
export const TRACED = { pass: 'path_trace', output: 'color' };
/** Its alpha: the fraction of samples that saw a rect light directly. */
const TRACED_ALBEDO = { pass: 'path_trace', output: 'albedo' };
/** Its w: 1 where geometry was drawn. */
const RASTER_NORMAL = { pass: 'gbuffer', output: 'normal' };
/** The passes that make the raster HDR image: a control that affects one
 * changes what the raster reference shows. */
const RASTER = ['shadows', 'depth_prepass', 'gbuffer', 'ltc_tables', 'lighting', 'volume_shadows', 'volume_march', 'volumes'];
/** At most one difference this often: it goes through two float images. */
const DIFFERENCE_MS = 500;

/** A streamed capture's floats (copied: a Float32Array needs a 4-byte aligned start). */
const floats = (bytes) => new Float32Array(bytes.slice().buffer);

const same = (header, key) => header.pass === key.pass && header.output === key.output;

export class PathView {
  /**
   * @param {object} hooks
   * @param {(message: object) => void} hooks.send sends a WebSocket message
   * @param {(wanted: {pass: string, output: string, encoding: string}[]) => void}
   *   hooks.want sets the outputs streamed for this view
   * @param {() => void} hooks.refreshCaptures refetches the capture list
   *   (throttled): the sample count is in its statistics
   * @param {() => {emitters: boolean, background: boolean}} hooks.maskChoice
   *   which masks the statistics leave out (the inspector's checkboxes)
   * @param {() => void} hooks.referenceChanged the raster reference or the
   *   masks changed
   * @param {() => void} hooks.open opens |path − raster| in the inspector
   */
  constructor(hooks) {
    this.hooks = hooks;
    this.buttons = { raster: $('renderer-raster'), path: $('renderer-path') };
    this.samplesEl = $('path-samples');
    this.rateEl = $('path-rate');
    this.toggle = $('path-difference');
    this.panel = $('path-panel');
    this.view = $('path-difference-view');
    this.stats = $('path-difference-stats');

    this.renderer = null; // 'raster' | 'path', as the server renders now
    this.spp = null;
    this.controlsKey = null;
    this.values = new Map(); // path → JSON value, of the controls that change the raster image
    this.rasterKey = null; // {pass, output} of the raster HDR image
    this.reference = null; // newest raster HDR capture: {data, width, height, frame, values, normal}
    this.rasterNormal = null; // newest gbuffer/normal capture: {data, width, height, frame}
    this.traced = null; // newest path-traced HDR capture, while the difference is on
    this.tracedAlbedo = null; // and its albedo (emitter coverage in alpha)
    this.shown = null; // what the statistics on screen were made from
    this.frame = 0; // newest frame event
    this.since = 0; // sample counts from frames after this one are of the current accumulation
    this.samples = null;
    this.rate = new SampleRate();
    this.timer = null;
    this.lastDifference = -Infinity;

    for (const [value, button] of Object.entries(this.buttons)) {
      button.addEventListener('click', () => this.hooks.send({ type: 'set_override', path: RENDERER, value }));
    }
    this.toggle.addEventListener('change', () => {
      this.subscribe();
      this.show();
    });
    $('path-difference-open').addEventListener('click', () => this.open());
    this.show();
  }

  /** A `ControlsReport`: the renderer, the samples per pixel, and the
   * values the raster reference was made with. */
  setControls(report) {
    if (!report || !Array.isArray(report.controls)) return;
    const key = JSON.stringify([report.controls.map((c) => [c.path, c.value]), report.overrides]);
    // Any change restarts the accumulation: counts captured before it (a
    // previous path-traced run's, kept by the server) are not this one's.
    if (this.controlsKey !== null && key !== this.controlsKey) {
      this.since = this.frame;
      this.rate.reset();
    }
    this.controlsKey = key;
    const value = (path) => report.controls.find((c) => c.path === path)?.value ?? null;
    this.renderer = value(RENDERER);
    this.spp = value(SPP);
    // A path-traced image from an earlier run is not compared with a newer raster one.
    if (this.renderer !== 'path') {
      this.traced = null;
      this.tracedAlbedo = null;
    }
    const raster = report.controls.filter((c) => c.path !== RENDERER && c.affects?.some((p) => RASTER.includes(p)));
    this.values = new Map(raster.map((c) => [c.path, JSON.stringify(c.value)]));
    this.subscribe();
    this.show();
    this.hooks.referenceChanged();
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
    if (this.renderer === 'raster' && this.rasterKey) wanted.push({ ...this.rasterKey, encoding: 'f32' }, { ...RASTER_NORMAL, encoding: 'f32' });
    if (this.renderer === 'path') {
      // Captured for its statistics; as PNG it is the smallest stream.
      wanted.push({ ...SAMPLES, encoding: 'png' });
      if (this.toggle.checked) wanted.push({ ...TRACED, encoding: 'f32' }, { ...TRACED_ALBEDO, encoding: 'f32' });
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
    this.rate.observe(this.renderer === 'path' ? this.samples : null, performance.now());
    this.show();
  }

  /** A binary `capture` message. */
  onCapture(header, bytes) {
    if (header.encoding !== 'f32' || bytes.byteLength !== header.width * header.height * 16) return;
    const image = { data: floats(bytes), width: header.width, height: header.height, frame: header.frame };
    if (this.rasterKey && same(header, this.rasterKey)) {
      this.reference = { ...image, values: this.values, normal: this.rasterNormal };
      this.hooks.referenceChanged();
    } else if (same(header, RASTER_NORMAL)) {
      this.rasterNormal = image;
      if (this.reference && this.renderer === 'raster') this.reference.normal = image;
    } else if (this.renderer === 'path' && same(header, TRACED)) {
      this.traced = image;
      this.scheduleDifference();
    } else if (this.renderer === 'path' && same(header, TRACED_ALBEDO)) {
      this.tracedAlbedo = image;
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
      this.showRate(converged);
    }
    if (!this.view.hidden) this.scheduleDifference();
  }

  /** Samples per second and the time left to the target spp. */
  showRate(converged) {
    const rate = this.rate.rate();
    const seconds = this.spp === null ? null : this.rate.secondsTo(this.spp);
    const left = converged ? 'converged' : seconds === null ? 'time to target: measuring…' : `~${formatDuration(seconds)} to ${this.spp} spp`;
    this.rateEl.textContent = `${rate === null ? '—' : fmt(rate)} samples/s · ${left}`;
    Object.assign(this.rateEl.dataset, { rate: rate ?? '', seconds: seconds ?? '' });
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

  /**
   * The raster reference as an inspector B: {slot: {data, width, height,
   * frame, format}, label} or {problem}.
   */
  referenceSlot() {
    const problem = this.referenceProblem();
    if (problem) return { problem };
    const r = this.reference;
    return { slot: { data: r.data, width: r.width, height: r.height, frame: r.frame, format: 'Rgba32Float' }, label: `raster reference · frame ${r.frame}` };
  }

  /**
   * The masks of a width × height difference: background from the
   * reference's G-buffer normal, emitters from the path-traced albedo;
   * null where the page has none of that size.
   */
  masks(width, height) {
    const fits = (i) => i && i.width === width && i.height === height;
    const normal = this.reference?.normal;
    return {
      background: fits(normal) ? backgroundMask(normal.data, width, height) : null,
      emitters: fits(this.tracedAlbedo) ? emitterMask(this.tracedAlbedo.data, width, height) : null,
    };
  }

  /** The union of the chosen masks of a width × height difference, with
   * the names of the chosen ones the page cannot make. */
  chosenMask(width, height) {
    const choice = this.hooks.maskChoice();
    const masks = this.masks(width, height);
    const names = Object.keys(masks).filter((k) => choice[k]);
    const missing = names.filter((k) => !masks[k]);
    return { mask: unionMask(names.map((k) => masks[k])), missing };
  }

  /** Opens |path − raster| in the inspector (streaming what it needs). */
  open() {
    if (!this.toggle.checked) {
      this.toggle.checked = true;
      this.subscribe();
      this.show();
    }
    this.hooks.open();
  }

  showDifference() {
    if (this.view.hidden) return;
    const problem = this.referenceProblem() ?? (this.traced ? null : 'waiting for a path-traced frame…');
    const keys = ['median', 'p95', 'relative', 'rmse', 'pixels', 'masked', 'frame', 'referenceFrame'];
    if (problem) {
      this.shown = null;
      this.stats.textContent = problem;
      for (const key of keys) delete this.stats.dataset[key];
      return;
    }
    const [t, r] = [this.traced, this.reference];
    const { mask, missing } = this.chosenMask(t.width, t.height);
    const shown = [t, r, this.tracedAlbedo, JSON.stringify(this.hooks.maskChoice())];
    if (this.shown && shown.every((x, i) => x === this.shown[i])) return;
    this.shown = shown;
    const d = compareStats(t.data, r.data, t.width, t.height, mask);
    this.stats.textContent = `${statsText(d, missing)} · path frame ${t.frame} vs raster frame ${r.frame}`;
    this.stats.title = statsTitle();
    Object.assign(this.stats.dataset, { median: d.median, p95: d.p95, relative: d.relative, rmse: d.rmse, pixels: d.pixels, masked: d.masked, frame: t.frame, referenceFrame: r.frame });
  }

  /** For `window.loupe.state`. */
  snapshot() {
    const image = (i) => i && { frame: i.frame, width: i.width, height: i.height };
    return {
      renderer: this.renderer,
      spp: this.spp,
      samples: this.samples,
      since: this.since,
      rate: this.rate.rate(),
      rasterKey: this.rasterKey,
      reference: image(this.reference),
      referenceNormal: image(this.reference?.normal),
      traced: image(this.traced),
      tracedAlbedo: image(this.tracedAlbedo),
    };
  }
}
