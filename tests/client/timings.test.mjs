// The pass and frame time wording of timings.js: no bare number for a
// pass, n/a with the server's reason, and a frame split that adds up.
import assert from 'node:assert/strict';
import { test } from 'node:test';

import { fpsTitle, frameTotal, passTime } from '../../client/timings.js';

test('a measured pass names its clock', () => {
  assert.deepEqual(
    { ...passTime({ time_ms: 1204.4, timing: 'wall', timing_reason: null }), title: '' },
    { ms: '1204 ms', clock: 'wall', title: '', kind: 'wall' },
  );
  const gpu = passTime({ time_ms: 0.0132, timing: 'gpu', timing_reason: null });
  assert.equal(`${gpu.ms} ${gpu.clock}`, '0.013 ms GPU');
  assert.match(gpu.title, /timestamps/);
});

test('a pass without a figure is n/a with the reason, never a number', () => {
  const reason = "n/a: the adapter's timestamps read 0.013 ms while 1190 ms of the frame's wall time lie outside every pass";
  assert.deepEqual(passTime({ time_ms: null, timing: null, timing_reason: reason }), { ms: 'n/a', clock: '', title: reason, kind: 'none' });
  // A number without its clock is not shown as measured.
  assert.equal(passTime({ time_ms: 0.013 }).kind, 'none');
  assert.equal(passTime({ time_ms: 0.013 }).ms, '—');
  assert.equal(passTime({ time_ms: null, timing: null, timing_reason: 'not run: culled' }).ms, '—');
  assert.equal(passTime(undefined).ms, '—');
});

test('the frame total shows the frame, the passes and the rest', () => {
  const f = { frame_ms: 1204, passes_ms: 1150, unattributed_ms: 54 };
  assert.equal(frameTotal(f).text, 'frame 1204 ms = passes 1150 + other 54.0');
  assert.match(frameTotal(f).title, /recording, readback/);
  assert.deepEqual(frameTotal({ frame: 3 }), { text: '', title: '' }, 'an event without the split shows nothing');
});

test('the frame-rate title reconciles the rate with the frame', () => {
  const f = { frame_ms: 1190, passes_ms: 1150, unattributed_ms: 40 };
  const lines = fpsTitle(1000 / 1204, f).split('\n');
  assert.deepEqual(lines, [
    '0.83 frames per second delivered: one every 1204 ms',
    'newest frame: 1190 ms = passes 1150 ms + 40.0 ms in no pass',
  ]);
  assert.match(fpsTitle(10, { frame_ms: 20, passes_ms: 15, unattributed_ms: 5 }), /80\.0 ms of each period between frames/);
  assert.match(fpsTitle(100, { frame_ms: 20, passes_ms: 15, unattributed_ms: 5 }), /frames overlap/);
  assert.equal(fpsTitle(0, null), '');
});
