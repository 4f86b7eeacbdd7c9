// The DOM-free helpers of util.js (el and $ need a document).
import assert from 'node:assert/strict';
import { test } from 'node:test';

import { coalesce, encodePath, errorText, formatMs, latestOnly, plural } from '../../client/util.js';
import { Clock } from './clock.mjs';

test('formatMs keeps a precision that suits the size', () => {
  assert.equal(formatMs(1234.5), '1235');
  assert.equal(formatMs(12.345), '12.3');
  assert.equal(formatMs(1.2345), '1.23');
  assert.equal(formatMs(0.12345), '0.123');
  for (const v of [null, undefined, NaN, Infinity]) assert.equal(formatMs(v), '—');
});

test('plural', () => {
  assert.equal(plural(1, 'pass'), '1 pass');
  assert.equal(plural(0, 'frame'), '0 frames');
  assert.equal(plural(2, 'frame'), '2 frames');
});

test('encodePath encodes each segment and keeps the slashes', () => {
  assert.equal(encodePath('shaders/my pass/a#b?.wgsl'), 'shaders/my%20pass/a%23b%3F.wgsl');
});

test('errorText is the message of anything thrown', () => {
  assert.equal(errorText(new Error('boom')), 'boom');
  assert.equal(errorText('plain'), 'plain');
  assert.equal(errorText(null), 'null');
});

test('latestOnly delivers only the newest call, whichever settles first', async () => {
  const resolvers = [];
  const delivered = [];
  const errors = [];
  const call = latestOnly(
    (n) => new Promise((resolve, reject) => resolvers.push({ n, resolve, reject })),
    (v) => delivered.push(v),
    (e) => errors.push(e.message),
  );
  const first = call(1);
  const second = call(2);
  resolvers[1].resolve('second');
  await second;
  resolvers[0].resolve('first');
  await first;
  assert.deepEqual(delivered, ['second'], 'the older response is dropped');
  const third = call(3);
  resolvers[2].reject(new Error('down'));
  await third;
  assert.deepEqual(errors, ['down']);
});

test('coalesce runs a burst of calls once, after the delay', (t) => {
  // util.js schedules on the global timers: a manual clock stands in,
  // as node 18 (Debian's) has no mock timers.
  const clock = new Clock();
  const saved = globalThis.setTimeout;
  globalThis.setTimeout = clock.setTimeout;
  t.after(() => (globalThis.setTimeout = saved));
  let runs = 0;
  const run = coalesce(() => runs++, 30);
  run();
  run();
  clock.advance(29);
  run();
  assert.equal(runs, 0);
  clock.advance(1);
  assert.equal(runs, 1, 'once for the whole burst');
  run();
  clock.advance(30);
  assert.equal(runs, 2, 'a later call runs again');
});
