// Display presets: how the inspector first shows an output, chosen by its
// format (which channels it has, float or integer) and by the meaning its
// pass declares (`writes[].meaning` of /api/passes: color, normal, depth,
// data, id; PROTOCOL.md), and remembered per output in localStorage once
// the user changes one. The choice per meaning is the table in
// presets.json, which `loupe view` compiles in too:
//
//   color   sRGB on, range 0…1
//   normal  range −1…1 (shows n·0.5+0.5), sRGB off
//   depth   one grey channel, linearised with the camera's near/far when
//           `writes[].depth` gives them, fitted without the clear value
//   data/id sRGB off, fitted to the values
//   integer formats: sRGB off, fitted to whole numbers
//
// No DOM here (storage is passed in), so node tests cover the choice
// (tests/client/presets.test.mjs); the browser test is
// tests/e2e/browser/presets.rs. Its hooks: #inspector[data-meaning] (the
// meaning the open output is shown by), #linearize (the linear depth
// toggle, hidden unless the output's planes are known), #channel's
// options (the format's channels), the readout's .ch-name spans and
// `window.loupe.state.inspector.options` (the preset applied).

import { CHANNELS } from './texture.js';
import TABLE from './presets.json' with { type: 'json' };

/** The display options a preset sets; the overlays stay the user's. */
const PRESET_FIELDS = ['channel', 'exposure', 'min', 'max', 'srgb', 'linearize'];

const STORAGE_PREFIX = 'loupe.preset.';

/**
 * What a wgpu format name (`Rgba16Float`, `Depth32Float`, `R32Uint`) says
 * about a capture: the names of the channels it has, in capture order
 * (the `.f32` capture always holds four, filling the rest), whether they
 * hold integers, and whether it is a depth format. An unknown or missing
 * format is taken as four float channels, as the capture holds.
 */
export function formatInfo(format) {
  const f = typeof format === 'string' ? format : '';
  if (/^(Depth|Stencil)/.test(f)) return { names: ['depth'], integer: false, depth: true };
  const integer = /[US]int/.test(f);
  let names = ['R', 'G', 'B', 'A'];
  // Packed formats first: their names start like the plain ones.
  if (/^(Rg11b10|Rgb9e5)/.test(f)) names = ['R', 'G', 'B'];
  else if (/^(Rgba|Bgra|Rgb10a2)/.test(f)) names = ['R', 'G', 'B', 'A'];
  else if (/^Rg\d/.test(f)) names = ['R', 'G'];
  else if (/^R\d/.test(f)) names = ['R'];
  return { names, integer, depth: false };
}

/**
 * The channel select's options for a format: only the channels it has,
 * the composite view first when there are several. Values are the
 * tonemapper's channel modes (texture.js CHANNELS).
 */
export function channelOptions(info) {
  const { names } = info;
  if (info.depth) return [{ value: 'r', label: 'depth' }];
  const singles = names.map((n) => ({ value: n.toLowerCase(), label: n }));
  if (names.length === 1) return singles;
  const composite = [{ value: 'rgb', label: names.slice(0, 3).join('') }];
  const lum = names.length >= 3 ? [{ value: 'luminance', label: 'luminance' }] : [];
  return [...composite, ...singles, ...lum];
}

/** The meaning to show an output by: the declared one, else a depth format's. */
function meaningOf(declared, info) {
  if (typeof declared === 'string' && declared) return declared;
  return info.depth ? 'depth' : 'color';
}

/** Whether depth can be linearised: the projection's planes are known. */
export function canLinearize(depth) {
  return !!depth && Number.isFinite(depth.near) && Number.isFinite(depth.far) && depth.far > depth.near && depth.near > 0;
}

/**
 * The automatic preset of an output: display options (PRESET_FIELDS) and
 * whether to fit the range to the data once it is loaded.
 * @param {{format?: string, meaning?: string, depth?: {near: number|null, far: number|null, reversed: boolean}|null}} output
 */
export function choosePreset({ format, meaning, depth } = {}) {
  const info = formatInfo(format);
  const kind = meaningOf(meaning, info);
  const p = TABLE.meanings[kind] ?? TABLE.meanings[TABLE.unknown_meaning];
  const opts = {
    channel: p.channel ?? channelOptions(info)[0].value,
    exposure: 0,
    min: p.min,
    max: p.max,
    srgb: p.srgb,
    linearize: p.linearize && canLinearize(depth),
  };
  let fit = p.fit;
  if (info.integer) {
    opts.srgb = TABLE.integer.srgb;
    fit = TABLE.integer.fit;
  }
  return { opts, fit, meaning: kind, info };
}

/** The false-colour map (presets.json): RGB 0…255 of `t` in 0…1 into `out`. */
export function viridis(t, out) {
  const c = TABLE.viridis;
  for (let k = 0; k < 3; k++) {
    let v = 0;
    for (let p = c.length - 1; p >= 0; p--) v = v * t + c[p][k];
    out[k] = Math.round(v * 255);
  }
}

/** View distance of depth `d` through a perspective projection. */
export function linearDepth(d, { near, far, reversed }) {
  return reversed ? (near * far) / (near + d * (far - near)) : (near * far) / (far - d * (far - near));
}

/** What a depth target is cleared to: no surface covered the pixel. */
export function depthClear(depth) {
  return depth?.reversed ? 0 : 1;
}

/** A copy of RGBA floats with the depth (R) turned into view distance. */
export function linearizeDepth(src, depth) {
  const out = new Float32Array(src);
  for (let i = 0; i < out.length; i += 4) out[i] = linearDepth(out[i], depth);
  return out;
}

/** The preset stored for `key` (`pass/output`), or null; invalid entries are ignored. */
export function loadPreset(storage, key) {
  let stored;
  try {
    stored = JSON.parse(storage?.getItem(STORAGE_PREFIX + key) ?? 'null');
  } catch {
    return null;
  }
  if (!stored || typeof stored !== 'object') return null;
  const ok =
    CHANNELS.includes(stored.channel) &&
    ['exposure', 'min', 'max'].every((k) => Number.isFinite(stored[k])) &&
    typeof stored.srgb === 'boolean' &&
    typeof stored.linearize === 'boolean';
  return ok ? pick(stored) : null;
}

/** Stores the preset fields of `opts` for `key`; storage errors (quota, privacy mode) are not fatal. */
export function savePreset(storage, key, opts) {
  try {
    storage?.setItem(STORAGE_PREFIX + key, JSON.stringify(pick(opts)));
  } catch {
    // A preset that cannot be stored is only forgotten.
  }
}

/** The preset fields of `opts`. */
export function pick(opts) {
  return Object.fromEntries(PRESET_FIELDS.map((k) => [k, opts[k]]));
}

/** Whether two sets of options show an output the same way. */
export function samePreset(a, b) {
  return PRESET_FIELDS.every((k) => a[k] === b[k]);
}
