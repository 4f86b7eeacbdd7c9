// Display presets: the choice by format and meaning, depth linearisation,
// the clear value left out of auto-fit, and presets remembered per output.
import assert from 'node:assert/strict';
import { test } from 'node:test';

import * as presets from '../../client/presets.js';
import * as tex from '../../client/texture.js';

const CAMERA = { near: 0.05, far: 200, reversed: false };

test('a format has only its own channels, in the readout and the channel select', () => {
  const names = (f) => presets.formatInfo(f).names;
  const values = (f) => presets.channelOptions(presets.formatInfo(f)).map((o) => o.label);
  assert.deepEqual(names('Depth32Float'), ['depth']);
  assert.deepEqual(values('Depth32Float'), ['depth']);
  assert.deepEqual(names('R32Float'), ['R']);
  assert.deepEqual(values('R32Float'), ['R']);
  assert.deepEqual(names('Rg16Float'), ['R', 'G']);
  assert.deepEqual(values('Rg16Float'), ['RG', 'R', 'G']);
  assert.deepEqual(names('Rg11b10Ufloat'), ['R', 'G', 'B']);
  assert.deepEqual(names('Rgb10a2Unorm'), ['R', 'G', 'B', 'A']);
  assert.deepEqual(values('Rgba16Float'), ['RGB', 'R', 'G', 'B', 'A', 'luminance']);
  assert.deepEqual(names(undefined), ['R', 'G', 'B', 'A'], 'unknown: the four the capture holds');
  assert.equal(presets.formatInfo('R32Uint').integer, true);
  assert.equal(presets.formatInfo('Rgba8Sint').integer, true);
  assert.equal(presets.formatInfo('R32Float').integer, false);
  for (const f of ['Depth32Float', 'R32Float', 'Rg16Float', 'Rgba16Float']) {
    for (const o of presets.channelOptions(presets.formatInfo(f))) assert.ok(tex.CHANNELS.includes(o.value), `${f}: ${o.value}`);
  }
});

test('depth opens as one grey channel, sRGB off, fitted, linearised when the planes are known', () => {
  const d = presets.choosePreset({ format: 'Depth32Float', meaning: 'depth', depth: CAMERA });
  assert.equal(d.meaning, 'depth');
  assert.equal(d.opts.channel, 'r');
  assert.equal(d.opts.srgb, false);
  assert.equal(d.opts.linearize, true);
  assert.equal(d.fit, true);
  const light = presets.choosePreset({ format: 'Depth32Float', meaning: 'depth', depth: { near: null, far: null, reversed: false } });
  assert.equal(light.opts.linearize, false, "a light's depth has no planes to linearise with");
  assert.equal(presets.choosePreset({ format: 'Depth32Float' }).meaning, 'depth', 'a depth format without a declared meaning');
});

test('normals open remapped (n·0.5+0.5) without sRGB; colour keeps sRGB; data and ids lose it', () => {
  const n = presets.choosePreset({ format: 'Rgba16Float', meaning: 'normal' });
  assert.deepEqual([n.opts.min, n.opts.max, n.opts.srgb, n.opts.channel], [-1, 1, false, 'rgb']);
  const shown = tex.tonemap(new Float32Array([-1, 0, 1, 1, 0.5, -0.5, 0, 1]), 2, 1, { ...tex.defaultOptions(), ...n.opts }, new Uint8ClampedArray(8));
  assert.deepEqual(Array.from(shown), [0, 128, 255, 255, 191, 64, 128, 255], 'n·0.5+0.5 in 8 bits');
  const c = presets.choosePreset({ format: 'Rgba16Float', meaning: 'color' });
  assert.deepEqual([c.opts.min, c.opts.max, c.opts.srgb, c.fit], [0, 1, true, false]);
  for (const meaning of ['data', 'id']) {
    const p = presets.choosePreset({ format: 'Rgba16Float', meaning });
    assert.deepEqual([p.opts.srgb, p.fit], [false, true], meaning);
  }
  const int = presets.choosePreset({ format: 'R32Uint', meaning: 'color' });
  assert.deepEqual([int.opts.srgb, int.fit, int.opts.channel], [false, true, 'r'], 'integers are never sRGB');
});

test('depth linearises to view distance, forward and reversed', () => {
  const near = (a, b) => assert.ok(Math.abs(a - b) < 1e-6 * b, `${a} ≈ ${b}`);
  near(presets.linearDepth(0, CAMERA), 0.05);
  near(presets.linearDepth(1, CAMERA), 200);
  const reversed = { ...CAMERA, reversed: true };
  near(presets.linearDepth(1, reversed), 0.05);
  near(presets.linearDepth(0, reversed), 200);
  // A point 10 units away, projected as glam's perspective_rh does.
  const z = 10;
  const d = (CAMERA.far * (z - CAMERA.near)) / (z * (CAMERA.far - CAMERA.near));
  assert.ok(Math.abs(presets.linearDepth(d, CAMERA) - z) < 1e-9);
  const lin = presets.linearizeDepth(new Float32Array([d, 0, 0, 1]), CAMERA);
  assert.ok(Math.abs(lin[0] - z) < 1e-4);
  assert.deepEqual(Array.from(lin.slice(1)), [0, 0, 1]);
  assert.equal(presets.depthClear(CAMERA), 1);
  assert.equal(presets.depthClear(reversed), 0);
});

test('auto-fit leaves out the clear value', () => {
  const src = new Float32Array([0.98, 0, 0, 1, 1, 0, 0, 1, 0.99, 0, 0, 1]);
  assert.deepEqual(tex.finiteRange(src, 'r'), { min: Math.fround(0.98), max: 1 });
  const fitted = tex.finiteRange(src, 'r', { src, value: 1 });
  assert.equal(fitted.max, Math.fround(0.99));
  assert.equal(fitted.min, Math.fround(0.98));
  assert.equal(tex.finiteRange(new Float32Array([1, 0, 0, 1]), 'r', { src: new Float32Array([1, 0, 0, 1]), value: 1 }), null);
});

test('presets are stored per output and bad entries ignored', () => {
  const map = new Map();
  const storage = { getItem: (k) => (map.has(k) ? map.get(k) : null), setItem: (k, v) => map.set(k, String(v)) };
  assert.equal(presets.loadPreset(storage, 'depth_prepass/depth'), null);
  const opts = { ...tex.defaultOptions(), channel: 'r', min: 2, max: 9, srgb: false, linearize: true, overlayNan: false };
  presets.savePreset(storage, 'depth_prepass/depth', opts);
  assert.deepEqual(presets.loadPreset(storage, 'depth_prepass/depth'), { channel: 'r', exposure: 0, min: 2, max: 9, srgb: false, linearize: true });
  assert.equal(presets.loadPreset(storage, 'gbuffer/normal'), null, 'per output');
  map.set('loupe.preset.x/y', '{not json');
  assert.equal(presets.loadPreset(storage, 'x/y'), null);
  map.set('loupe.preset.x/y', JSON.stringify({ ...presets.pick(opts), channel: 'purple' }));
  assert.equal(presets.loadPreset(storage, 'x/y'), null);
  const full = { setItem: () => { throw new Error('quota'); } };
  presets.savePreset(full, 'x/y', opts); // does not throw
  assert.ok(presets.samePreset(opts, presets.pick(opts)));
  assert.ok(!presets.samePreset(opts, { ...opts, min: 3 }));
});
