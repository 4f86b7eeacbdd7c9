// The texture inspector: one captured output as exact floats, drawn with
// nearest-neighbour pixels under zoom and pan, with a value readout,
// channel isolation, exposure and range, NaN/Inf/negative overlays, and an
// A/B compare (split view or absolute difference).
//
// Data flow: fetch `.f32` (or, when live, the streamed f32 capture of the
// output the inspector subscribed to) → slot.data (Float32Array) → tonemap into the
// slot's ImageData on an off-screen canvas (only when data or display
// options change) → drawImage onto the visible canvas with the view
// transform (every pan/zoom, cheap).

import * as api from './api.js';
import * as tex from './texture.js';
import { $, el, errorText, formatMs } from './util.js';

const MIN_SCALE = 1 / 64;
const MAX_SCALE = 512;
const GRID_MIN_SCALE = 16; // pixel grid from this zoom (CSS px per pixel)
const VALUES_MIN_SCALE = 84; // values written inside pixels from this zoom
const LIVE_MIN_INTERVAL_MS = 250;
const DIVIDER_GRAB_PX = 6;

export const keyOf = (pass, output) => `${pass}/${output}`;

/** `pass/output` → {pass, output}; the output is after the last slash. */
export function parseKey(key) {
  const i = key.lastIndexOf('/');
  return i < 0 ? null : { pass: key.slice(0, i), output: key.slice(i + 1) };
}

export class Inspector {
  /**
   * @param {object} hooks
   * @param {() => Promise<object[]>} hooks.fetchCaptures refreshes /api/captures
   * @param {(pass: string, output: string) => void} hooks.onTarget
   * @param {(wanted: {pass: string, output: string}[]) => void}
   *   hooks.subscribeOnly asks the server to capture and stream exactly
   *   these outputs (as f32) to this page
   * @param {(pass: string, output: string) => Promise<boolean>}
   *   hooks.awaitCapture resolves true once the output has been captured
   */
  constructor(hooks) {
    this.hooks = hooks;
    this.root = $('inspector');
    this.canvas = this.root.querySelector('canvas');
    this.ctx = this.canvas.getContext('2d');
    this.wrap = $('canvas-wrap');
    this.messageEl = $('inspector-message');
    this.noticeEl = $('inspector-notice');
    this.selA = $('inspect-a');
    this.selMode = $('compare-mode');
    this.selB = $('compare-b');
    this.channelSel = $('channel');
    this.exposureIn = $('exposure');
    this.exposureOut = $('exposure-value');
    this.minIn = $('range-min');
    this.maxIn = $('range-max');
    this.ovNan = $('overlay-nan');
    this.ovInf = $('overlay-inf');
    this.ovNeg = $('overlay-neg');
    this.srgbIn = $('srgb');
    this.liveIn = $('live');
    this.readA = $('pixel-value');
    this.readB = $('pixel-value-b');
    this.readD = $('pixel-value-diff');
    this.zoomEl = $('zoom-level');
    this.infoEl = $('image-info');
    this.statsEl = $('stats');

    this.opts = tex.defaultOptions();
    this.target = null; // {pass, output}
    this.a = null; // slot: {key, pass, output, lastGood, data, width, height, frame, format, stats, canvas, image}
    this.b = null;
    this.diff = null;
    this.error = null; // why A could not be loaded
    this.bError = null;
    this.captures = [];
    this.view = { scale: 1, tx: 0, ty: 0 };
    this.autoView = true; // refit on resize until the user pans or zooms
    this.split = 0.5;
    this.hover = null; // {x, y} image pixel under the mouse
    this.pinned = null;
    this.drag = null;
    this.waiting = null; // `pass/output` whose first capture is awaited
    this.shownSize = null; // size of the last image shown, to keep the view

    this.seq = 0;
    this.loading = false;
    this.current = Promise.resolve(false);
    this.loads = 0;
    this.lastStart = 0;
    this.lastDuration = 0;
    this.dirty = false;
    this.refreshTimer = null;
    this.needsRebuild = false;
    this.frameRequested = false;
    this.streamed = new Map(); // `pass/output` → newest streamed capture not yet shown
    this.streamTimer = null;
    this.lastStreamed = -Infinity; // when a streamed capture last arrived
    this.lastApplied = -Infinity;
    this.streamedLoads = 0;

    this.syncControls();
    this.bindControls();
    this.bindCanvas();
    this.resize();
    new ResizeObserver(() => this.resize()).observe(this.wrap);
    this.showMessage();
    this.refreshReadout();
  }

  // ---- selection and loading ------------------------------------------

  /** Inspects `pass/output`; resolves true once its data is shown. */
  inspect(pass, output) {
    if (typeof pass !== 'string' || typeof output !== 'string') return Promise.resolve(false);
    const changed = !this.target || keyOf(this.target.pass, this.target.output) !== keyOf(pass, output);
    this.target = { pass, output };
    if (changed) {
      // Never show one output's pixels under another's name while the new
      // one loads; the view is kept if the new output has the same size.
      this.pinned = null;
      this.a = null;
      this.b = null;
      this.diff = null;
      this.error = null;
      this.bError = null;
      this.draw();
      this.updateInfo();
      this.refreshReadout();
    }
    this.ensureOption(this.selA, keyOf(pass, output));
    this.selA.value = keyOf(pass, output);
    this.hooks.onTarget?.(pass, output);
    return this.load();
  }

  /** What B is: A's previous good version, or another output. */
  compareSpec() {
    const mode = this.selMode.value;
    if (mode === 'off' || !this.target) return null;
    const value = this.selB.value;
    if (value === 'last_good' || !value) return { ...this.target, lastGood: true };
    const parsed = parseKey(value);
    return parsed ? { ...parsed, lastGood: false } : null;
  }

  metaFor(pass, output) {
    return this.captures.find((c) => c.pass === pass && c.output === output) || null;
  }

  /**
   * Fetches A (and B when comparing) and shows them. Overlapping loads are
   * resolved newest-wins: an older response never replaces a newer one,
   * and every caller's promise settles with the newest load's result.
   */
  load() {
    if (!this.target) return Promise.resolve(false);
    const seq = ++this.seq;
    const run = this.loadOnce(seq);
    this.current = run.then((ok) => (seq === this.seq ? ok : this.current));
    return this.current;
  }

  async loadOnce(seq) {
    const { pass, output } = this.target;
    const key = keyOf(pass, output);
    const bSpec = this.compareSpec();
    this.loading = true;
    this.root.classList.add('loading');
    this.lastStart = performance.now();
    this.showMessage();

    // The server captures only the final output and what clients
    // subscribe to, and streams subscribed outputs to this page.
    this.hooks.subscribeOnly?.([{ pass, output }, ...(bSpec && !bSpec.lastGood ? [bSpec] : [])]);
    // The capture list carries formats and sizes; refreshing it alongside
    // keeps the selects and the info line in step with the data.
    const capturesP = this.hooks.fetchCaptures ? this.hooks.fetchCaptures().catch(() => null) : null;
    const fetchSlot = async (spec) => {
      const get = () =>
        api.captureF32(spec.pass, spec.output, {
          lastGood: spec.lastGood,
          fallback: this.metaFor(spec.pass, spec.output),
        });
      try {
        return await get();
      } catch (err) {
        // Not captured yet: a new subscription shows up a frame or two
        // later. Wait for it once, then give up with the 404.
        if (spec.lastGood || !(err instanceof api.ApiError) || !err.notFound || !this.hooks.awaitCapture) throw err;
        this.waiting = keyOf(spec.pass, spec.output);
        this.showMessage();
        const captured = await this.hooks.awaitCapture(spec.pass, spec.output);
        if (this.waiting === keyOf(spec.pass, spec.output)) this.waiting = null;
        if (!captured) throw err;
        return get();
      }
    };
    const [ra, rb] = await Promise.allSettled([fetchSlot({ pass, output, lastGood: false }), bSpec ? fetchSlot(bSpec) : null]);
    await capturesP;
    if (seq !== this.seq) return false; // superseded: the newer load reports
    this.waiting = null;

    this.lastDuration = performance.now() - this.lastStart;
    this.loading = false;
    this.root.classList.remove('loading');
    this.loads++;

    const meta = this.metaFor(pass, output);
    if (ra.status === 'fulfilled') {
      const prev = this.a;
      this.a = this.makeSlot(ra.value, { key, pass, output, lastGood: false, format: ra.value.format || meta?.format }, prev);
      this.error = null;
      const size = `${this.a.width}x${this.a.height}`;
      if (size !== this.shownSize) this.autoView = true;
      this.shownSize = size;
    } else {
      this.error = ra.reason;
      // A failed live refresh keeps the last image (the server may be
      // restarting); a failed new selection must not show the old one.
      if (this.a && this.a.key !== key) this.a = null;
    }
    if (bSpec && rb.status === 'fulfilled') {
      const bKey = bSpec.lastGood ? `${key}@last_good` : keyOf(bSpec.pass, bSpec.output);
      const bMeta = this.metaFor(bSpec.pass, bSpec.output);
      this.b = this.makeSlot(rb.value, { key: bKey, ...bSpec, format: rb.value.format || bMeta?.format }, this.b);
      this.bError = null;
    } else {
      this.b = null;
      this.bError = bSpec ? rb.reason : null;
    }

    this.redisplay();

    if (this.dirty) {
      this.dirty = false;
      this.requestRefresh();
    }
    return ra.status === 'fulfilled';
  }

  makeSlot(loaded, info, prev) {
    const slot = { ...info, ...loaded, stats: tex.computeStats(loaded.data, loaded.width, loaded.height) };
    // Reuse the off-screen canvas and ImageData when the size is the same:
    // live refresh would otherwise allocate megabytes per frame.
    if (prev && prev.width === slot.width && prev.height === slot.height && prev.canvas) {
      slot.canvas = prev.canvas;
      slot.image = prev.image;
    }
    return slot;
  }

  /**
   * A frame was rendered: refresh the inspected data when live. Streamed
   * captures refresh A (and B when it is another output) by themselves;
   * a fetch is needed only before the stream starts and for a last-good B.
   */
  onFrame() {
    if (!this.liveIn.checked || !this.target) return;
    const streaming = performance.now() - this.lastStreamed < 2000;
    if (!streaming || this.compareSpec()?.lastGood) this.requestRefresh();
  }

  /** The slot spec a streamed `pass/output` fills when live: 'a', 'b' or null. */
  streamSlot(key) {
    if (!this.liveIn.checked || !this.target) return null;
    if (key === keyOf(this.target.pass, this.target.output)) return 'a';
    const b = this.compareSpec();
    return b && !b.lastGood && key === keyOf(b.pass, b.output) ? 'b' : null;
  }

  /**
   * A binary `capture` message. Newest wins: captures that arrive while
   * one is shown are dropped, and at most one is shown per
   * LIVE_MIN_INTERVAL_MS (a float image is megabytes to analyse).
   */
  onCapture(header, bytes) {
    const key = keyOf(header.pass, header.output);
    if (header.encoding !== 'f32' || !this.streamSlot(key)) return;
    if (bytes.byteLength !== header.width * header.height * 16) return;
    this.streamed.set(key, { header, bytes });
    this.lastStreamed = performance.now();
    this.scheduleStreamed();
  }

  scheduleStreamed() {
    if (this.streamTimer !== null) return;
    const wait = Math.max(0, this.lastApplied + LIVE_MIN_INTERVAL_MS - performance.now());
    this.streamTimer = setTimeout(() => {
      this.streamTimer = null;
      this.applyStreamed();
    }, wait);
  }

  applyStreamed() {
    // A fetch in flight reports when it lands; streamed data waits for it.
    if (this.loading) return this.scheduleStreamed();
    this.lastApplied = performance.now();
    for (const [key, { header, bytes }] of this.streamed) {
      const which = this.streamSlot(key);
      if (!which) continue;
      // Copied: a Float32Array needs a 4-byte aligned start.
      const loaded = { data: new Float32Array(bytes.slice().buffer), width: header.width, height: header.height, frame: header.frame, format: header.format };
      const info = { key, pass: header.pass, output: header.output, lastGood: false, format: header.format };
      if (which === 'a') {
        this.a = this.makeSlot(loaded, info, this.a);
        this.error = null;
      } else {
        this.b = this.makeSlot(loaded, info, this.b);
        this.bError = null;
      }
    }
    this.streamed.clear();
    this.streamedLoads++;
    this.redisplay();
  }

  /** New data in A or B: retonemap, draw, update the message and readout. */
  redisplay() {
    this.needsRebuild = true;
    this.flush();
    this.showMessage();
    this.refreshReadout();
  }

  /**
   * Throttled refresh: at most one fetch in flight, no sooner than
   * LIVE_MIN_INTERVAL_MS or twice the last fetch time after the previous
   * one (so a large capture on a slow link cannot saturate it), and always
   * a trailing fetch so the last frame of a burst is the one shown.
   */
  requestRefresh() {
    if (this.loading) {
      this.dirty = true;
      return;
    }
    if (this.refreshTimer !== null) return;
    // A failing target (404 while a pass is broken) is polled gently.
    const floor = this.error ? 4 * LIVE_MIN_INTERVAL_MS : LIVE_MIN_INTERVAL_MS;
    const interval = Math.max(floor, 2 * this.lastDuration);
    const wait = Math.max(0, this.lastStart + interval - performance.now());
    this.refreshTimer = setTimeout(() => {
      this.refreshTimer = null;
      this.load();
    }, wait);
  }

  /** New capture list: rebuild the A and B selects, keeping selections. */
  setCaptures(list) {
    this.captures = Array.isArray(list) ? list : [];
    const keys = this.captures.map((c) => keyOf(c.pass, c.output));
    const label = (c) => `${c.pass} / ${c.output}${c.format ? `  ${c.format}` : ''}${c.width ? ` ${c.width}×${c.height}` : ''}`;
    const aValue = this.target ? keyOf(this.target.pass, this.target.output) : '';
    const bValue = this.selB.value || 'last_good';
    // Refreshed with every live fetch: rebuilding identical options would
    // close a dropdown the user has open.
    const aMetaNow = this.target ? this.metaFor(this.target.pass, this.target.output) : null;
    const signature = JSON.stringify([this.captures.map(label), aValue, aMetaNow?.last_good]);
    if (signature === this.optionsSignature) {
      this.updateInfo();
      return;
    }
    this.optionsSignature = signature;

    const aOptions = [el('option', { value: '', disabled: true }, keys.length ? 'select an output…' : 'no captures yet')];
    for (const c of this.captures) aOptions.push(el('option', { value: keyOf(c.pass, c.output) }, label(c)));
    this.selA.replaceChildren(...aOptions);
    if (aValue) this.ensureOption(this.selA, aValue);
    this.selA.value = aValue;

    // The list says whether A has a previous good version to compare with.
    const aMeta = this.target ? this.metaFor(this.target.pass, this.target.output) : null;
    const lastGoodText = aMeta && aMeta.last_good === false ? 'A · last good version (none yet)' : 'A · last good version';
    const bOptions = [el('option', { value: 'last_good' }, lastGoodText)];
    for (const c of this.captures) bOptions.push(el('option', { value: keyOf(c.pass, c.output) }, label(c)));
    this.selB.replaceChildren(...bOptions);
    if (bValue !== 'last_good') this.ensureOption(this.selB, bValue);
    this.selB.value = bValue;
    this.updateInfo();
  }

  ensureOption(select, value) {
    if ([...select.options].some((o) => o.value === value)) return;
    select.append(el('option', { value }, `${value} · not captured yet`));
  }

  // ---- controls ---------------------------------------------------------

  syncControls() {
    this.channelSel.value = this.opts.channel;
    this.exposureIn.value = String(this.opts.exposure);
    this.minIn.value = String(this.opts.min);
    this.maxIn.value = String(this.opts.max);
    this.srgbIn.checked = this.opts.srgb;
    this.ovNan.checked = this.opts.overlayNan;
    this.ovInf.checked = this.opts.overlayInf;
    this.ovNeg.checked = this.opts.overlayNeg;
    this.showExposure();
  }

  showExposure() {
    const ev = this.opts.exposure;
    this.exposureOut.textContent = `${ev >= 0 ? '+' : ''}${ev.toFixed(1)} EV`;
  }

  bindControls() {
    const changed = () => {
      this.needsRebuild = true;
      this.requestFrame();
    };
    this.selA.addEventListener('change', () => {
      const parsed = parseKey(this.selA.value);
      if (parsed) this.inspect(parsed.pass, parsed.output);
    });
    this.selMode.addEventListener('change', () => {
      this.root.dataset.compare = this.selMode.value;
      this.load();
    });
    this.selB.addEventListener('change', () => {
      if (this.selMode.value !== 'off') this.load();
    });
    this.channelSel.addEventListener('change', () => {
      this.opts.channel = tex.CHANNELS.includes(this.channelSel.value) ? this.channelSel.value : 'rgb';
      changed();
    });
    this.exposureIn.addEventListener('input', () => {
      const v = Number(this.exposureIn.value);
      this.opts.exposure = Number.isFinite(v) ? v : 0;
      this.showExposure();
      changed();
    });
    this.exposureOut.addEventListener('dblclick', () => {
      this.opts.exposure = 0;
      this.syncControls();
      changed();
    });
    for (const [input, field] of [
      [this.minIn, 'min'],
      [this.maxIn, 'max'],
    ]) {
      input.addEventListener('input', () => {
        const v = Number(input.value);
        const ok = input.value.trim() !== '' && Number.isFinite(v);
        input.classList.toggle('invalid', !ok);
        if (!ok) return;
        this.opts[field] = v;
        changed();
      });
    }
    for (const [input, field] of [
      [this.ovNan, 'overlayNan'],
      [this.ovInf, 'overlayInf'],
      [this.ovNeg, 'overlayNeg'],
      [this.srgbIn, 'srgb'],
    ]) {
      input.addEventListener('change', () => {
        this.opts[field] = input.checked;
        changed();
      });
    }
    $('auto-fit').addEventListener('click', () => this.autoFit());
    $('reset-range').addEventListener('click', () => {
      Object.assign(this.opts, { exposure: 0, min: 0, max: 1 });
      this.syncControls();
      changed();
    });
    $('refresh').addEventListener('click', () => this.load());
    $('fit').addEventListener('click', () => this.fit());
    $('zoom-1').addEventListener('click', () => this.zoomTo(1 / (window.devicePixelRatio || 1)));
    this.liveIn.addEventListener('change', () => {
      if (this.liveIn.checked) this.requestRefresh();
    });
  }

  /** The image the display options apply to: the difference in diff mode. */
  displayedSlot() {
    if (this.mode() === 'diff' && this.diff) return this.diff;
    return this.a;
  }

  /** Sets range to the finite min/max of what is displayed, at 0 EV. */
  autoFit() {
    const slot = this.displayedSlot();
    if (!slot) return null;
    const range = tex.finiteRange(slot.data, this.opts.channel);
    if (!range) {
      this.notice('auto-fit: no finite values in this channel');
      return null;
    }
    let { min, max } = range;
    if (min === max) {
      // A constant image: centre it in a unit-wide window.
      min -= 0.5;
      max += 0.5;
    }
    Object.assign(this.opts, { exposure: 0, min, max });
    this.syncControls();
    this.needsRebuild = true;
    this.requestFrame();
    return { min, max };
  }

  mode() {
    const m = this.selMode.value;
    return m === 'split' || m === 'diff' ? m : 'off';
  }

  // ---- rendering --------------------------------------------------------

  requestFrame() {
    if (this.frameRequested) return;
    this.frameRequested = true;
    requestAnimationFrame(() => {
      this.frameRequested = false;
      this.flush();
    });
  }

  /** Does any pending rebuild now, then draws. */
  flush() {
    if (this.needsRebuild) {
      this.needsRebuild = false;
      this.rebuild();
    }
    this.draw();
  }

  rebuild() {
    const mode = this.mode();
    if (this.a && mode !== 'diff') this.tonemapSlot(this.a);
    if (this.b && mode === 'split') this.tonemapSlot(this.b);
    if (this.a && this.b && mode === 'diff') {
      const d = tex.difference(this.a.data, this.a.width, this.a.height, this.b.data, this.b.width, this.b.height);
      const prev = this.diff;
      this.diff = { key: 'diff', ...d };
      if (prev && prev.width === d.width && prev.height === d.height) {
        this.diff.canvas = prev.canvas;
        this.diff.image = prev.image;
      }
      this.tonemapSlot(this.diff);
    } else {
      this.diff = null;
    }
    if (this.autoView && this.a) this.fit();
    this.updateInfo();
  }

  /**
   * Lays a map over A (quad statistics): {width, height, rgba} or null.
   * Shown only without a compare, at A's scale, from A's top-left corner.
   */
  setOverlay(map) {
    if (!map) this.overlay = null;
    else {
      const canvas = document.createElement('canvas');
      canvas.width = map.width;
      canvas.height = map.height;
      canvas.getContext('2d').putImageData(new ImageData(map.rgba, map.width, map.height), 0, 0);
      this.overlay = { canvas, width: map.width, height: map.height, kind: map.kind };
    }
    this.draw();
  }

  tonemapSlot(slot) {
    if (!slot.canvas) {
      slot.canvas = document.createElement('canvas');
      slot.canvas.width = slot.width;
      slot.canvas.height = slot.height;
      slot.image = new ImageData(slot.width, slot.height);
    }
    tex.tonemap(slot.data, slot.width, slot.height, this.opts, slot.image.data);
    slot.canvas.getContext('2d').putImageData(slot.image, 0, 0);
  }

  resize() {
    const rect = this.wrap.getBoundingClientRect();
    const dpr = window.devicePixelRatio || 1;
    const w = Math.max(1, Math.round(rect.width * dpr));
    const h = Math.max(1, Math.round(rect.height * dpr));
    if (this.canvas.width !== w || this.canvas.height !== h) {
      this.canvas.width = w;
      this.canvas.height = h;
    }
    if (this.autoView && this.a) this.fit();
    else this.draw();
  }

  cssSize() {
    const dpr = window.devicePixelRatio || 1;
    return { w: this.canvas.width / dpr, h: this.canvas.height / dpr, dpr };
  }

  draw() {
    const { ctx } = this;
    const { w, h, dpr } = this.cssSize();
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    ctx.clearRect(0, 0, w, h);
    ctx.imageSmoothingEnabled = false;
    const { scale, tx, ty } = this.view;
    const mode = this.mode();
    const put = (slot) => {
      if (slot?.canvas) ctx.drawImage(slot.canvas, tx, ty, slot.width * scale, slot.height * scale);
    };
    const splitX = this.split * w;

    if (mode === 'diff' && this.diff) put(this.diff);
    else if (mode === 'split' && this.a && this.b) {
      ctx.save();
      ctx.beginPath();
      ctx.rect(0, 0, splitX, h);
      ctx.clip();
      put(this.a);
      ctx.restore();
      ctx.save();
      ctx.beginPath();
      ctx.rect(splitX, 0, w - splitX, h);
      ctx.clip();
      put(this.b);
      ctx.restore();
    } else put(this.a);
    if (this.overlay?.canvas && mode === 'off') put(this.overlay);

    const shown = this.displayedSlot();
    if (shown) {
      ctx.strokeStyle = 'rgba(255,255,255,0.18)';
      ctx.lineWidth = 1;
      ctx.strokeRect(tx - 0.5, ty - 0.5, shown.width * scale + 1, shown.height * scale + 1);
      if (scale >= GRID_MIN_SCALE) this.drawGrid(shown, w, h);
      if (scale >= VALUES_MIN_SCALE) this.drawValues(w, h, splitX);
      this.drawMarker(this.pinned, '#ffd33d');
      if (this.hover && (!this.pinned || this.hover.x !== this.pinned.x || this.hover.y !== this.pinned.y)) {
        this.drawMarker(this.hover, 'rgba(255,255,255,0.85)');
      }
    }

    if (mode === 'split' && this.a && this.b) {
      ctx.fillStyle = '#e6e6e6';
      ctx.fillRect(Math.round(splitX) - 1, 0, 2, h);
      ctx.fillStyle = '#2b6fd6';
      ctx.fillRect(Math.round(splitX) - 5, h / 2 - 18, 10, 36);
      this.label('A', 8, 8, 'left');
      this.label(this.b.lastGood ? 'B · last good' : `B · ${this.b.key}`, w - 8, 8, 'right');
    } else if (mode === 'diff' && this.diff) {
      this.label(`|A − B|  vs ${this.b.lastGood ? 'last good' : this.b.key}`, 8, 8, 'left');
    }
    this.zoomEl.textContent = `${Math.round(scale * dpr * 100)}%`;
  }

  label(text, x, y, align) {
    const { ctx } = this;
    ctx.font = '11px ui-monospace, SFMono-Regular, Menlo, Consolas, monospace';
    ctx.textAlign = align;
    ctx.textBaseline = 'top';
    const m = ctx.measureText(text).width;
    ctx.fillStyle = 'rgba(0,0,0,0.65)';
    ctx.fillRect(align === 'right' ? x - m - 6 : x - 2, y - 2, m + 8, 16);
    ctx.fillStyle = '#e6e6e6';
    ctx.fillText(text, align === 'right' ? x - 2 : x + 2, y + 1);
  }

  /** Visible pixel index range of `slot`. */
  visible(slot, w, h) {
    const { scale, tx, ty } = this.view;
    return {
      x0: Math.max(0, Math.floor(-tx / scale)),
      y0: Math.max(0, Math.floor(-ty / scale)),
      x1: Math.min(slot.width, Math.ceil((w - tx) / scale)),
      y1: Math.min(slot.height, Math.ceil((h - ty) / scale)),
    };
  }

  drawGrid(slot, w, h) {
    const { ctx } = this;
    const { scale, tx, ty } = this.view;
    const { x0, y0, x1, y1 } = this.visible(slot, w, h);
    ctx.strokeStyle = 'rgba(128,128,128,0.35)';
    ctx.lineWidth = 1;
    ctx.beginPath();
    for (let x = x0; x <= x1; x++) {
      const sx = Math.round(tx + x * scale) + 0.5;
      ctx.moveTo(sx, ty + y0 * scale);
      ctx.lineTo(sx, ty + y1 * scale);
    }
    for (let y = y0; y <= y1; y++) {
      const sy = Math.round(ty + y * scale) + 0.5;
      ctx.moveTo(tx + x0 * scale, sy);
      ctx.lineTo(tx + x1 * scale, sy);
    }
    ctx.stroke();
  }

  /** At high zoom, each pixel shows its values, like a spreadsheet. */
  drawValues(w, h, splitX) {
    const { ctx } = this;
    const { scale, tx, ty } = this.view;
    const base = this.displayedSlot();
    const { x0, y0, x1, y1 } = this.visible(base, w, h);
    if ((x1 - x0) * (y1 - y0) > 600) return;
    const fontPx = Math.min(12, Math.floor(scale / 7));
    ctx.font = `${fontPx}px ui-monospace, SFMono-Regular, Menlo, Consolas, monospace`;
    ctx.textAlign = 'left';
    ctx.textBaseline = 'top';
    const split = this.mode() === 'split' && this.a && this.b;
    for (let y = y0; y < y1; y++) {
      for (let x = x0; x < x1; x++) {
        const cx = tx + (x + 0.5) * scale;
        const slot = split && cx >= splitX ? this.b : base;
        const v = tex.pixel(slot.data, slot.width, slot.height, x, y);
        if (!v) continue;
        const i = (y * slot.width + x) * 4;
        const img = slot.image?.data;
        const lum = img ? 0.2126 * img[i] + 0.7152 * img[i + 1] + 0.0722 * img[i + 2] : 0;
        ctx.fillStyle = lum > 140 ? 'rgba(0,0,0,0.85)' : 'rgba(255,255,255,0.9)';
        const left = tx + x * scale + 3;
        const top = ty + y * scale + 3;
        ['R', 'G', 'B', 'A'].forEach((c, k) => {
          const s = tex.formatF32(v[k]);
          ctx.fillText(`${c} ${s.length > 9 ? Number(v[k]).toPrecision(4) : s}`, left, top + k * (fontPx + 2));
        });
      }
    }
  }

  drawMarker(p, color) {
    if (!p || this.view.scale < 4) return;
    const { scale, tx, ty } = this.view;
    this.ctx.strokeStyle = color;
    this.ctx.lineWidth = 2;
    this.ctx.strokeRect(tx + p.x * scale, ty + p.y * scale, scale, scale);
  }

  // ---- view -------------------------------------------------------------

  fit() {
    const slot = this.displayedSlot() || this.a;
    if (!slot) return;
    const { w, h } = this.cssSize();
    let scale = Math.min(w / slot.width, h / slot.height) * 0.96;
    // Upscaled images get an integer zoom so pixels stay equal in size.
    if (scale > 1) scale = Math.floor(scale);
    scale = Math.min(MAX_SCALE, Math.max(MIN_SCALE, scale));
    this.view = {
      scale,
      tx: Math.round((w - slot.width * scale) / 2),
      ty: Math.round((h - slot.height * scale) / 2),
    };
    this.autoView = true;
    this.draw();
  }

  zoomTo(scale, cx, cy) {
    const { w, h } = this.cssSize();
    const ax = cx ?? w / 2;
    const ay = cy ?? h / 2;
    const s = Math.min(MAX_SCALE, Math.max(MIN_SCALE, scale));
    const { view } = this;
    // Keep the image point under (ax, ay) fixed.
    view.tx = ax - ((ax - view.tx) * s) / view.scale;
    view.ty = ay - ((ay - view.ty) * s) / view.scale;
    view.scale = s;
    this.autoView = false;
    this.draw();
  }

  /** Canvas CSS coordinates of a pointer event. */
  local(e) {
    const r = this.canvas.getBoundingClientRect();
    return { x: e.clientX - r.left, y: e.clientY - r.top };
  }

  toPixel(p) {
    const { scale, tx, ty } = this.view;
    return { x: Math.floor((p.x - tx) / scale), y: Math.floor((p.y - ty) / scale) };
  }

  bindCanvas() {
    const c = this.canvas;
    c.addEventListener(
      'wheel',
      (e) => {
        e.preventDefault();
        const p = this.local(e);
        const lines = e.deltaMode === 1 ? 33 : e.deltaMode === 2 ? 400 : 1;
        this.zoomTo(this.view.scale * Math.pow(2, (-e.deltaY * lines) / 240), p.x, p.y);
        this.setHover(this.toPixel(p));
      },
      { passive: false },
    );
    c.addEventListener('pointerdown', (e) => {
      if (e.button !== 0) return;
      const p = this.local(e);
      const { w } = this.cssSize();
      const onDivider = this.mode() === 'split' && this.b && Math.abs(p.x - this.split * w) <= DIVIDER_GRAB_PX;
      this.drag = { kind: onDivider ? 'split' : 'pan', start: p, last: p, moved: false };
      c.setPointerCapture(e.pointerId);
      c.focus({ preventScroll: true });
    });
    c.addEventListener('pointermove', (e) => {
      const p = this.local(e);
      const d = this.drag;
      if (d) {
        if (Math.abs(p.x - d.start.x) + Math.abs(p.y - d.start.y) > 3) d.moved = true;
        if (d.kind === 'split') {
          this.split = Math.min(1, Math.max(0, p.x / this.cssSize().w));
        } else if (d.moved) {
          this.view.tx += p.x - d.last.x;
          this.view.ty += p.y - d.last.y;
          this.autoView = false;
        }
        d.last = p;
        this.draw();
      }
      const { w } = this.cssSize();
      const nearDivider = this.mode() === 'split' && this.b && Math.abs(p.x - this.split * w) <= DIVIDER_GRAB_PX;
      c.style.cursor = nearDivider || d?.kind === 'split' ? 'ew-resize' : d?.moved ? 'grabbing' : 'crosshair';
      this.setHover(this.toPixel(p));
    });
    const end = (e) => {
      const d = this.drag;
      this.drag = null;
      if (c.hasPointerCapture?.(e.pointerId)) c.releasePointerCapture(e.pointerId);
      // A click without a drag pins the pixel (or unpins it).
      if (d && d.kind === 'pan' && !d.moved && e.type === 'pointerup') {
        const px = this.toPixel(this.local(e));
        const same = this.pinned && this.pinned.x === px.x && this.pinned.y === px.y;
        this.pinned = same || !this.inside(px) ? null : px;
        this.refreshReadout();
        this.draw();
      }
    };
    c.addEventListener('pointerup', end);
    c.addEventListener('pointercancel', end);
    c.addEventListener('pointerleave', () => {
      if (!this.drag) this.setHover(null);
    });
    c.addEventListener('dblclick', () => this.fit());
    c.addEventListener('keydown', (e) => {
      if (e.key === 'f') this.fit();
      else if (e.key === '1') this.zoomTo(1 / (window.devicePixelRatio || 1));
      else if (e.key === 'Escape') {
        this.pinned = null;
        this.refreshReadout();
        this.draw();
      } else if (e.key.startsWith('Arrow') && this.pinned) {
        // Step the pinned pixel: reading neighbours without a steady hand.
        const d = { ArrowLeft: [-1, 0], ArrowRight: [1, 0], ArrowUp: [0, -1], ArrowDown: [0, 1] }[e.key];
        const next = { x: this.pinned.x + d[0], y: this.pinned.y + d[1] };
        if (this.inside(next)) this.pinned = next;
        e.preventDefault();
        this.refreshReadout();
        this.draw();
      } else return;
    });
  }

  inside(p) {
    const s = this.a;
    return !!(s && p && p.x >= 0 && p.y >= 0 && p.x < s.width && p.y < s.height);
  }

  setHover(p) {
    const next = p && this.inside(p) ? p : null;
    const prev = this.hover;
    if (next === prev || (next && prev && next.x === prev.x && next.y === prev.y)) return;
    this.hover = next;
    this.refreshReadout();
    this.draw();
  }

  // ---- readout and info -------------------------------------------------

  refreshReadout() {
    const p = this.pinned || this.hover;
    const mode = this.mode();
    this.writeValues(this.readA, 'A', this.a, p);
    this.readB.hidden = mode === 'off';
    this.readD.hidden = mode !== 'diff';
    if (mode !== 'off') this.writeValues(this.readB, 'B', this.b, p);
    if (mode === 'diff') this.writeValues(this.readD, '|A−B|', this.diff, p);
    this.readA.classList.toggle('pinned', !!this.pinned);
  }

  writeValues(node, label, slot, p) {
    for (const k of ['x', 'y', 'r', 'g', 'b', 'a']) delete node.dataset[k];
    const v = slot && p ? tex.pixel(slot.data, slot.width, slot.height, p.x, p.y) : null;
    if (!v) {
      node.replaceChildren(
        ...(this.mode() !== 'off' ? [el('span', { class: 'ro-label' }, label), ' '] : []),
        el('span', { class: 'muted' }, slot ? 'hover the image to read a pixel · click to pin · wheel zooms · drag pans' : '—'),
      );
      return;
    }
    node.dataset.x = String(p.x);
    node.dataset.y = String(p.y);
    // Attributes hold the exact value (the float32 widened to a double,
    // as JS prints it): a test can parse them back bit-exactly.
    ['r', 'g', 'b', 'a'].forEach((c, i) => (node.dataset[c] = String(v[i])));
    const cls = (x) => (x !== x ? 'nan' : x === Infinity || x === -Infinity ? 'inf' : x < 0 ? 'neg' : '');
    // Real spaces between the parts, so the element's text reads well when
    // copied or asserted on: "(3, 2) R 0.5 G 1 B 0 A 1".
    const parts = [];
    if (this.mode() !== 'off') parts.push(el('span', { class: 'ro-label' }, label));
    parts.push(el('span', { class: 'coord' }, `(${p.x}, ${p.y})`));
    ['R', 'G', 'B', 'A'].forEach((c, i) =>
      parts.push(
        el(
          'span',
          { class: `ch ch-${c.toLowerCase()} ${cls(v[i])}`, title: `${c} = ${String(v[i])} (${tex.f32Bits(v[i])})` },
          el('span', { class: 'ch-name' }, c),
          ' ',
          tex.formatF32(v[i]),
        ),
      ),
    );
    if (this.pinned && label !== '|A−B|' && label !== 'B') {
      parts.push(el('span', { class: 'pin-tag', title: 'Esc or click again to unpin' }, 'pinned'));
    }
    node.replaceChildren(...parts.flatMap((part, i) => (i ? [' ', part] : [part])));
  }

  updateInfo() {
    const a = this.a;
    if (!a) {
      this.infoEl.textContent = '';
      this.statsEl.replaceChildren();
      return;
    }
    const meta = this.metaFor(a.pass, a.output);
    const format = a.format || meta?.format || '';
    const frame = a.frame ?? meta?.frame;
    this.infoEl.textContent = `${a.key} · ${a.width}×${a.height}${format ? ` · ${format}` : ''}${frame != null ? ` · frame ${frame}` : ''}`;

    const s = a.stats;
    const items = [];
    const badge = (n, cls, word) =>
      el('span', { class: `stat ${n ? cls : 'zero'}`, dataset: { stat: cls } }, `${n} ${word}`);
    items.push(badge(s.nan, 'nan', 'NaN'));
    if (s.first_nan && (s.nan || s.inf)) {
      items.push(
        el(
          'button',
          {
            type: 'button',
            class: 'link',
            title: 'centre and pin the first pixel holding a NaN or Inf',
            onclick: () => this.goTo(s.first_nan[0], s.first_nan[1]),
          },
          `first at ${s.first_nan[0]},${s.first_nan[1]}`,
        ),
      );
    }
    items.push(badge(s.inf, 'inf', 'Inf'));
    items.push(badge(s.negative, 'neg', 'negative'));
    const fmt = (x) => (Number.isFinite(x) ? tex.formatF32(Math.fround(x)) : '—');
    items.push(
      el(
        'span',
        { class: 'stat range', title: 'finite min / max per channel (R G B A)' },
        `min ${s.min.map(fmt).join(' ')}  max ${s.max.map(fmt).join(' ')}`,
      ),
    );
    this.statsEl.replaceChildren(...items);
  }

  /** Centres (x, y) at a readable zoom and pins it. */
  goTo(x, y) {
    const { w, h } = this.cssSize();
    const scale = Math.max(this.view.scale, 16);
    this.view = { scale, tx: w / 2 - (x + 0.5) * scale, ty: h / 2 - (y + 0.5) * scale };
    this.autoView = false;
    this.pinned = { x, y };
    this.refreshReadout();
    this.draw();
  }

  notice(text) {
    this.noticeEl.textContent = text;
    this.noticeEl.hidden = !text;
  }

  showMessage() {
    const m = this.messageEl;
    let text = '';
    let kind = 'info';
    if (!this.target) {
      text = 'Select a pass or an output to inspect it.';
    } else if (this.error && !this.a) {
      kind = 'error';
      const what = keyOf(this.target.pass, this.target.output);
      text = this.error.notFound
        ? `No capture of ${what} (404). The pass may be culled or failed, or it has not rendered yet.`
        : `Could not load ${what}: ${errorText(this.error)}`;
    } else if (!this.a && this.waiting) {
      text = `Waiting for the server to capture ${this.waiting}…`;
    } else if (!this.a && this.loading) {
      text = 'Loading…';
    }
    m.textContent = text;
    m.className = kind;
    m.hidden = !text;

    const notes = [];
    if (this.error && this.a) notes.push(`refresh failed, showing the last data: ${errorText(this.error)}`);
    if (this.bError) {
      notes.push(
        this.bError.notFound && this.compareSpec()?.lastGood
          ? 'B: no previous good version of this output yet (404)'
          : `B: ${errorText(this.bError)}`,
      );
    }
    if (this.a && this.b && (this.a.width !== this.b.width || this.a.height !== this.b.height)) {
      notes.push(
        `A is ${this.a.width}×${this.a.height}, B is ${this.b.width}×${this.b.height}: the difference covers the overlap`,
      );
    }
    this.notice(notes.join(' · '));
  }

  // ---- test hooks -------------------------------------------------------

  /** Float RGBA of pixel (x, y) of A, B or the difference. */
  valueAt(x, y, which = 'a') {
    const slot = which === 'b' ? this.b : which === 'diff' ? this.diff : this.a;
    return slot ? tex.pixel(slot.data, slot.width, slot.height, x, y) : null;
  }

  /** Display RGBA8 of pixel (x, y) after tonemapping and overlays. */
  displayedAt(x, y, which) {
    this.flush();
    const slot = which === 'b' ? this.b : which === 'a' ? this.a : this.displayedSlot();
    if (!slot?.image) return null;
    const p = tex.pixel(slot.image.data, slot.width, slot.height, x, y);
    return p ? Array.from(p) : null;
  }

  /** Acts as if the mouse were over image pixel (x, y); null clears. */
  hoverPixel(x, y) {
    this.pinned = null;
    this.hover = null;
    this.setHover(x === null || x === undefined ? null : { x, y });
    return this.valueAt(x, y);
  }

  snapshot() {
    const a = this.a;
    return {
      pass: this.target?.pass ?? null,
      output: this.target?.output ?? null,
      loaded: !!a,
      loading: this.loading,
      loads: this.loads,
      streamedLoads: this.streamedLoads,
      // Whether live refresh rides the stream (true) or fetches (false).
      streaming: performance.now() - this.lastStreamed < 2000,
      error: this.error ? errorText(this.error) : null,
      width: a?.width ?? null,
      height: a?.height ?? null,
      frame: a?.frame ?? null,
      format: a?.format ?? null,
      stats: a ? { ...a.stats } : null,
      overlay: this.overlay ? { kind: this.overlay.kind, width: this.overlay.width, height: this.overlay.height } : null,
      compare: {
        mode: this.mode(),
        b: this.selB.value,
        loaded: !!this.b,
        error: this.bError ? errorText(this.bError) : null,
      },
      options: { ...this.opts },
      view: { ...this.view },
      hover: this.hover,
      pinned: this.pinned,
      live: this.liveIn.checked,
      lastFetchMs: this.lastDuration ? Number(formatMs(this.lastDuration)) : null,
    };
  }
}
