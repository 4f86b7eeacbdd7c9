import test from 'node:test';
import assert from 'node:assert/strict';
import { tileChips, formatBytes, CLASSES } from '../../client/tiles.js';

test('one chip per class, cheapest first, with its tiles and pixels', () => {
  const tiles = {
    pixels: { empty: 900, simple: 1200, single: 0, complex: 204 },
    tiles: { empty: 16, simple: 18, single: 0, complex: 6 },
    material_bytes_written: 27360,
  };
  const shown = tileChips(tiles);
  assert.deepEqual(shown.chips.map((c) => [c.name, c.tiles, c.pixels]), [
    ['empty', 16, 900],
    ['simple', 18, 1200],
    ['single', 0, 0],
    ['complex', 6, 204],
  ]);
  assert.equal(shown.chips[3].text, 'complex 6');
  assert.match(shown.chips[3].title, /two or more closures/);
  assert.equal(shown.bytes, 27360);
  assert.equal(shown.text, 'material 26.7 KiB written');
});

test('no statistics, no chips', () => {
  assert.equal(tileChips(null), null);
  assert.equal(tileChips(undefined), null);
  assert.equal(tileChips({}), null);
});

test('the legend names the classes in the debug view order', () => {
  assert.deepEqual(CLASSES.map((c) => c.name), ['empty', 'simple', 'single', 'complex']);
  assert.equal(formatBytes(512), '512 B');
  assert.equal(formatBytes(3 * 1024 * 1024), '3.00 MiB');
});
