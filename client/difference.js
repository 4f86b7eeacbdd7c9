// The numbers of a difference view, with no DOM so node can test them:
// per-pixel errors of an image against a reference, the masks that leave
// pixels out of them (background, emitters), their statistics (median, p95,
// mean relative error, RMSE), the scale a difference is shown with and its
// heat map, and the path tracer's samples per second and time to its
// target.
//
// Images are RGBA f32, row-major (the `.f32` capture layout); a mask is a
// Uint8Array with 1 where a pixel is left out.
//
// Used by inspector.js (statistics, scale and masks of its compare) and
// path.js (the path panel's figures). Tests: tests/client/difference.test.mjs.

/** Added to the reference under the relative error, so that black pixels
 * do not divide by zero. */
export const RELATIVE_EPSILON = 0.01;

/** The quantiles the statistics give. */
const MEDIAN = 0.5;
const P95 = 0.95;

/**
 * The q-quantile of `sorted` (ascending) by nearest rank: the value at rank
 * ⌈q·n⌉, so that it is one of the values and a test can recompute it
 * exactly. NaN when empty.
 */
export function quantile(sorted, q) {
  if (!sorted.length) return NaN;
  return sorted[Math.min(sorted.length - 1, Math.max(0, Math.ceil(q * sorted.length) - 1))];
}

/**
 * A and B compared pixel by pixel over RGB, among the pixels finite in both
 * and not in `mask` (or all when null): per pixel, the absolute error is
 * the mean of |a − b| over RGB and the relative error the mean of
 * |a − b| / (|b| + RELATIVE_EPSILON), B being the reference.
 *
 * Returns `median` and `p95` of the per-pixel relative errors, `relative`
 * their mean, `rmse` the root mean square of a − b over the channels,
 * `pixels` how many pixels counted, `masked` how many the mask left out and
 * `nonFinite` how many more were left out for a NaN or Inf in either image.
 * Null when the sizes differ.
 */
export function compareStats(a, b, width, height, mask = null) {
  if (a.length !== width * height * 4 || b.length !== a.length || (mask && mask.length !== width * height)) return null;
  const n = width * height;
  const relative = new Float64Array(n);
  let count = 0;
  let masked = 0;
  let squares = 0;
  let sum = 0;
  for (let i = 0; i < n; i++) {
    if (mask && mask[i]) {
      masked++;
      continue;
    }
    let square = 0;
    let rel = 0;
    for (let c = 4 * i; c < 4 * i + 3; c++) {
      const d = Math.abs(a[c] - b[c]);
      square += d * d;
      rel += d / (Math.abs(b[c]) + RELATIVE_EPSILON);
    }
    if (!Number.isFinite(square) || !Number.isFinite(rel)) continue;
    squares += square;
    sum += rel / 3;
    relative[count++] = rel / 3;
  }
  const sorted = relative.subarray(0, count).sort();
  return {
    median: quantile(sorted, MEDIAN),
    p95: quantile(sorted, P95),
    relative: count ? sum / count : NaN,
    rmse: count ? Math.sqrt(squares / (3 * count)) : NaN,
    pixels: count,
    masked,
    nonFinite: n - masked - count,
  };
}

/**
 * The top of a difference's display scale: `{kind: 'percentile', value}`
 * is that percentile (0–100) of the per-pixel mean of |a − b| over RGB
 * among the unmasked finite pixels of `diff` (|A − B| as RGBA f32);
 * `{kind: 'fixed', value}` is the value itself. 0 when nothing counts.
 */
export function scaleTop(diff, width, height, scale, mask = null) {
  if (scale.kind === 'fixed') return scale.value;
  const n = width * height;
  const values = new Float64Array(n);
  let count = 0;
  for (let i = 0; i < n; i++) {
    if (mask && mask[i]) continue;
    const v = (diff[4 * i] + diff[4 * i + 1] + diff[4 * i + 2]) / 3;
    if (Number.isFinite(v)) values[count++] = v;
  }
  const top = quantile(values.subarray(0, count).sort(), scale.value / 100);
  return Number.isNaN(top) ? 0 : top;
}

/**
 * Background: the pixels where the raster G-buffer's normal output
 * (`gbuffer/normal`, w = 1 where geometry was drawn, 0 where cleared) says
 * no geometry was drawn.
 */
export function backgroundMask(gbufferNormal, width, height) {
  const mask = new Uint8Array(width * height);
  for (let i = 0; i < mask.length; i++) mask[i] = gbufferNormal[4 * i + 3] > 0 ? 0 : 1;
  return mask;
}

/**
 * Emitters: the pixels where some camera ray of the path tracer saw an
 * emitter (a rect light) directly, which `path_trace/albedo` holds in its
 * alpha as the fraction of samples that did.
 */
export function emitterMask(pathAlbedo, width, height) {
  const mask = new Uint8Array(width * height);
  for (let i = 0; i < mask.length; i++) mask[i] = pathAlbedo[4 * i + 3] > 0 ? 1 : 0;
  return mask;
}

/** The union of masks of one size (null entries skipped); null when none. */
export function unionMask(masks) {
  const present = masks.filter(Boolean);
  if (!present.length) return null;
  const out = new Uint8Array(present[0].length);
  for (const m of present) for (let i = 0; i < out.length; i++) out[i] |= m[i];
  return out;
}

/** The heat map's colours (inferno), from no difference to the scale's
 * top and beyond: none of them is the masked grey or the NaN magenta. */
export const RAMP = [
  [0, 0, 4],
  [87, 16, 110],
  [188, 55, 84],
  [249, 142, 9],
  [252, 255, 164],
];
/** Pixels non-finite in either image, as the inspector's NaN overlay. */
const NON_FINITE = [255, 0, 255];

/**
 * Writes into display RGBA8 `out` the per-pixel mean over RGB of `diff`
 * (|A − B| as RGBA f32) on RAMP from 0 to `top`; `top` and above share
 * its last colour, non-finite pixels are magenta.
 */
export function heatMap(diff, top, out) {
  const last = RAMP.length - 1;
  for (let i = 0; 4 * i < diff.length; i++) {
    const v = (diff[4 * i] + diff[4 * i + 1] + diff[4 * i + 2]) / 3;
    let color = NON_FINITE;
    if (Number.isFinite(v)) {
      const x = top > 0 ? Math.min(v / top, 1) * last : 0;
      const k = Math.min(Math.floor(x), last - 1);
      const f = x - k;
      color = RAMP[k].map((a, c) => a + f * (RAMP[k + 1][c] - a));
    }
    out.set(color, 4 * i);
    out[4 * i + 3] = 255;
  }
  return out;
}

/** A CSS gradient of RAMP, for a legend. */
export const RAMP_CSS = `linear-gradient(90deg, ${RAMP.map((c, i) => `rgb(${c.join(',')}) ${(100 * i) / (RAMP.length - 1)}%`).join(', ')})`;

/** The grey masked pixels are painted with in a displayed difference. */
export const MASKED_RGB = [48, 48, 48];

/** Paints the masked pixels of display RGBA8 `rgba` in MASKED_RGB. */
export function paintMask(rgba, mask) {
  for (let i = 0; i < mask.length; i++) {
    if (!mask[i]) continue;
    rgba.set(MASKED_RGB, 4 * i);
    rgba[4 * i + 3] = 255;
  }
}

/**
 * Samples per second of a progressive renderer: the samples accumulated
 * over the wall time between the first and the newest sample-count change
 * of the current accumulation. A count lower than the last one starts a
 * new accumulation.
 */
export class SampleRate {
  constructor() {
    this.reset();
  }

  reset() {
    this.first = null; // {samples, ms} at the first change seen
    this.last = null; // {samples, ms} at the newest count or change
  }

  /** A sample count seen at wall time `ms`; null (none yet) resets. */
  observe(samples, ms) {
    if (samples === null || (this.last && samples < this.last.samples)) {
      this.reset();
      if (samples === null) return;
    }
    if (this.last && samples === this.last.samples) return;
    // The first count seen may have been reached long before the page saw
    // it: the rate is measured from the first change on.
    if (this.last && !this.first) this.first = { samples, ms };
    this.last = { samples, ms };
  }

  /** Samples per second, or null before two changes. */
  rate() {
    if (!this.first || this.last.ms <= this.first.ms) return null;
    return ((this.last.samples - this.first.samples) * 1000) / (this.last.ms - this.first.ms);
  }

  /** Seconds until `target` samples at the measured rate: 0 once there,
   * null when unknown. */
  secondsTo(target) {
    if (this.last && this.last.samples >= target) return 0;
    const rate = this.rate();
    return rate ? (target - this.last.samples) / rate : null;
  }
}

/** A figure as the page shows it: three significant digits. */
export const fmt = (v) => Number(v).toPrecision(3);

/** A relative error as a percentage, three significant digits. */
export const percent = (v) => `${fmt(100 * v)} %`;

/** The statistics as the page writes them (the path panel and the
 * inspector), with the chosen masks the page could not make. */
export function statsText(d, missing = []) {
  if (!d.pixels) return `no pixel left to compare (${d.masked} masked, ${d.nonFinite} non-finite)`;
  const parts = [`median ${percent(d.median)}`, `p95 ${percent(d.p95)}`, `mean relative ${percent(d.relative)}`, `RMSE ${fmt(d.rmse)}`];
  parts.push(`${d.pixels} px${d.masked ? `, ${d.masked} masked` : ''}${d.nonFinite ? `, ${d.nonFinite} non-finite left out` : ''}`);
  for (const m of missing) parts.push(`no ${m} mask yet`);
  return parts.join(' · ');
}

/** What the statistics are, for a title. */
export function statsTitle() {
  return `per pixel: relative error = mean over RGB of |A − B| / (|B| + ${RELATIVE_EPSILON}), B the reference; median and p95 by nearest rank, over the unmasked pixels finite in both; RMSE over their RGB channels`;
}

/** A duration for the page: "45 s", "3 min 20 s", "2 h 5 min". */
export function formatDuration(seconds) {
  if (seconds === null || !Number.isFinite(seconds)) return '—';
  const s = Math.round(seconds);
  if (s < 60) return `${s} s`;
  if (s < 3600) return `${Math.floor(s / 60)} min ${s % 60} s`;
  return `${Math.floor(s / 3600)} h ${Math.floor((s % 3600) / 60)} min`;
}
