import test from 'node:test';
import assert from 'node:assert/strict';
import { parseEntry, rangeText } from '../../client/numeric_entry.js';

const exposure = { min: -24, max: 24, step: 0.1 };
const steps = { min: 1, max: 256, step: 1 };

test('a number in range is the value to send', () => {
  assert.deepEqual(parseEntry(' 1.5 ', exposure), { value: 1.5 });
  assert.deepEqual(parseEntry('−2', exposure), { value: -2 });
  assert.deepEqual(parseEntry('24', exposure), { value: 24 });
  assert.deepEqual(parseEntry('64', steps), { value: 64 });
});

test('out of range, not a number, empty or not whole is an error naming the range', () => {
  assert.match(parseEntry('25', exposure).error, /out of range: −24 … 24/);
  assert.match(parseEntry('abc', exposure).error, /not a number/);
  assert.match(parseEntry('', exposure).error, /−24 … 24/);
  assert.match(parseEntry('Infinity', exposure).error, /not a number/);
  assert.match(parseEntry('2.5', steps).error, /not a whole number/);
  for (const t of ['25', 'abc', '', '2.5']) assert.equal(parseEntry(t, t === '2.5' ? steps : exposure).value, undefined);
});

test('the range reads with real minus signs', () => {
  assert.equal(rangeText(exposure), '−24 … 24');
});
