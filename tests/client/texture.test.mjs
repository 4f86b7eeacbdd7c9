// The inspector's pixel math: float RGBA in, display RGBA8 out.
import assert from 'node:assert/strict';
import { test } from 'node:test';

import * as tex from '../../client/texture.js';

const image = (...pixels) => new Float32Array(pixels.flat());
const shown = (src, opts) => Array.from(tex.tonemap(src, src.length / 4, 1, { ...tex.defaultOptions(), ...opts }, new Uint8ClampedArray(src.length)));

test('tonemap maps [min, max] to [0, 255], after exposure, sRGB-encoded when asked', () => {
  const src = image([0, 0.5, 1, 0.25], [2, -1, 0.25, 1]);
  assert.deepEqual(shown(src, { srgb: false }), [0, 128, 255, 255, 255, 0, 64, 255], 'linear, clamped, opaque');
  assert.deepEqual(shown(src, { srgb: true }).slice(0, 3), [0, 188, 255], 'sRGB of 0.5 is 188');
  assert.deepEqual(shown(src, { srgb: false, exposure: 1 }).slice(0, 3), [0, 255, 255], '+1 EV doubles');
  assert.deepEqual(shown(src, { srgb: false, min: 0.5, max: 1 }).slice(0, 3), [0, 0, 255], 'the range window');
});

test('tonemap shows one channel or luminance as grey', () => {
  const src = image([0.25, 0.5, 1, 0.75]);
  assert.deepEqual(shown(src, { srgb: false, channel: 'g' }), [128, 128, 128, 255]);
  assert.deepEqual(shown(src, { srgb: false, channel: 'a' }), [191, 191, 191, 255]);
  const y = Math.round(tex.luminance(0.25, 0.5, 1) * 255);
  assert.deepEqual(shown(src, { srgb: false, channel: 'luminance' }), [y, y, y, 255]);
});

test('tonemap paints NaN, Inf and negatives in their overlay colours, NaN first', () => {
  const src = image([NaN, -1, 0, 1], [Infinity, 0, 0, 1], [-Infinity, 0, 0, 1], [-0.5, 0, 0, 1], [0, 0, 0, NaN]);
  const out = shown(src, { overlayNeg: true });
  const px = (i) => out.slice(4 * i, 4 * i + 3);
  assert.deepEqual(px(0), tex.OVERLAY_COLORS.nan, 'NaN wins over a negative');
  assert.deepEqual(px(1), tex.OVERLAY_COLORS.posInf);
  assert.deepEqual(px(2), tex.OVERLAY_COLORS.negInf);
  assert.deepEqual(px(3), tex.OVERLAY_COLORS.negative);
  assert.deepEqual(px(4), tex.OVERLAY_COLORS.nan, 'a NaN in alpha shows in the RGB view');
  const off = shown(src, { overlayNan: false, overlayInf: false, overlayNeg: false, srgb: false });
  assert.deepEqual(off.slice(0, 8), [0, 0, 0, 255, 255, 0, 0, 255], 'without overlays NaN is black and Inf clamps');
});

test('finiteRange skips NaN and Inf, per channel mode', () => {
  const src = image([1, NaN, -2, 100], [Infinity, 3, 0.5, -100]);
  assert.deepEqual(tex.finiteRange(src, 'rgb'), { min: -2, max: 3 }, 'RGB ignores alpha');
  assert.deepEqual(tex.finiteRange(src, 'a'), { min: -100, max: 100 });
  assert.deepEqual(tex.finiteRange(src, 'r'), { min: 1, max: 1 });
  assert.equal(tex.finiteRange(image([NaN, 0, 0, 0]), 'r'), null, 'no finite value');
  const lum = image([1, 1, 1, 0], [NaN, 0, 0, 0], [0, Infinity, 0, 0], [0.5, 0, 0, 0]);
  assert.deepEqual(tex.finiteRange(lum, 'luminance'), { min: tex.luminance(0.5, 0, 0), max: tex.luminance(1, 1, 1) });
});

test('computeStats counts bad channel values and finds the first bad pixel in row order', () => {
  // 2×2: (1, 0) holds an Inf, (0, 1) a NaN and a negative.
  const src = image([0.5, 1, 0, 1], [Infinity, 0, 0, 1], [NaN, -2, 3, 1], [0.25, 0, 0, 0]);
  assert.deepEqual(tex.computeStats(src, 2, 2), {
    nan: 1,
    inf: 1,
    negative: 1,
    min: [0.25, -2, 0, 0],
    max: [0.5, 1, 3, 1],
    first_nan: [1, 0],
  });
  assert.equal(tex.computeStats(image([0, 0, 0, 0]), 1, 1).first_nan, null);
});

test('difference is |A − B| over the overlap, keeping NaN', () => {
  const a = image([1, 2, 3, 4], [5, 6, 7, 8], [0, 0, 0, 0], [NaN, 0, 0, 0]); // 2×2
  const b = image([2, 2, 2, 2], [0, 0, 0, 0], [9, 9, 9, 9]); // 3×1
  const d = tex.difference(a, 2, 2, b, 3, 1);
  assert.equal(d.width, 2);
  assert.equal(d.height, 1);
  assert.deepEqual(Array.from(d.data), [1, 0, 1, 2, 5, 6, 7, 8]);
  const wide = tex.difference(b, 3, 1, a, 2, 2);
  assert.deepEqual([wide.width, wide.height, Array.from(wide.data)], [2, 1, Array.from(d.data)], 'the overlap either way round');
  assert.equal(Number.isNaN(tex.difference(a, 2, 2, a, 2, 2).data[12]), true);
});

test('pixel reads RGBA at (x, y), null outside or off the grid', () => {
  const src = image([1, 2, 3, 4], [5, 6, 7, 8]);
  assert.deepEqual(tex.pixel(src, 2, 1, 1, 0), [5, 6, 7, 8]);
  for (const [x, y] of [
    [2, 0],
    [0, 1],
    [-1, 0],
    [0.5, 0],
  ])
    assert.equal(tex.pixel(src, 2, 1, x, y), null, `(${x}, ${y})`);
});

test('formatF32 prints the shortest decimal that reads back as the same float32', () => {
  assert.equal(tex.formatF32(Math.fround(0.1)), '0.1');
  assert.equal(tex.formatF32(Math.fround(1 / 3)), '0.33333334');
  assert.equal(tex.formatF32(Math.fround(16777217)), '16777216');
  assert.equal(tex.formatF32(-0), '-0');
  assert.equal(tex.formatF32(NaN), 'NaN');
  assert.equal(tex.formatF32(-Infinity), '-Inf');
  for (const v of [Math.fround(0.1), Math.fround(1e-38), Math.fround(3.4e38), Math.fround(-123.456)]) {
    assert.equal(Math.fround(Number(tex.formatF32(v))), v, `${v} round-trips`);
  }
});

test('f32Bits is the float32 bit pattern', () => {
  assert.equal(tex.f32Bits(1), '0x3f800000');
  assert.equal(tex.f32Bits(-2), '0xc0000000');
  assert.equal(tex.f32Bits(0), '0x00000000');
  assert.equal(tex.f32Bits(Infinity), '0x7f800000');
});
