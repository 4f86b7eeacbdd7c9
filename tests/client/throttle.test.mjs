// The live inspector's throttle: when a streamed capture is shown and when
// the inspector fetches instead.
import assert from 'node:assert/strict';
import { test } from 'node:test';

import { LiveThrottle, MIN_INTERVAL_MS, STREAM_FRESH_MS } from '../../client/inspector_throttle.js';
import { Clock } from './clock.mjs';

function setup() {
  const clock = new Clock();
  const applied = []; // batches, as [key, capture] pairs
  const fetched = []; // times of fetches
  const throttle = new LiveThrottle({
    fetch: () => fetched.push(clock.now()),
    apply: (batch) => applied.push([...batch]),
    now: clock.now,
    timers: clock,
  });
  return { clock, throttle, applied, fetched };
}

test('a streamed capture is shown at once, later ones at most once per interval, newest per output', () => {
  const { clock, throttle, applied } = setup();
  throttle.streamed('tonemap/color', 1);
  clock.advance(0);
  assert.deepEqual(applied, [[['tonemap/color', 1]]]);
  // Three more within the interval: one timer, and only the newest shows.
  for (const [dt, n] of [
    [10, 2],
    [10, 3],
    [10, 4],
  ]) {
    clock.advance(dt);
    throttle.streamed('tonemap/color', n);
  }
  throttle.streamed('gbuffer/normal', 7);
  const lastStreamed = clock.now();
  assert.equal(clock.timers.size, 1, 'one pending timer for any number of captures');
  clock.advance(MIN_INTERVAL_MS - 31);
  assert.equal(applied.length, 1, 'nothing before the interval is over');
  clock.advance(1);
  assert.deepEqual(applied[1], [
    ['tonemap/color', 4],
    ['gbuffer/normal', 7],
  ]);
  assert.equal(throttle.streamedLoads, 2);
  assert.deepEqual(throttle.snapshot(), {
    streaming: true,
    lastStreamed,
    streamedLoads: 2,
    fetches: 0,
    loading: false,
    pending: 0,
    applyTimer: false,
    fetchTimer: false,
  });
});

test('a frame is fetched only while no capture streams in, or when asked to anyway', () => {
  const { clock, throttle, fetched } = setup();
  throttle.frame();
  clock.advance(0);
  assert.equal(fetched.length, 1, 'before the stream starts, a frame is fetched');
  throttle.fetchStarted();
  clock.advance(5);
  throttle.fetchEnded(true);

  throttle.streamed('tonemap/color', 1);
  const streamedAt = clock.now();
  clock.advance(10);
  throttle.frame();
  clock.advance(MIN_INTERVAL_MS);
  assert.equal(fetched.length, 1, 'a streaming inspector does not fetch');
  throttle.frame(true);
  clock.advance(MIN_INTERVAL_MS);
  assert.equal(fetched.length, 2, 'a last-good B is fetched even while streaming');
  throttle.fetchStarted();
  throttle.fetchEnded(true);

  clock.advance(streamedAt + STREAM_FRESH_MS - 1 - clock.now());
  assert.equal(throttle.streaming(), true);
  clock.advance(1);
  assert.equal(throttle.streaming(), false, 'the stream went quiet');
  throttle.frame();
  clock.advance(MIN_INTERVAL_MS);
  assert.equal(fetched.length, 3, 'so frames are fetched again');
});

test('streamed data waits for a fetch in flight and shows after it lands', () => {
  const { clock, throttle, applied } = setup();
  throttle.fetchStarted();
  throttle.streamed('tonemap/color', 1);
  assert.equal(clock.timers.size, 0, 'no timer while a fetch is in flight');
  clock.advance(10 * MIN_INTERVAL_MS);
  assert.equal(applied.length, 0, 'not shown under a fetch in flight');
  assert.equal(clock.timers.size, 0, 'nor polling for its end');
  throttle.fetchEnded(true);
  clock.advance(0);
  assert.deepEqual(applied, [[['tonemap/color', 1]]]);

  // A fetch that starts while the apply timer waits defers it too.
  throttle.streamed('tonemap/color', 2);
  throttle.fetchStarted();
  clock.advance(MIN_INTERVAL_MS);
  assert.equal(applied.length, 1);
  throttle.fetchEnded(true);
  clock.advance(0);
  assert.deepEqual(applied[1], [['tonemap/color', 2]]);
});

test('fetches: one in flight, spaced by the interval or twice the last duration, with a trailing one', () => {
  const { clock, throttle, fetched } = setup();
  throttle.requestFetch();
  throttle.requestFetch();
  assert.equal(clock.timers.size, 1, 'requests coalesce into one timer');
  clock.advance(0);
  assert.deepEqual(fetched, [1000]);
  throttle.fetchStarted();
  throttle.requestFetch();
  throttle.requestFetch();
  assert.equal(clock.timers.size, 0, 'none while one is in flight');
  clock.advance(400); // a slow fetch: 400 ms
  throttle.fetchEnded(true);
  assert.equal(clock.timers.size, 1, 'the trailing fetch of the burst');
  clock.advance(2 * 400 - 400 - 1);
  assert.equal(fetched.length, 1, 'no sooner than twice the last duration after the last start');
  clock.advance(1);
  assert.deepEqual(fetched, [1000, 1800]);
});

test('a failing fetch is polled gently', () => {
  const { clock, throttle, fetched } = setup();
  throttle.fetchStarted();
  throttle.fetchEnded(false);
  throttle.requestFetch();
  clock.advance(4 * MIN_INTERVAL_MS - 1);
  assert.equal(fetched.length, 0);
  clock.advance(1);
  assert.equal(fetched.length, 1);
  throttle.fetchStarted();
  throttle.fetchEnded(true);
  throttle.requestFetch();
  clock.advance(MIN_INTERVAL_MS);
  assert.equal(fetched.length, 2, 'back to the normal pace once it succeeds');
});
