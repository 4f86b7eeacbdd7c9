// tensor_image.js's constant-channel label.
import assert from 'node:assert/strict';
import { test } from 'node:test';

import { channelCaption, constantValue } from '../../client/tensor_image.js';

test('a channel whose every value is equal is constant, with that value', () => {
  // Three pixels of three channels: c0 all zero, c1 varies, c2 all 0.25.
  const data = new Float32Array([0, 1, 0.25, 0, 2, 0.25, -0, 3, 0.25]);
  assert.equal(constantValue(data, 3, 0), 0);
  assert.equal(constantValue(data, 3, 1), null);
  assert.equal(constantValue(data, 3, 2), 0.25);
  assert.equal(channelCaption(0, constantValue(data, 3, 0)), 'c0 constant = 0');
  assert.equal(channelCaption(2, 0.25), 'c2 constant = 0.2500');
  assert.equal(channelCaption(1, null), 'c1');
});

test('a channel holding NaN or Inf is not constant, nor is one differing only in its last pixel', () => {
  assert.equal(constantValue(new Float32Array([NaN, NaN]), 1, 0), null);
  assert.equal(constantValue(new Float32Array([Infinity, Infinity]), 1, 0), null);
  assert.equal(constantValue(new Float32Array([1, 1, 1, 1.5]), 1, 0), null);
  assert.equal(constantValue(new Float32Array([0, 5, 0, 6]), 2, 0), 0);
});
