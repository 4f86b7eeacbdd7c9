// The wait for a first capture: it must not miss a frame that lands before
// or during a read of the capture list.
import test from 'node:test';
import assert from 'node:assert/strict';
import { awaitListed } from '../../client/capture_wait.js';

/** Frames as the page's `frame` events: `emit()` resolves every waiter. */
function frames() {
  const waiters = [];
  return {
    waiters,
    next: () => new Promise((resolve) => waiters.push(resolve)),
    emit: () => waiters.splice(0).forEach((w) => w(true)),
    timeOut: () => waiters.splice(0).forEach((w) => w(false)),
  };
}

test('an output already captured is found without waiting for a frame', async () => {
  const f = frames();
  const found = awaitListed({ listed: async () => true, nextFrame: f.next, frames: 3 });
  setTimeout(f.timeOut, 10); // no frame will come (on-change rendering)
  assert.equal(await found, true);
});

test('a frame that lands while the list is read is not missed', async () => {
  const f = frames();
  let reads = 0;
  const listed = async () => {
    reads++;
    if (reads === 1) f.emit(); // the capturing frame arrives mid-read
    return reads > 1;
  };
  const found = awaitListed({ listed, nextFrame: f.next, frames: 3 });
  setTimeout(f.timeOut, 10);
  assert.equal(await found, true);
  assert.equal(reads, 2);
});

test('it gives up after its frames, having read the list after the last one', async () => {
  const f = frames();
  let reads = 0;
  const listed = async () => {
    reads++;
    queueMicrotask(f.emit);
    return false;
  };
  assert.equal(await awaitListed({ listed, nextFrame: f.next, frames: 3 }), false);
  assert.equal(reads, 4);
});

test('it gives up when the time allowed is over, and a failed read is not found', async () => {
  const f = frames();
  const found = awaitListed({ listed: async () => { throw new Error('offline'); }, nextFrame: f.next, frames: 3 });
  setTimeout(f.timeOut, 10);
  assert.equal(await found, false);
});
