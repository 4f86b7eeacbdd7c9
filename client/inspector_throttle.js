// When the live inspector shows new data: a streamed capture as it
// arrives, or a fetch while nothing streams. No DOM here, and the clock and
// timers come in from outside, so node can test it.
//
// Streamed captures are megabytes of floats to analyse: the newest per
// output is kept and at most one batch is shown per MIN_INTERVAL_MS. A fetch
// in flight is shown first; streamed data waits for it. Fetches are for
// frames rendered while no capture streams in (the stream has not started,
// or the server is not streaming this output): at most one in flight, no
// sooner than MIN_INTERVAL_MS (or twice the last fetch's duration, so a
// large capture on a slow link cannot saturate it) after the previous one,
// and a trailing one so the last frame of a burst is the one shown.

export const MIN_INTERVAL_MS = 250;
/** A capture streamed this recently means the stream is on. */
export const STREAM_FRESH_MS = 2000;

export class LiveThrottle {
  /**
   * @param {object} io
   * @param {() => void} io.fetch starts a fetch, which calls fetchStarted()
   *   now and fetchEnded() when it lands
   * @param {(batch: Map<string, *>) => void} io.apply shows the newest
   *   streamed capture of each key
   * @param {() => number} [io.now] milliseconds
   * @param {{setTimeout: Function, clearTimeout: Function}} [io.timers]
   */
  constructor({ fetch, apply, now = () => performance.now(), timers = globalThis }) {
    this.io = { fetch, apply, now, timers };
    this.pending = new Map(); // key → newest streamed capture not yet shown
    this.applyTimer = null;
    this.lastApplied = -Infinity;
    this.lastStreamed = -Infinity;
    this.streamedLoads = 0;
    this.loading = false;
    this.dirty = false; // a fetch was asked for while one was in flight
    this.fetchTimer = null;
    this.lastStart = -Infinity;
    this.lastDuration = 0;
    this.failing = false;
    this.fetches = 0;
  }

  streaming() {
    return this.io.now() - this.lastStreamed < STREAM_FRESH_MS;
  }

  /** A frame was rendered: fetch it unless the stream brings it. */
  frame(fetchAnyway = false) {
    if (fetchAnyway || !this.streaming()) this.requestFetch();
  }

  /** A capture of `key` streamed in; it replaces any not yet shown. */
  streamed(key, capture) {
    this.pending.set(key, capture);
    this.lastStreamed = this.io.now();
    this.scheduleApply();
  }

  scheduleApply() {
    if (this.applyTimer !== null || this.loading || this.pending.size === 0) return;
    const wait = Math.max(0, this.lastApplied + MIN_INTERVAL_MS - this.io.now());
    this.applyTimer = this.io.timers.setTimeout(() => {
      this.applyTimer = null;
      // A fetch started meanwhile: fetchEnded() schedules this again.
      if (this.loading) return;
      this.lastApplied = this.io.now();
      const batch = this.pending;
      this.pending = new Map();
      this.streamedLoads++;
      this.io.apply(batch);
    }, wait);
  }

  /** Asks for a fetch, throttled as the header says. */
  requestFetch() {
    if (this.loading) {
      this.dirty = true;
      return;
    }
    if (this.fetchTimer !== null) return;
    // A failing target (404 while a pass is broken) is polled gently.
    const floor = this.failing ? 4 * MIN_INTERVAL_MS : MIN_INTERVAL_MS;
    const interval = Math.max(floor, 2 * this.lastDuration);
    const wait = Math.max(0, this.lastStart + interval - this.io.now());
    this.fetchTimer = this.io.timers.setTimeout(() => {
      this.fetchTimer = null;
      this.io.fetch();
    }, wait);
  }

  fetchStarted() {
    this.loading = true;
    this.lastStart = this.io.now();
  }

  /** The newest fetch landed (`ok`: it got its data). */
  fetchEnded(ok) {
    this.lastDuration = this.io.now() - this.lastStart;
    this.loading = false;
    this.failing = !ok;
    this.fetches++;
    if (this.dirty) {
      this.dirty = false;
      this.requestFetch();
    }
    this.scheduleApply();
  }

  /** Plain data for tests and the console. */
  snapshot() {
    return {
      streaming: this.streaming(),
      lastStreamed: this.lastStreamed,
      streamedLoads: this.streamedLoads,
      fetches: this.fetches,
      loading: this.loading,
      pending: this.pending.size,
      applyTimer: this.applyTimer !== null,
      fetchTimer: this.fetchTimer !== null,
    };
  }
}
