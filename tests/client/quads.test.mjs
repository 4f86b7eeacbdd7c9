// The quad maps' pure parts (quads.js): the colour steps, the count under
// the cursor and the culling text of the per-draw table.
import assert from 'node:assert/strict';
import { test } from 'node:test';

import { countAt, countColor, countText, cullingText, paintMap } from '../../client/quads.js';

/** HSV saturation of an [r, g, b] colour, 0…1. */
const saturation = ([r, g, b]) => (Math.max(r, g, b) - Math.min(r, g, b)) / Math.max(r, g, b, 1);
/** Relative luminance (Rec. 709 weights on the bytes). */
const luma = ([r, g, b]) => 0.2126 * r + 0.7152 * g + 0.0722 * b;

test('no step of either map is white, grey or black: every colour is saturated', () => {
  for (const kind of ['overdraw', 'helpers']) {
    for (let n = 1; n <= 8; n++) {
      for (const [x, y] of [[0, 0], [2, 0], [1, 3]]) {
        const c = countColor(n, kind, x, y);
        assert.ok(saturation(c) >= 0.6, `${kind} ${n} at ${x},${y}: ${c} is not saturated`);
      }
    }
  }
});

test('the solid steps rise in lightness and the same count has the same colour in both maps', () => {
  const solid = [1, 2, 3, 4].map((n) => countColor(n, 'overdraw', 0, 0));
  for (let i = 1; i < solid.length; i++) assert.ok(luma(solid[i]) > luma(solid[i - 1]), `step ${i + 1} lighter than step ${i}`);
  for (const n of [1, 2]) assert.deepEqual(countColor(n, 'helpers', 0, 0), countColor(n, 'overdraw', 0, 0));
});

test('the top step is hatched: stripes of two colours, on the map and in the legend', () => {
  for (const [kind, top] of [['overdraw', 5], ['helpers', 3]]) {
    const stripes = new Set([0, 1, 2, 3].map((x) => String(countColor(top + 4, kind, x, 0))));
    assert.equal(stripes.size, 2, `${kind}: ${[...stripes]}`);
    const { legend } = paintMap({ values: new Float32Array(0), width: 1 }, kind);
    assert.equal(legend.length, top);
    assert.deepEqual(legend.map((l) => l.label).at(-1), `${top}+`);
    assert.deepEqual(legend.map((l) => l.hatched), [...Array(top - 1).fill(false), true]);
    assert.match(legend.at(-1).color, /repeating-linear-gradient/);
  }
});

test('paintMap leaves zero transparent and paints counts with their colour', () => {
  const values = new Float32Array([0, 1, 2, 7]);
  const { rgba } = paintMap({ values, width: 2 }, 'overdraw');
  assert.equal(rgba[3], 0);
  assert.deepEqual(Array.from(rgba.subarray(4, 7)), countColor(1, 'overdraw', 1, 0));
  assert.deepEqual(Array.from(rgba.subarray(8, 11)), countColor(2, 'overdraw', 0, 1));
  assert.deepEqual(Array.from(rgba.subarray(12, 15)), countColor(7, 'overdraw', 1, 1));
  assert.ok(rgba[7] > 0 && rgba[15] > 0);
});

test('countAt reads the map row by row, and nothing outside it', () => {
  const map = { width: 3, height: 2, values: new Float32Array([0, 1, 2, 3, 4, 5]) };
  assert.equal(countAt(map, 2, 0), 2);
  assert.equal(countAt(map, 0, 1), 3);
  assert.equal(countAt(map, 2, 1), 5);
  for (const [x, y] of [[3, 0], [0, 2], [-1, 0]]) assert.equal(countAt(map, x, y), null);
  assert.equal(countAt(null, 0, 0), null);
  assert.match(countText('overdraw', 3), /^quad overdraw 3 /);
  assert.match(countText('helpers', 2), /^helper lanes 2 /);
});

test('the culling state reads off or on with the mode', () => {
  assert.equal(cullingText('none'), 'off (cull_mode none)');
  assert.equal(cullingText('back'), 'on (cull_mode back)');
  assert.equal(cullingText(null), '—');
});
