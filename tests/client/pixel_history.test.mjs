import test from 'node:test';
import assert from 'node:assert/strict';
import { formatBefore, formatValue, fragmentRows, isSurvivor, verdictText } from '../../client/pixel_history.js';

test('the fragments of a pass list draw by draw, in submission order', () => {
  const draws = [
    { name: 'floor', fragments: [{ primitive: 1, depth: 0.9, verdict: 'passed', helper: false }] },
    {
      name: 'knot',
      fragments: [
        { primitive: 7, depth: 0.4, verdict: 'passed', helper: false },
        { primitive: 8, depth: 0.41, verdict: 'failed_depth', helper: true },
      ],
    },
  ];
  assert.deepEqual(
    fragmentRows(draws).map((f) => [f.draw, f.primitive, f.verdict]),
    [
      ['floor', 1, 'passed'],
      ['knot', 7, 'passed'],
      ['knot', 8, 'failed_depth'],
    ],
  );
  assert.deepEqual(fragmentRows(null), []);
});

test('verdicts, values and what came before read as words or exact numbers', () => {
  assert.equal(verdictText({ verdict: 'failed_depth', helper: false }), 'failed depth');
  assert.equal(verdictText({ verdict: 'not_tested', helper: true }), 'not tested (helper lane)');
  assert.equal(formatValue([0.1, 1, 0, 0]), '0.1, 1, 0, 0');
  assert.equal(formatValue(null), 'not read');
  assert.equal(formatBefore({ origin: 'cleared', before: null }), 'cleared');
  assert.equal(formatBefore({ origin: 'undefined', before: null }), 'undefined (first write)');
  assert.equal(formatBefore({ origin: 'read', before: [0.5, 0.25, 0, 1] }), '0.5, 0.25, 0, 1');
  assert.equal(formatBefore({ origin: 'unread', before: null }), 'not read');
});

test('the survivor is the fragment the pass kept, never a helper lane', () => {
  const survivor = { draw: 'knot', primitive: 7 };
  assert.equal(isSurvivor(survivor, { draw: 'knot', primitive: 7, helper: false }), true);
  assert.equal(isSurvivor(survivor, { draw: 'knot', primitive: 7, helper: true }), false);
  assert.equal(isSurvivor(survivor, { draw: 'floor', primitive: 7, helper: false }), false);
  assert.equal(isSurvivor(null, { draw: 'knot', primitive: 7, helper: false }), false);
});
