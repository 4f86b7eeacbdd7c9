// A material preview the full preview queue refused (503) is asked again
// after each pause, until it is answered, a newer request supersedes it,
// or the pauses run out. The server side and the page are covered by the
// browser tests (tests/e2e/browser/budget.rs asks for four at once).
import assert from 'node:assert/strict';
import { test } from 'node:test';

import { BUSY_RETRIES_MS, fetchPreview } from '../../client/preview_image.js';

/** A fetch that answers each call with the next status. */
function answering(statuses) {
  const calls = [];
  return {
    calls,
    fetch: async (url) => {
      calls.push(url);
      return new Response('', { status: statuses[Math.min(calls.length - 1, statuses.length - 1)] });
    },
  };
}

test('a refused preview is asked again after each pause until it is answered', async () => {
  const server = answering([503, 503, 200]);
  globalThis.fetch = server.fetch;
  const paused = [];
  const r = await fetchPreview('/p', () => false, async (ms) => paused.push(ms));
  assert.equal(r.status, 200);
  assert.equal(server.calls.length, 3);
  assert.deepEqual(paused, BUSY_RETRIES_MS.slice(0, 2));
});

test('a newer request ends the retries, and they end when the pauses run out', async () => {
  let server = answering([503, 200]);
  globalThis.fetch = server.fetch;
  assert.equal((await fetchPreview('/p', () => true, async () => {})).status, 503);
  assert.equal(server.calls.length, 1, 'superseded: not asked again');
  server = answering([503]);
  globalThis.fetch = server.fetch;
  assert.equal((await fetchPreview('/p', () => false, async () => {})).status, 503);
  assert.equal(server.calls.length, 1 + BUSY_RETRIES_MS.length);
  server = answering([422]);
  globalThis.fetch = server.fetch;
  assert.equal((await fetchPreview('/p', () => false, async () => {})).status, 422);
  assert.equal(server.calls.length, 1, 'only a busy queue is asked again');
});
