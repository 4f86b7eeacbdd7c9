// The inspector's compare tools: the display scale of |A − B| (the
// toolbar's min/max range, a percentile of the differences, or a fixed
// value, the value in use shown), a heat map of it (the mean over RGB on a
// colour ramp, with its legend), the masks that leave the background or
// the emitters out when B is the page's raster reference, and the
// statistics of A against B (median, p95, mean relative error, RMSE) in
// the status line. The numbers are difference.js's.
//
// Test hooks: #diff-scale (range | p99 | p95 | fixed), #diff-scale-value
// (the top of the scale in use), #diff-heat, #diff-legend, #mask-emitters, #mask-background,
// #compare-stats[data-median][data-p95][data-relative][data-rmse]
// [data-pixels][data-masked].

import { compareStats, fmt, heatMap, paintMask, RAMP_CSS, scaleTop, statsText, statsTitle } from './difference.js';
import { tonemapSlot } from './inspector_draw.js';
import { $, el } from './util.js';

/** The B option of the page's raster reference. */
export const REFERENCE = 'raster_reference';

/** The percentile each scale choice takes. */
const PERCENTILES = { p99: 99, p95: 95 };

export class CompareTools {
  /** @param {() => void} changed a scale or mask choice changed */
  constructor(changed) {
    this.scaleSel = $('diff-scale');
    this.scaleIn = $('diff-scale-value');
    this.heatIn = $('diff-heat');
    this.legend = $('diff-legend');
    this.maskIns = { emitters: $('mask-emitters'), background: $('mask-background') };
    this.statsEl = $('compare-stats');
    this.top = null; // the top of the scale in use, null with the range
    this.scaleSel.addEventListener('change', () => {
      this.showScaleInput();
      changed();
    });
    this.scaleIn.addEventListener('input', () => {
      const ok = this.fixedValue() !== null;
      this.scaleIn.classList.toggle('invalid', !ok);
      if (ok) changed();
    });
    for (const input of [...Object.values(this.maskIns), this.heatIn]) input.addEventListener('change', changed);
    this.showScaleInput();
  }

  /** Sets the scale ('range' | 'p99' | 'p95' | 'fixed'), heat map and masks given. */
  set({ scale, heat, emitters, background }) {
    if (scale) this.scaleSel.value = scale;
    if (heat !== undefined) this.heatIn.checked = heat;
    if (emitters !== undefined) this.maskIns.emitters.checked = emitters;
    if (background !== undefined) this.maskIns.background.checked = background;
    this.showScaleInput();
  }

  /** Masks apply to a compare with the raster reference only. */
  setReference(on) {
    for (const input of Object.values(this.maskIns)) input.disabled = !on;
  }

  /** Which masks are chosen, whatever B is (the path panel uses them too). */
  maskChoice() {
    return { emitters: this.maskIns.emitters.checked, background: this.maskIns.background.checked };
  }

  showScaleInput() {
    const fixed = this.scaleSel.value === 'fixed';
    this.scaleIn.readOnly = !fixed;
    this.scaleIn.hidden = this.scaleSel.value === 'range';
  }

  fixedValue() {
    const v = Number(this.scaleIn.value);
    return this.scaleIn.value.trim() !== '' && Number.isFinite(v) && v > 0 ? v : null;
  }

  /**
   * Tonemaps |A − B| into its canvas: from 0 to the scale's top (or with
   * the toolbar's range), on the heat ramp when chosen, the masked pixels
   * in grey.
   */
  showDiff(diff, opts, mask) {
    const choice = this.scaleSel.value;
    const m = mask && mask.length === diff.width * diff.height ? mask : null;
    if (choice === 'range') {
      this.top = null;
      tonemapSlot(diff, opts);
    } else {
      const scale = choice === 'fixed' ? { kind: 'fixed', value: this.fixedValue() ?? 1 } : { kind: 'percentile', value: PERCENTILES[choice] };
      this.top = scaleTop(diff.data, diff.width, diff.height, scale, m);
      if (choice !== 'fixed') this.scaleIn.value = String(Number(this.top.toPrecision(4)));
      // A zero top (no difference at all) shows black rather than dividing by zero.
      tonemapSlot(diff, { ...opts, exposure: 0, min: 0, max: this.top > 0 ? this.top : 1 });
    }
    const heatTop = this.top ?? opts.max;
    if (this.heatIn.checked) heatMap(diff.data, heatTop, diff.image.data);
    this.legend.hidden = !this.heatIn.checked;
    this.legend.replaceChildren(
      el('span', { class: 'num' }, '0'),
      el('i', { class: 'ramp', style: `background: ${RAMP_CSS}` }),
      el('span', { class: 'num' }, fmt(heatTop)),
    );
    this.legend.title = '|A − B|, the mean over RGB; larger differences share the top colour, magenta is not finite';
    this.scaleSel.title = this.top === null ? 'the toolbar min/max range' : `0 … ${this.top}: larger differences share the top colour`;
    if (m) paintMask(diff.image.data, m);
    if (m || this.heatIn.checked) diff.canvas.getContext('2d').putImageData(diff.image, 0, 0);
  }

  /**
   * The statistics of A against B (B the reference) in the status line;
   * `mask` is {mask, missing} or null, a == null clears. Returns them.
   */
  showStats(a, b, mask) {
    const el = this.statsEl;
    for (const k of ['median', 'p95', 'relative', 'rmse', 'pixels', 'masked']) delete el.dataset[k];
    el.title = statsTitle();
    if (!a) {
      el.textContent = '';
      return null;
    }
    const d = compareStats(a.data, b.data, a.width, a.height, mask?.mask ?? null);
    if (!d) {
      el.textContent = `no statistics: A is ${a.width}×${a.height}, B ${b.width}×${b.height}`;
      return null;
    }
    el.textContent = statsText(d, mask?.missing ?? []);
    Object.assign(el.dataset, { median: d.median, p95: d.p95, relative: d.relative, rmse: d.rmse, pixels: d.pixels, masked: d.masked });
    return d;
  }

  snapshot() {
    return { scale: this.scaleSel.value, scaleTop: this.top, heat: this.heatIn.checked, masks: this.maskChoice() };
  }
}
