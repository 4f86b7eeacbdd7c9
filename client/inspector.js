// The texture inspector: one captured output as exact floats, drawn with
// nearest-neighbour pixels under zoom and pan, with a value readout,
// channel isolation, exposure and range, NaN/Inf/negative overlays, and an
// A/B compare (split view or absolute difference).
//
// Data flow: fetch `.f32` (or, when live, the streamed f32 capture of the
// output the inspector subscribed to) → slot.data (Float32Array) → tonemap
// into the slot's ImageData on an off-screen canvas (only when data or
// display options change) → drawImage onto the visible canvas with the
// view transform (every pan/zoom, cheap).
//
// This class holds the slots and the controls and wires the parts:
// inspector_loader.js (fetching and streaming, throttled by
// inspector_throttle.js), inspector_view.js (zoom, pan, selection),
// inspector_draw.js (the canvas) and inspector_readout.js (the text).
// B may also be the page's raster reference (path.js, through
// hooks.reference), which is not fetched; a compare has statistics, a
// display scale and masks (inspector_compare.js).

import { CompareTools, REFERENCE } from './inspector_compare.js';
import { tonemapSlot, draw } from './inspector_draw.js';
import { keyOf, Loader, parseKey } from './inspector_loader.js';
import { Readout } from './inspector_readout.js';
import { bindPointer, View } from './inspector_view.js';
import * as presets from './presets.js';
import * as tex from './texture.js';
import { $, el, errorText, formatMs } from './util.js';

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
   * @param {(pass: string, output: string) => object | null}
   *   hooks.outputInfo the output's `writes[]` entry of /api/passes (its
   *   meaning and depth projection pick its display preset)
   * @param {() => {slot?: object, label?: string, problem?: string}} hooks.reference
   *   the page's raster reference, a B that is not fetched
   * @param {(width: number, height: number) => {mask: Uint8Array | null, missing: string[]}} hooks.maskFor
   *   the chosen masks of a difference against the reference
   * @param {() => void} hooks.masksChanged the mask choice changed
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
    this.linearizeIn = $('linearize');
    this.liveIn = $('live');
    this.zoomEl = $('zoom-level');

    this.opts = tex.defaultOptions();
    // The output whose display preset `opts` holds, the preset as applied
    // (what the user's changes are measured against), and whether it was
    // guessed from the format before the pass list said the meaning.
    this.presetKey = null;
    this.applied = null;
    this.presetGuessed = false;
    this.target = null; // {pass, output}
    this.a = null; // slot: {key, pass, output, lastGood, data, width, height, frame, format, stats, canvas, image}
    this.b = null;
    this.diff = null;
    this.overlay = null; // {canvas, width, height, kind}
    this.error = null; // why A could not be loaded
    this.bError = null;
    this.captures = [];
    this.shownSize = null; // size of the last image shown, to keep the view
    this.needsRebuild = false;
    this.frameRequested = false;

    this.compareTools = new CompareTools(() => {
      this.hooks.masksChanged?.();
      this.needsRebuild = true;
      this.requestFrame();
    });
    this.compareStats = null; // statistics of A against B, when comparing
    this.view = new View();
    this.readout = new Readout();
    this.loader = new Loader(hooks, {
      wanted: () => (this.target ? { a: this.target, b: this.compareSpec() } : null),
      metaFor: (pass, output) => this.metaFor(pass, output),
      changed: () => this.loadingChanged(),
      landed: (result) => this.landed(result),
      streamed: (captures) => this.showStreamed(captures),
    });

    this.syncControls();
    this.bindControls();
    bindPointer(this.canvas, this.view, {
      size: () => this.cssSize(),
      splitShown: () => this.mode() === 'split' && !!this.b,
      inside: (p) => this.inside(p),
      setHover: (p) => this.setHover(p),
      selected: () => {
        this.onPin?.(this.view.pinned, this.a);
        this.refreshReadout();
        this.draw();
      },
      draw: () => this.draw(),
      fit: () => this.fit(),
    });
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
      this.view.pinned = null;
      this.a = null;
      this.b = null;
      this.diff = null;
      this.error = null;
      this.bError = null;
      this.presetKey = null;
      this.draw();
      this.describe();
      this.refreshReadout();
    }
    this.ensureOption(this.selA, keyOf(pass, output));
    this.selA.value = keyOf(pass, output);
    this.hooks.onTarget?.(pass, output);
    return this.load();
  }

  /** Fetches A (and B when comparing) and shows them; see Loader.load. */
  load() {
    return this.loader.load();
  }

  /** What B is: A's previous good version, or another output. */
  compareSpec() {
    const mode = this.selMode.value;
    if (mode === 'off' || !this.target) return null;
    const value = this.selB.value;
    if (value === REFERENCE) return null; // the page's own: see takeReference
    if (value === 'last_good' || !value) return { ...this.target, lastGood: true };
    const parsed = parseKey(value);
    return parsed ? { ...parsed, lastGood: false } : null;
  }

  metaFor(pass, output) {
    return this.captures.find((c) => c.pass === pass && c.output === output) || null;
  }

  loadingChanged() {
    this.root.classList.toggle('loading', this.loader.loading);
    this.showMessage();
  }

  /** The newest fetch settled: its results become A and B. */
  landed({ a: ra, b: rb, wanted }) {
    this.root.classList.remove('loading');
    const { pass, output } = wanted.a;
    const key = keyOf(pass, output);
    const bSpec = wanted.b;
    if (ra.status === 'fulfilled') {
      const meta = this.metaFor(pass, output);
      this.a = makeSlot(ra.value, { key, pass, output, lastGood: false, format: ra.value.format || meta?.format }, this.a);
      this.error = null;
      const size = `${this.a.width}x${this.a.height}`;
      if (size !== this.shownSize) this.view.auto = true;
      this.shownSize = size;
    } else {
      this.error = ra.reason;
      // A failed live refresh keeps the last image (the server may be
      // restarting); a failed new selection must not show the old one.
      if (this.a && this.a.key !== key) this.a = null;
    }
    if (rb?.status === 'fulfilled') {
      const bKey = bSpec.lastGood ? `${key}@last_good` : keyOf(bSpec.pass, bSpec.output);
      const bMeta = this.metaFor(bSpec.pass, bSpec.output);
      this.b = makeSlot(rb.value, { key: bKey, ...bSpec, format: rb.value.format || bMeta?.format }, this.b);
      this.bError = null;
    } else {
      this.b = null;
      this.bError = rb ? rb.reason : null;
    }
    this.usePreset();
    this.redisplay();
  }

  /**
   * A frame was rendered: refresh the inspected data when live. Streamed
   * captures refresh A (and B when it is another output) by themselves;
   * a fetch is needed only before the stream starts and for a last-good B.
   */
  onFrame() {
    if (!this.liveIn.checked || !this.target) return;
    this.loader.throttle.frame(!!this.compareSpec()?.lastGood);
  }

  /** The slot a streamed `pass/output` fills when live: 'a', 'b' or null. */
  streamSlot(key) {
    if (!this.liveIn.checked || !this.target) return null;
    if (key === keyOf(this.target.pass, this.target.output)) return 'a';
    const b = this.compareSpec();
    return b && !b.lastGood && key === keyOf(b.pass, b.output) ? 'b' : null;
  }

  /** A binary `capture` message; shown when it is of A or B, throttled. */
  onCapture(header, bytes) {
    if (this.streamSlot(keyOf(header.pass, header.output))) this.loader.stream(header, bytes);
  }

  /** Streamed captures are due: those still of A or B replace them. */
  showStreamed(captures) {
    for (const { header, loaded } of captures) {
      const key = keyOf(header.pass, header.output);
      const which = this.streamSlot(key);
      if (!which) continue;
      const info = { key, pass: header.pass, output: header.output, lastGood: false, format: header.format };
      if (which === 'a') {
        this.a = makeSlot(loaded, info, this.a);
        this.error = null;
      } else {
        this.b = makeSlot(loaded, info, this.b);
        this.bError = null;
      }
    }
    this.usePreset();
    this.redisplay();
  }

  /** Whether B is the page's raster reference (in a compare). */
  comparesReference() {
    return this.mode() !== 'off' && this.selB.value === REFERENCE;
  }

  /** B becomes the raster reference when it is chosen (unchanged if it is
   * the same image). */
  takeReference() {
    if (!this.comparesReference()) return;
    const ref = this.hooks.reference?.() ?? { problem: 'no raster reference in this page' };
    if (!ref.slot) {
      this.b = null;
      this.bError = new Error(ref.problem);
      return;
    }
    this.bError = null;
    if (this.b?.data === ref.slot.data) return;
    this.b = makeSlot(ref.slot, { key: ref.label, pass: 'raster reference', output: 'color', lastGood: false }, this.b);
  }

  /** The raster reference changed (path.js): shown anew when it is B. */
  referenceChanged() {
    this.relabelReference();
    if (this.comparesReference()) this.redisplay();
  }

  /** New data in A or B: retonemap, draw, update the message and readout. */
  redisplay() {
    this.takeReference();
    this.needsRebuild = true;
    this.flush();
    this.showMessage();
    this.refreshReadout();
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
    const signature = JSON.stringify([this.captures.map(label), aValue, aMetaNow?.last_good, this.referenceLabel()]);
    if (signature === this.optionsSignature) {
      this.describe();
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
    const bOptions = [el('option', { value: 'last_good' }, lastGoodText), el('option', { value: REFERENCE }, this.referenceLabel())];
    for (const c of this.captures) bOptions.push(el('option', { value: keyOf(c.pass, c.output) }, label(c)));
    this.selB.replaceChildren(...bOptions);
    if (bValue !== 'last_good') this.ensureOption(this.selB, bValue);
    this.selB.value = bValue;
    this.describe();
  }

  /** The B option of the raster reference: "raster reference · frame N". */
  referenceLabel() {
    return this.hooks.reference?.().label ?? 'raster reference (none yet)';
  }

  relabelReference() {
    const option = [...this.selB.options].find((o) => o.value === REFERENCE);
    if (option) option.textContent = this.referenceLabel();
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
    this.linearizeIn.checked = this.opts.linearize;
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
      this.remember();
      this.requestFrame();
    };
    this.selA.addEventListener('change', () => {
      const parsed = parseKey(this.selA.value);
      if (parsed) this.inspect(parsed.pass, parsed.output);
    });
    this.selMode.addEventListener('change', () => {
      this.root.dataset.compare = this.selMode.value;
      this.compareChanged();
    });
    this.selB.addEventListener('change', () => {
      if (this.selMode.value !== 'off') this.compareChanged();
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
      [this.linearizeIn, 'linearize'],
    ]) {
      input.addEventListener('change', () => {
        this.opts[field] = input.checked;
        changed();
      });
    }
    $('auto-fit').addEventListener('click', () => {
      this.autoFit();
      this.remember();
    });
    $('reset-range').addEventListener('click', () => {
      Object.assign(this.opts, { exposure: 0, min: 0, max: 1 });
      this.syncControls();
      changed();
    });
    $('refresh').addEventListener('click', () => this.load());
    $('fit').addEventListener('click', () => this.fit());
    $('zoom-1').addEventListener('click', () => this.actualSize());
    this.liveIn.addEventListener('change', () => {
      if (this.liveIn.checked) this.loader.throttle.requestFetch();
    });
  }

  /** The compare mode or B changed: B is fetched, or taken from the page. */
  compareChanged() {
    this.compareTools.setReference(this.selB.value === REFERENCE);
    this.b = null;
    this.bError = null;
    this.redisplay();
    return this.load();
  }

  /**
   * Compares `pass/output` with the raster reference as |A − B|, a heat
   * map at the 99th percentile scale, emitters masked: what the path
   * panel opens.
   */
  compareWithReference(pass, output) {
    this.ensureOption(this.selB, REFERENCE);
    this.selB.value = REFERENCE;
    this.selMode.value = 'diff';
    this.root.dataset.compare = 'diff';
    this.compareTools.set({ scale: 'p99', heat: true, emitters: true });
    this.compareTools.setReference(true);
    // Inspecting loads A, and B is taken from the page once A lands.
    return this.inspect(pass, output);
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
    const range = tex.finiteRange(this.shownData(slot), this.opts.channel, this.clearOf(slot));
    if (!range) {
      this.notice('auto-fit: no finite values in this channel');
      return null;
    }
    let { min, max } = range;
    if (presets.formatInfo(slot.format).integer) {
      min = Math.floor(min);
      max = Math.ceil(max);
    }
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

  // ---- display presets (presets.js) -----------------------------------

  /**
   * Shows a newly opened output by its preset: the one the user left on
   * it, else the automatic one for its format and meaning. Chosen again
   * once the pass list gives the meaning of an output first shown by a
   * guess from its format, unless the user changed it meanwhile.
   */
  usePreset() {
    const a = this.a;
    if (!a || a.lastGood) return;
    const output = this.hooks.outputInfo?.(a.pass, a.output) || null;
    if (this.presetKey === a.key && !(this.presetGuessed && output)) return;
    this.presetKey = a.key;
    this.presetGuessed = !output;
    const auto = presets.choosePreset({ format: a.format, meaning: output?.meaning, depth: output?.depth });
    const options = presets.channelOptions(auto.info);
    this.channelSel.replaceChildren(...options.map((o) => el('option', { value: o.value }, o.label)));
    this.linearizeIn.closest('label').hidden = !presets.canLinearize(output?.depth);
    for (const input of [this.minIn, this.maxIn]) input.step = auto.info.integer ? '1' : 'any';
    const stored = presets.loadPreset(localStorage, a.key);
    const usable = stored && options.some((o) => o.value === stored.channel) ? stored : null;
    Object.assign(this.opts, usable || auto.opts);
    this.syncControls();
    if (!usable && auto.fit) this.autoFit();
    this.applied = presets.pick(this.opts);
    this.root.dataset.meaning = auto.meaning;
  }

  /** Keeps the display options of the output shown, once the user made them differ from its preset. */
  remember() {
    if (!this.presetKey || !this.applied || presets.samePreset(this.opts, this.applied)) return;
    presets.savePreset(localStorage, this.presetKey, this.opts);
    this.applied = presets.pick(this.opts);
    this.presetGuessed = false;
  }

  /** A depth output's projection (`writes[].depth`), else null. */
  depthOf(slot) {
    const output = slot?.pass ? this.hooks.outputInfo?.(slot.pass, slot.output) : null;
    return output?.meaning === 'depth' ? output.depth || { near: null, far: null, reversed: false } : null;
  }

  /** The floats `slot` is shown from: depth as view distance when linearised. */
  shownData(slot) {
    const depth = this.opts.linearize ? this.depthOf(slot) : null;
    if (!presets.canLinearize(depth)) return slot.data;
    if (slot.linear?.depth !== depth) slot.linear = { depth, data: presets.linearizeDepth(slot.data, depth) };
    return slot.linear.data;
  }

  /** What auto-fit leaves out of `slot`: a depth output's clear value. */
  clearOf(slot) {
    const depth = this.depthOf(slot);
    return depth ? { src: slot.data, value: presets.depthClear(depth) } : null;
  }

  // ---- rendering --------------------------------------------------------

  /** A flush in the next animation frame: control changes come in bursts. */
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

  /** Tonemaps what the mode shows (computing the difference in diff mode). */
  rebuild() {
    const mode = this.mode();
    if (this.a && mode !== 'diff') tonemapSlot(this.a, this.opts, this.shownData(this.a));
    if (this.b && mode === 'split') tonemapSlot(this.b, this.opts, this.shownData(this.b));
    const mask = this.compareMask();
    if (this.a && this.b && mode === 'diff') {
      const d = tex.difference(this.a.data, this.a.width, this.a.height, this.b.data, this.b.width, this.b.height);
      this.diff = reuseCanvas({ key: 'diff', format: this.a.format, names: this.a.names, ...d }, this.diff);
      this.compareTools.showDiff(this.diff, this.opts, mask?.mask ?? null);
    } else {
      this.diff = null;
    }
    this.compareStats = this.a && this.b ? this.compareTools.showStats(this.a, this.b, mask) : this.compareTools.showStats(null);
    if (this.view.auto && this.a) this.fit();
    this.describe();
  }

  /** The chosen masks when B is the raster reference: {mask, missing} or null. */
  compareMask() {
    if (!this.a || !this.comparesReference() || !this.hooks.maskFor) return null;
    return this.hooks.maskFor(this.a.width, this.a.height);
  }

  /**
   * Lays a map over A (quad statistics): {width, height, rgba, kind,
   * values (the counts, read under the cursor)} or null.
   * Shown only without a compare, at A's scale, from A's top-left corner.
   */
  setOverlay(map) {
    if (!map) this.overlay = null;
    else {
      const canvas = document.createElement('canvas');
      canvas.width = map.width;
      canvas.height = map.height;
      canvas.getContext('2d').putImageData(new ImageData(map.rgba, map.width, map.height), 0, 0);
      this.overlay = { canvas, width: map.width, height: map.height, kind: map.kind, values: map.values };
    }
    this.refreshReadout();
    this.draw();
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
    if (this.view.auto && this.a) this.fit();
    else this.draw();
  }

  cssSize() {
    const dpr = window.devicePixelRatio || 1;
    return { w: this.canvas.width / dpr, h: this.canvas.height / dpr, dpr };
  }

  draw() {
    const size = this.cssSize();
    const { a, b, diff, overlay, view } = this;
    draw(this.ctx, size, { view, mode: this.mode(), a, b, diff, overlay });
    this.zoomEl.textContent = `${Math.round(view.scale * size.dpr * 100)}%`;
  }

  // ---- view -------------------------------------------------------------

  fit() {
    const slot = this.displayedSlot();
    if (!slot) return;
    const { w, h } = this.cssSize();
    this.view.fit(slot.width, slot.height, w, h);
    this.draw();
  }

  /** Zooms by `factor` about the centre of the view. */
  zoomBy(factor) {
    const { w, h } = this.cssSize();
    this.view.zoomAt(this.view.scale * factor, w / 2, h / 2);
    this.draw();
  }

  /** One image pixel per device pixel, about the centre. */
  actualSize() {
    const { w, h, dpr } = this.cssSize();
    this.view.zoomAt(1 / dpr, w / 2, h / 2);
    this.draw();
  }

  inside(p) {
    const s = this.a;
    return !!(s && p && p.x >= 0 && p.y >= 0 && p.x < s.width && p.y < s.height);
  }

  setHover(p) {
    const next = p && this.inside(p) ? p : null;
    const prev = this.view.hover;
    if (next === prev || (next && prev && next.x === prev.x && next.y === prev.y)) return;
    this.view.hover = next;
    this.refreshReadout();
    this.draw();
  }

  /** Centres (x, y) at a readable zoom and pins it. */
  goTo(x, y) {
    const { w, h } = this.cssSize();
    this.view.centreOn(x, y, w, h, 16);
    this.view.pinned = { x, y };
    this.onPin?.(this.view.pinned, this.a);
    this.refreshReadout();
    this.draw();
  }

  // ---- readout and messages ---------------------------------------------

  refreshReadout() {
    const { pinned, hover } = this.view;
    const depthOf = (slot) => this.depthOf(slot);
    this.readout.values({ mode: this.mode(), a: this.a, b: this.b, diff: this.diff, p: pinned || hover, pinned: !!pinned, depthOf });
    this.readout.overlayCount({ mode: this.mode(), overlay: this.overlay, p: pinned || hover });
  }

  describe() {
    const a = this.a;
    this.readout.describe(a, a && this.metaFor(a.pass, a.output), (x, y) => this.goTo(x, y));
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
      text = this.error.notCaptured
        ? `No capture of ${what} yet. The pass may be culled or failed, or it has not rendered yet.`
        : this.error.notFound
        ? `${what} is not an output of the frame graph (404).`
        : `Could not load ${what}: ${errorText(this.error)}`;
    } else if (!this.a && this.loader.waiting) {
      text = `Waiting for the server to capture ${this.loader.waiting}…`;
    } else if (!this.a && this.loader.loading) {
      text = 'Loading…';
    }
    m.textContent = text;
    m.className = kind;
    m.hidden = !text;

    const notes = [];
    if (this.error && this.a) notes.push(`refresh failed, showing the last data: ${errorText(this.error)}`);
    if (this.bError) {
      notes.push(
        this.bError.notCaptured && this.compareSpec()?.lastGood
          ? 'B: no previous good version of this output yet'
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
    this.view.pinned = null;
    this.view.hover = null;
    this.setHover(x === null || x === undefined ? null : { x, y });
    return this.valueAt(x, y);
  }

  snapshot() {
    const a = this.a;
    const live = this.loader.throttle.snapshot();
    const { scale, tx, ty, hover, pinned } = this.view;
    return {
      pass: this.target?.pass ?? null,
      output: this.target?.output ?? null,
      loaded: !!a,
      loading: live.loading,
      loads: live.fetches,
      streamedLoads: live.streamedLoads,
      throttle: live,
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
        bLabel: this.b?.key ?? null,
        loaded: !!this.b,
        error: this.bError ? errorText(this.bError) : null,
        stats: this.compareStats,
        ...this.compareTools.snapshot(),
      },
      options: { ...this.opts },
      view: { scale, tx, ty },
      hover,
      pinned,
      live: this.liveIn.checked,
      lastFetchMs: this.loader.throttle.lastDuration ? Number(formatMs(this.loader.throttle.lastDuration)) : null,
    };
  }
}

/** A slot: what was loaded, its statistics and the labels in `info`. */
function makeSlot(loaded, info, prev) {
  const slot = { ...info, ...loaded, stats: tex.computeStats(loaded.data, loaded.width, loaded.height) };
  // The names of the channels the format has: the readout shows only these.
  slot.names = presets.formatInfo(slot.format).names;
  return reuseCanvas(slot, prev);
}

/**
 * Gives `slot` the off-screen canvas and ImageData of `prev` when the size
 * is the same: live refresh would otherwise allocate megabytes per frame.
 */
function reuseCanvas(slot, prev) {
  if (prev && prev.width === slot.width && prev.height === slot.height && prev.canvas) {
    slot.canvas = prev.canvas;
    slot.image = prev.image;
  }
  return slot;
}
