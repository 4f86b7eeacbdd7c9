import test from 'node:test';
import assert from 'node:assert/strict';
import { groupPrints, framePixel } from '../../client/prints.js';

const line = (pass, file, l, text) => ({ pass, file, line: l, column: 5, text, values: [] });

test('prints group by pass, then by call, in the order printed', () => {
  const groups = groupPrints([
    line('lighting', 'shaders/passes/lighting.wgsl', 40, 'i 0'),
    line('tonemap', 'shaders/post/tonemap.wgsl', 18, 'at 1.5'),
    line('lighting', 'shaders/passes/lighting.wgsl', 40, 'i 1'),
    line('lighting', 'shaders/lib/brdf.wgsl', 7, 'ndotl 0.5'),
  ]);
  assert.deepEqual(
    groups.map((g) => [g.pass, g.calls.map((c) => [c.at, c.texts])]),
    [
      [
        'lighting',
        [
          ['shaders/passes/lighting.wgsl:40:5', ['i 0', 'i 1']],
          ['shaders/lib/brdf.wgsl:7:5', ['ndotl 0.5']],
        ],
      ],
      ['tonemap', [['shaders/post/tonemap.wgsl:18:5', ['at 1.5']]]],
    ],
  );
  assert.deepEqual(groupPrints(undefined), []);
});

test('a pinned pixel maps to the frame pixel under it', () => {
  const frame = { width: 640, height: 360 };
  assert.deepEqual(framePixel({ x: 70, y: 20 }, frame, frame), { x: 70, y: 20 });
  // A half-size image: the frame pixel under its pixel's centre.
  assert.deepEqual(framePixel({ x: 10, y: 3 }, { width: 320, height: 180 }, frame), { x: 21, y: 7 });
  assert.deepEqual(framePixel({ x: 319, y: 179 }, { width: 320, height: 180 }, frame), { x: 639, y: 359 });
  assert.equal(framePixel(null, frame, frame), null);
  assert.equal(framePixel({ x: 1, y: 1 }, frame, null), null);
});
