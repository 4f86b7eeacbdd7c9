// Pixel math for the inspector: float RGBA in, display RGBA8 out. No DOM
// here, so it can be exercised from node.
//
// Data layout everywhere: Float32Array, RGBA interleaved, row-major, top
// row first (the `.f32` capture format).

export const CHANNELS = ['rgb', 'r', 'g', 'b', 'a', 'luminance'];

/** Overlay colours, RGB. Chosen to be distinct from each other and from
 * anything a tonemapped image usually contains. */
export const OVERLAY_COLORS = {
  nan: [255, 0, 255], // magenta
  posInf: [255, 255, 0], // yellow
  negInf: [0, 255, 255], // cyan
  negative: [40, 90, 255], // blue
};

// Classification codes, ordered by priority: a pixel with a NaN in one
// channel and a negative in another shows as NaN.
const NONE = 0;
const NAN = 1;
const POS_INF = 2;
const NEG_INF = 3;
const NEGATIVE = 4;

function classify(v) {
  if (v !== v) return NAN;
  if (v === Infinity) return POS_INF;
  if (v === -Infinity) return NEG_INF;
  if (v < 0) return NEGATIVE;
  return NONE;
}

function worse(a, b) {
  if (a === NONE) return b;
  if (b === NONE) return a;
  return a < b ? a : b;
}

// Display encoding through a lookup table: a pow() per channel per pixel
// is the slowest part of tonemapping a large capture.
const LUT_SIZE = 4096;
function buildLut(srgb) {
  const lut = new Uint8ClampedArray(LUT_SIZE + 1);
  for (let i = 0; i <= LUT_SIZE; i++) {
    const x = i / LUT_SIZE;
    const y = srgb ? (x <= 0.0031308 ? 12.92 * x : 1.055 * Math.pow(x, 1 / 2.4) - 0.055) : x;
    lut[i] = Math.round(y * 255);
  }
  return lut;
}
const SRGB_LUT = buildLut(true);
const LINEAR_LUT = buildLut(false);

/** Rec. 709 luminance of linear RGB. */
export function luminance(r, g, b) {
  return 0.2126 * r + 0.7152 * g + 0.0722 * b;
}

/**
 * Default display options: linear [0,1] → sRGB, NaN/Inf overlays on,
 * negative overlay off (negatives are legitimate in normals or velocity).
 */
export function defaultOptions() {
  return {
    channel: 'rgb',
    exposure: 0,
    min: 0,
    max: 1,
    srgb: true,
    overlayNan: true,
    overlayInf: true,
    overlayNeg: false,
    // Depth shown as view distance (presets.js); the tonemapper itself
    // never reads it.
    linearize: false,
  };
}

/**
 * Maps float RGBA to display RGBA8.
 *
 * value' = (value · 2^exposure − min) / (max − min), clamped to [0,1], then
 * sRGB-encoded when `srgb` (captures are linear). With a single channel or
 * luminance the result is grey. NaN/Inf/negative pixels are painted in
 * their overlay colours when enabled, otherwise NaN shows black and ±Inf
 * clamp like any large value.
 *
 * `out` is a Uint8ClampedArray of width·height·4 (e.g. ImageData.data).
 */
export function tonemap(src, width, height, opts, out) {
  const n = width * height * 4;
  const scale = Math.pow(2, opts.exposure || 0);
  let span = opts.max - opts.min;
  if (!Number.isFinite(span) || span === 0) span = span === 0 ? 1e-30 : 1;
  // t = (v·scale − min) / span, pre-multiplied into LUT units.
  const k = (scale / span) * LUT_SIZE;
  const offset = (-opts.min / span) * LUT_SIZE + 0.5;
  const lut = opts.srgb ? SRGB_LUT : LINEAR_LUT;
  const mode = CHANNELS.indexOf(opts.channel);
  const ov = [
    null,
    opts.overlayNan ? OVERLAY_COLORS.nan : null,
    opts.overlayInf ? OVERLAY_COLORS.posInf : null,
    opts.overlayInf ? OVERLAY_COLORS.negInf : null,
    opts.overlayNeg ? OVERLAY_COLORS.negative : null,
  ];
  // Index into the LUT. `t > 0` is false for NaN, so NaN maps to 0
  // (black); the clamp handles ±Inf.
  const idx = (v) => {
    const t = v * k + offset;
    return t > 0 ? (t < LUT_SIZE ? t | 0 : LUT_SIZE) : 0;
  };
  const paint = (i, cls) => {
    const color = ov[cls];
    if (!color) return false;
    out[i] = color[0];
    out[i + 1] = color[1];
    out[i + 2] = color[2];
    out[i + 3] = 255;
    return true;
  };

  if (mode <= 0) {
    // RGB view: alpha is not displayed, but a NaN hiding in it is still a
    // bug worth seeing, so it takes part in the overlays.
    for (let i = 0; i < n; i += 4) {
      const r = src[i];
      const g = src[i + 1];
      const b = src[i + 2];
      const a = src[i + 3];
      // Fast path: every channel finite and non-negative (NaN fails >=).
      if (!(r >= 0 && g >= 0 && b >= 0 && a >= 0 && r < Infinity && g < Infinity && b < Infinity && a < Infinity)) {
        const cls = worse(worse(classify(r), classify(g)), worse(classify(b), classify(a)));
        if (paint(i, cls)) continue;
      }
      out[i] = lut[idx(r)];
      out[i + 1] = lut[idx(g)];
      out[i + 2] = lut[idx(b)];
      out[i + 3] = 255;
    }
    return out;
  }

  const lum = mode === 5;
  const c = mode - 1; // r g b a → 0..3
  for (let i = 0; i < n; i += 4) {
    let v;
    let cls = NONE;
    if (lum) {
      const r = src[i];
      const g = src[i + 1];
      const b = src[i + 2];
      v = luminance(r, g, b);
      if (!(r >= 0 && g >= 0 && b >= 0 && r < Infinity && g < Infinity && b < Infinity)) {
        cls = worse(worse(classify(r), classify(g)), classify(b));
      }
    } else {
      v = src[i + c];
      if (!(v >= 0 && v < Infinity)) cls = classify(v);
    }
    if (cls !== NONE && paint(i, cls)) continue;
    const y = lut[idx(v)];
    out[i] = y;
    out[i + 1] = y;
    out[i + 2] = y;
    out[i + 3] = 255;
  }
  return out;
}

/**
 * Min and max of the finite values a channel mode displays, for auto-fit.
 * Null when there is no finite value at all. With `ignore` ({src, value}),
 * pixels whose first channel in `ignore.src` is exactly `value` are left
 * out: a depth buffer's clear value, which no surface wrote.
 */
export function finiteRange(src, channel, ignore = null) {
  let min = Infinity;
  let max = -Infinity;
  const n = src.length;
  const c = { r: 0, g: 1, b: 2, a: 3 }[channel];
  const skip = ignore ? ignore.src : null;
  const skipped = ignore ? ignore.value : NaN;
  // `v > -Infinity && v < Infinity` holds exactly for finite v.
  if (c !== undefined || channel === 'luminance') {
    const lum = c === undefined;
    for (let i = 0; i < n; i += 4) {
      if (skip && skip[i] === skipped) continue;
      const v = lum ? luminance(src[i], src[i + 1], src[i + 2]) : src[i + c];
      if (v > -Infinity && v < Infinity) {
        if (v < min) min = v;
        if (v > max) max = v;
      }
    }
  } else {
    for (let i = 0; i < n; i += 4) {
      if (skip && skip[i] === skipped) continue;
      for (let k = i; k < i + 3; k++) {
        const v = src[k];
        if (v > -Infinity && v < Infinity) {
          if (v < min) min = v;
          if (v > max) max = v;
        }
      }
    }
  }
  return min <= max ? { min, max } : null;
}

/**
 * The server's ImageStats, computed here for whatever is loaded (including
 * last-good versions the capture list does not describe): NaN, Inf and
 * negative counts are of channel values; min/max are per channel over
 * finite values; `first_nan` is the first pixel, in row order, holding a
 * NaN or an Inf.
 */
export function computeStats(src, width, height) {
  let nan = 0;
  let inf = 0;
  let negative = 0;
  let firstBad = -1;
  const min = [Infinity, Infinity, Infinity, Infinity];
  const max = [-Infinity, -Infinity, -Infinity, -Infinity];
  let min0 = Infinity, min1 = Infinity, min2 = Infinity, min3 = Infinity;
  let max0 = -Infinity, max1 = -Infinity, max2 = -Infinity, max3 = -Infinity;
  const n = width * height * 4;
  for (let i = 0; i < n; i += 4) {
    const r = src[i];
    const g = src[i + 1];
    const b = src[i + 2];
    const a = src[i + 3];
    if (r >= 0 && g >= 0 && b >= 0 && a >= 0 && r < Infinity && g < Infinity && b < Infinity && a < Infinity) {
      // The common case, kept in locals: finite, non-negative pixels.
      if (r < min0) min0 = r;
      if (r > max0) max0 = r;
      if (g < min1) min1 = g;
      if (g > max1) max1 = g;
      if (b < min2) min2 = b;
      if (b > max2) max2 = b;
      if (a < min3) min3 = a;
      if (a > max3) max3 = a;
      continue;
    }
    let bad = false;
    for (let c = 0; c < 4; c++) {
      const v = src[i + c];
      if (v !== v) {
        nan++;
        bad = true;
      } else if (v === Infinity || v === -Infinity) {
        inf++;
        bad = true;
      } else {
        if (v < 0) negative++;
        if (v < min[c]) min[c] = v;
        if (v > max[c]) max[c] = v;
      }
    }
    if (bad && firstBad < 0) firstBad = i / 4;
  }
  const lo = [min0, min1, min2, min3];
  const hi = [max0, max1, max2, max3];
  for (let c = 0; c < 4; c++) {
    min[c] = Math.min(min[c], lo[c]);
    max[c] = Math.max(max[c], hi[c]);
  }
  const first_nan = firstBad < 0 ? null : [firstBad % width, Math.floor(firstBad / width)];
  return { nan, inf, negative, min, max, first_nan };
}

/**
 * |A − B| per channel over the overlapping area. NaN stays NaN (either
 * side), so the overlays still point at broken pixels.
 */
export function difference(a, aw, ah, b, bw, bh) {
  const width = Math.min(aw, bw);
  const height = Math.min(ah, bh);
  const data = new Float32Array(width * height * 4);
  for (let y = 0; y < height; y++) {
    let ai = y * aw * 4;
    let bi = y * bw * 4;
    let oi = y * width * 4;
    for (let x = 0; x < width * 4; x++) data[oi++] = Math.abs(a[ai++] - b[bi++]);
  }
  return { data, width, height };
}

/** RGBA at (x, y) as numbers, or null outside the image. */
export function pixel(src, width, height, x, y) {
  if (!src || !Number.isInteger(x) || !Number.isInteger(y)) return null;
  if (x < 0 || y < 0 || x >= width || y >= height) return null;
  const i = (y * width + x) * 4;
  return [src[i], src[i + 1], src[i + 2], src[i + 3]];
}

/**
 * Shortest decimal that reads back as exactly this float32 — "full
 * precision" without the noise of printing the widened double
 * (0.1f32 prints as 0.1, not 0.10000000149011612).
 */
export function formatF32(v) {
  if (v !== v) return 'NaN';
  if (v === Infinity) return '+Inf';
  if (v === -Infinity) return '-Inf';
  if (v === 0) return Object.is(v, -0) ? '-0' : '0';
  for (let p = 1; p <= 9; p++) {
    const s = v.toPrecision(p);
    if (Math.fround(Number(s)) === v) return String(Number(s));
  }
  return String(v);
}

/** The bit pattern of a float32, e.g. 0x3f800000 for 1.0. */
export function f32Bits(v) {
  const view = new DataView(new ArrayBuffer(4));
  view.setFloat32(0, v, true);
  return '0x' + view.getUint32(0, true).toString(16).padStart(8, '0');
}
