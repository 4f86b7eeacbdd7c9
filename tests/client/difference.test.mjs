// The numbers of the difference view (client/difference.js): statistics
// over the unmasked pixels, the masks, the display scale, samples per
// second and the time to the target.
import assert from 'node:assert/strict';
import { test } from 'node:test';

import {
  backgroundMask,
  compareStats,
  emitterMask,
  formatDuration,
  heatMap,
  MASKED_RGB,
  paintMask,
  RAMP,
  quantile,
  RELATIVE_EPSILON,
  SampleRate,
  scaleTop,
  unionMask,
} from '../../client/difference.js';

/** RGBA f32 pixels from [r, g, b] triples (alpha 1). */
const image = (rgb) => new Float32Array(rgb.flatMap(([r, g, b]) => [r, g, b, 1]));

test('quantiles are by nearest rank, one of the values', () => {
  const sorted = [1, 2, 3, 4, 5, 6, 7, 8, 9, 10];
  assert.equal(quantile(sorted, 0.5), 5);
  assert.equal(quantile(sorted, 0.95), 10);
  assert.equal(quantile(sorted, 0.9), 9);
  assert.equal(quantile([7], 0.5), 7);
  assert.ok(Number.isNaN(quantile([], 0.5)));
});

test('statistics: per-pixel relative error against B, its median, p95 and mean, and the RMSE', () => {
  // Reference B: 1 everywhere; A off by 0, 0.1, 0.2, 1.0 in every channel.
  const b = image([[1, 1, 1], [1, 1, 1], [1, 1, 1], [1, 1, 1]]);
  const a = image([[1, 1, 1], [1.1, 1.1, 1.1], [1.2, 1.2, 1.2], [2, 2, 2]]);
  const s = compareStats(a, b, 2, 2);
  const rel = [0, 0.1, 0.2, 1].map((d) => Math.fround(1 + d) - 1).map((d) => d / (1 + RELATIVE_EPSILON));
  assert.equal(s.pixels, 4);
  assert.equal(s.masked, 0);
  assert.ok(Math.abs(s.median - rel[1]) < 1e-12, `median ${s.median}`);
  assert.ok(Math.abs(s.p95 - rel[3]) < 1e-12, `p95 ${s.p95}`);
  assert.ok(Math.abs(s.relative - rel.reduce((x, y) => x + y) / 4) < 1e-12);
  const squares = [0, 0.1, 0.2, 1].map((d) => (Math.fround(1 + d) - 1) ** 2);
  assert.ok(Math.abs(s.rmse - Math.sqrt(squares.reduce((x, y) => x + y) / 4)) < 1e-12);
});

test('a mask leaves its pixels out of every statistic', () => {
  const b = image([[0, 0, 0], [1, 1, 1], [1, 1, 1]]);
  const a = image([[50, 50, 50], [1.5, 1.5, 1.5], [1, 1, 1]]); // a bright emitter the reference lacks
  const all = compareStats(a, b, 3, 1);
  const masked = compareStats(a, b, 3, 1, new Uint8Array([1, 0, 0]));
  assert.equal(all.pixels, 3);
  assert.equal(masked.pixels, 2);
  assert.equal(masked.masked, 1);
  assert.ok(all.p95 > 4000, `the emitter dominates: ${all.p95}`);
  assert.ok(Math.abs(masked.p95 - 0.5 / 1.01) < 1e-9, `without it: ${masked.p95}`);
  assert.ok(masked.relative < all.relative);
  assert.ok(masked.rmse < all.rmse);
});

test('non-finite pixels are left out and counted; sizes that differ give no statistics', () => {
  const s = compareStats(image([[NaN, 0, 0], [1, 1, 1]]), image([[0, 0, 0], [1, 1, 1]]), 2, 1);
  assert.equal(s.pixels, 1);
  assert.equal(s.nonFinite, 1);
  assert.equal(s.median, 0);
  assert.equal(compareStats(image([[1, 1, 1]]), image([[1, 1, 1], [1, 1, 1]]), 1, 1), null);
  const none = compareStats(image([[1, 1, 1]]), image([[1, 1, 1]]), 1, 1, new Uint8Array([1]));
  assert.equal(none.pixels, 0);
  assert.ok(Number.isNaN(none.median) && Number.isNaN(none.rmse));
});

test('background is where the G-buffer drew nothing (normal w = 0); emitters where some camera ray saw a light (albedo alpha > 0)', () => {
  const normal = new Float32Array([0, 1, 0, 1, 0, 0, 0, 0, 0, 0, 1, 1]);
  assert.deepEqual([...backgroundMask(normal, 3, 1)], [0, 1, 0]);
  const albedo = new Float32Array([0.5, 0.5, 0.5, 0, 0, 0, 0, 0.25, 0.8, 0.8, 0.8, 1]);
  assert.deepEqual([...emitterMask(albedo, 3, 1)], [0, 1, 1]);
  assert.deepEqual([...unionMask([new Uint8Array([0, 1, 0]), null, new Uint8Array([0, 0, 1])])], [0, 1, 1]);
  assert.equal(unionMask([null, null]), null);
});

test('the scale is a percentile of the unmasked per-pixel mean differences, or fixed', () => {
  // |A − B| per pixel (mean over RGB): 1, 2, …, 100, and one of 1000.
  const values = [...Array.from({ length: 100 }, (_, i) => i + 1), 1000];
  const diff = image(values.map((v) => [v, v, v]));
  assert.equal(scaleTop(diff, 101, 1, { kind: 'percentile', value: 99 }), 100);
  assert.equal(scaleTop(diff, 101, 1, { kind: 'percentile', value: 100 }), 1000);
  const mask = new Uint8Array(101);
  mask.fill(1, 50);
  assert.equal(scaleTop(diff, 101, 1, { kind: 'percentile', value: 99 }, mask), 50);
  assert.equal(scaleTop(diff, 101, 1, { kind: 'fixed', value: 0.25 }), 0.25);
  assert.equal(scaleTop(image([[NaN, 0, 0]]), 1, 1, { kind: 'percentile', value: 99 }), 0);
});

test('the heat map puts 0 at the ramp foot, the top and above at its head, non-finite in magenta; masks paint grey', () => {
  const diff = image([[0, 0, 0], [2, 2, 2], [9, 9, 9], [NaN, 0, 0], [0.5, 0.5, 0.5]]);
  const out = heatMap(diff, 2, new Uint8ClampedArray(5 * 4));
  const px = (i) => [...out.slice(4 * i, 4 * i + 4)];
  assert.deepEqual(px(0), [...RAMP[0], 255]);
  assert.deepEqual(px(1), [...RAMP[RAMP.length - 1], 255]);
  assert.deepEqual(px(2), [...RAMP[RAMP.length - 1], 255]);
  assert.deepEqual(px(3), [255, 0, 255, 255]);
  assert.deepEqual(px(4), [...RAMP[1], 255], 'a quarter of the top is the second of five stops');
  paintMask(out, new Uint8Array([0, 1, 0, 0, 0]));
  assert.deepEqual(px(1), [...MASKED_RGB, 255]);
  assert.ok(!RAMP.some((c) => c.join() === MASKED_RGB.join()), 'the masked grey is no ramp colour');
});

test('samples per second count from the first change seen, and the time to the target follows', () => {
  const r = new SampleRate();
  r.observe(3, 0); // reached at some unknown time before
  assert.equal(r.rate(), null);
  r.observe(3, 500);
  r.observe(4, 1000);
  assert.equal(r.rate(), null, 'one change gives no rate');
  assert.equal(r.secondsTo(8), null);
  r.observe(6, 2000);
  assert.equal(r.rate(), 2);
  assert.equal(r.secondsTo(8), 1);
  r.observe(8, 3000);
  assert.equal(r.secondsTo(8), 0);
  r.observe(1, 4000); // a new accumulation
  assert.equal(r.rate(), null);
  r.observe(null, 5000);
  assert.equal(r.last, null);
});

test('durations read as a person says them', () => {
  assert.equal(formatDuration(4.4), '4 s');
  assert.equal(formatDuration(200), '3 min 20 s');
  assert.equal(formatDuration(7500), '2 h 5 min');
  assert.equal(formatDuration(null), '—');
});
