// materials.js's slider bounds for a material parameter.
import assert from 'node:assert/strict';
import { test } from 'node:test';

import { sliderOf } from '../../client/materials.js';

test('a bounded parameter slides over its range', () => {
  assert.deepEqual(sliderOf({ min: 1, max: 2.5, default: 1.5 }, 1.5), { min: 1, max: 2.5, step: 0.0015 });
});

test('an unbounded one slides to four times its value or default, at least 1', () => {
  assert.deepEqual(sliderOf({ min: 0, max: 3.4028234663852886e38, default: 0.5 }, 2), { min: 0, max: 8, step: 0.008 });
  assert.deepEqual(sliderOf({ min: null, max: null, default: 0.1 }, 0.1), { min: 0, max: 1, step: 0.001 });
});
