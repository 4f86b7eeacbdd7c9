// Brings the inspected data in: fetches A (and B when comparing) as exact
// floats (`.f32`), and takes the f32 captures the server streams to this
// page for the outputs it subscribed to. inspector_throttle.js decides
// when a fetch runs and when a streamed capture is shown.

import * as api from './api.js';
import { LiveThrottle } from './inspector_throttle.js';

export const keyOf = (pass, output) => `${pass}/${output}`;

/** `pass/output` → {pass, output}; the output is after the last slash. */
export function parseKey(key) {
  const i = key.lastIndexOf('/');
  return i < 0 ? null : { pass: key.slice(0, i), output: key.slice(i + 1) };
}

export class Loader {
  /**
   * @param {object} hooks app.js's: fetchCaptures, subscribeOnly, awaitCapture
   *   (see Inspector)
   * @param {object} host the inspector
   * @param {() => {a: {pass: string, output: string}, b: object | null} | null} host.wanted
   *   what to load: A, and B's compare spec ({pass, output, lastGood}) or null
   * @param {(pass: string, output: string) => object | null} host.metaFor
   *   the capture list's entry of an output
   * @param {() => void} host.changed loading or waiting changed
   * @param {(result: {a: PromiseSettledResult, b: PromiseSettledResult | null, wanted: object}) => void}
   *   host.landed the newest fetch settled
   * @param {(captures: {header: object, loaded: object}[]) => void} host.streamed
   *   streamed captures to show, newest per output
   */
  constructor(hooks, host) {
    this.hooks = hooks;
    this.host = host;
    this.seq = 0;
    this.current = Promise.resolve(false);
    this.waiting = null; // `pass/output` whose first capture is awaited
    this.throttle = new LiveThrottle({
      fetch: () => this.load(),
      apply: (batch) => host.streamed([...batch.values()].map(decode)),
    });
  }

  get loading() {
    return this.throttle.loading;
  }

  /**
   * Fetches what the host wants and hands it over. Overlapping loads are
   * resolved newest-wins: an older response never replaces a newer one,
   * and every caller's promise settles with the newest load's result.
   */
  load() {
    const wanted = this.host.wanted();
    if (!wanted) return Promise.resolve(false);
    const seq = ++this.seq;
    const run = this.loadOnce(seq, wanted);
    this.current = run.then((ok) => (seq === this.seq ? ok : this.current));
    return this.current;
  }

  async loadOnce(seq, wanted) {
    const { a, b } = wanted;
    this.throttle.fetchStarted();
    this.host.changed();
    // The server captures only the final output and what clients
    // subscribe to, and streams subscribed outputs to this page.
    this.hooks.subscribeOnly?.([a, ...(b && !b.lastGood ? [b] : [])]);
    // The capture list carries formats and sizes; refreshing it alongside
    // keeps the selects and the info line in step with the data.
    const capturesP = this.hooks.fetchCaptures ? this.hooks.fetchCaptures().catch(() => null) : null;
    const [ra, rb] = await Promise.allSettled([this.fetchSlot({ ...a, lastGood: false }), b ? this.fetchSlot(b) : null]);
    await capturesP;
    if (seq !== this.seq) return false; // superseded: the newer load reports
    this.waiting = null;
    this.throttle.fetchEnded(ra.status === 'fulfilled');
    this.host.landed({ a: ra, b: b ? rb : null, wanted });
    return ra.status === 'fulfilled';
  }

  async fetchSlot(spec) {
    const get = () => api.captureF32(spec.pass, spec.output, { lastGood: spec.lastGood, fallback: this.host.metaFor(spec.pass, spec.output) });
    try {
      return await get();
    } catch (err) {
      // Not captured yet: a new subscription shows up a frame or two
      // later. Wait for it once, then give up with that state.
      if (spec.lastGood || !(err instanceof api.ApiError) || !err.notCaptured || !this.hooks.awaitCapture) throw err;
      const key = keyOf(spec.pass, spec.output);
      this.waiting = key;
      this.host.changed();
      const captured = await this.hooks.awaitCapture(spec.pass, spec.output);
      if (this.waiting === key) this.waiting = null;
      if (!captured) throw err;
      return get();
    }
  }

  /** A binary `capture` message of an output the inspector shows. */
  stream(header, bytes) {
    if (header.encoding !== 'f32' || bytes.byteLength !== header.width * header.height * 16) return;
    this.throttle.streamed(keyOf(header.pass, header.output), { header, bytes });
  }
}

function decode({ header, bytes }) {
  // Copied: a Float32Array needs a 4-byte aligned start.
  const data = new Float32Array(bytes.slice().buffer);
  return { header, loaded: { data, width: header.width, height: header.height, frame: header.frame, format: header.format } };
}
