// How pass and frame times read in the page, DOM-free (tested by
// tests/client/timings.test.mjs): each pass's figure with the clock that
// measured it (GPU timestamps, or the wall clock with the pass submitted
// alone), or "n/a" with the server's reason, never a bare number; and a
// frame's wall time split into the passes' sum and what no pass accounts
// for, beside the frame rate actually delivered (header #fps's title).

import { formatMs } from './util.js';

/** The clocks a pass's `timing` names (protocol.rs `Clock`). */
const CLOCKS = {
  gpu: { label: 'GPU', help: "GPU time: the adapter's timestamps around the pass" },
  wall: {
    label: 'wall',
    help: "wall-clock time: the pass submitted alone and waited for (recording, execution and the copies of its captured outputs); the adapter's timestamps do not bracket its work",
  },
};

/**
 * A pass's time as its row shows it: `{ ms, clock, title, kind }`, where
 * `kind` is `gpu`, `wall` or `none` (the row's data-timing).
 */
export function passTime(t) {
  const clock = CLOCKS[t?.timing];
  if (clock && Number.isFinite(t.time_ms)) {
    return { ms: `${formatMs(t.time_ms)} ms`, clock: clock.label, title: clock.help, kind: t.timing };
  }
  const reason = typeof t?.timing_reason === 'string' ? t.timing_reason : '';
  return { ms: reason.startsWith('n/a') ? 'n/a' : '—', clock: '', title: reason, kind: 'none' };
}

/** Whether a frame event carries the frame's wall time and its split. */
export function hasSplit(f) {
  return !!f && ['frame_ms', 'passes_ms', 'unattributed_ms'].every((k) => Number.isFinite(f[k]));
}

/** The Passes panel's total: the frame, the passes' sum, the rest. */
export function frameTotal(f) {
  if (!hasSplit(f)) return { text: '', title: '' };
  return {
    text: `frame ${formatMs(f.frame_ms)} ms = passes ${formatMs(f.passes_ms)} + other ${formatMs(f.unattributed_ms)}`,
    title: [
      `frame: ${formatMs(f.frame_ms)} ms by the wall clock, from the start of its recording to its publication`,
      `passes: ${formatMs(f.passes_ms)} ms, the sum of the pass times shown (a pass marked n/a adds nothing)`,
      `other: ${formatMs(f.unattributed_ms)} ms in no pass: recording, readback, conversion, waiting for the frame before`,
    ].join('\n'),
  };
}

/**
 * The frame-rate title: the rate delivered, the period it means, and how
 * the newest frame's wall time splits. `fps` 0: nothing is rendering.
 */
export function fpsTitle(fps, f) {
  const lines = [];
  if (fps > 0) {
    const period = 1000 / fps;
    lines.push(`${fps >= 10 ? fps.toFixed(0) : fps.toFixed(2)} frames per second delivered: one every ${formatMs(period)} ms`);
    if (hasSplit(f)) {
      const gap = period - f.frame_ms;
      if (gap > 0.1 * period) lines.push(`${formatMs(gap)} ms of each period between frames (the frame-rate cap, or nothing to render)`);
      else if (gap < -0.1 * period) lines.push('frames overlap: the next is recorded while one is on the GPU');
    }
  }
  if (hasSplit(f)) {
    lines.push(
      `newest frame: ${formatMs(f.frame_ms)} ms = passes ${formatMs(f.passes_ms)} ms + ${formatMs(f.unattributed_ms)} ms in no pass`,
    );
  }
  return lines.join('\n');
}
