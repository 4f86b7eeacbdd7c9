// The WebSocket side of the protocol: JSON text events, binary image
// frames, and reconnecting with backoff so the page survives server
// restarts (the dev server is restarted often; the tab should not be).

const BACKOFF_MIN_MS = 250;
const BACKOFF_MAX_MS = 2000;

/**
 * Splits a binary message: [u32 LE header length N][N bytes JSON header]
 * [payload]. Returns {header, payload} or throws with a reason.
 */
export function parseBinaryFrame(buffer) {
  if (buffer.byteLength < 4) throw new Error(`binary message too short (${buffer.byteLength} bytes)`);
  const headerLen = new DataView(buffer).getUint32(0, true);
  if (4 + headerLen > buffer.byteLength) {
    throw new Error(`binary header length ${headerLen} exceeds message (${buffer.byteLength} bytes)`);
  }
  const text = new TextDecoder().decode(new Uint8Array(buffer, 4, headerLen));
  const header = JSON.parse(text);
  if (!header || typeof header !== 'object') throw new Error('binary header is not a JSON object');
  return { header, payload: new Uint8Array(buffer, 4 + headerLen) };
}

/**
 * A self-healing connection to `/ws`.
 *
 * Callbacks: onState('connecting' | 'connected' | 'reconnecting'),
 * onOpen() after every (re)connect, onEvent(json), onBinary(header, bytes),
 * onProblem(message) for malformed messages (never thrown: one bad message
 * must not kill the stream).
 */
export class Connection {
  constructor(url, callbacks) {
    this.url = url;
    this.cb = callbacks;
    this.ws = null;
    this.delay = BACKOFF_MIN_MS;
    this.timer = null;
    this.state = 'connecting';
    /** Outputs this page asked to have captured, as `pass/output` →
     * message. Sent again after each reconnect: a restarted server has
     * forgotten them. */
    this.subscriptions = new Map();
    /** What each panel wants streamed (`want`): owner → [{pass, output, encoding}]. */
    this.wants = new Map();
    this.everConnected = false;
  }

  start() {
    this.open();
  }

  setState(state) {
    if (state === this.state) return;
    this.state = state;
    this.cb.onState?.(state);
  }

  open() {
    this.timer = null;
    let ws;
    try {
      ws = new WebSocket(this.url);
    } catch (err) {
      // A malformed URL throws synchronously; treat it like a failed connect.
      this.cb.onProblem?.(`WebSocket: ${err.message}`);
      this.retry();
      return;
    }
    ws.binaryType = 'arraybuffer';
    this.ws = ws;
    ws.onopen = () => {
      this.delay = BACKOFF_MIN_MS;
      this.everConnected = true;
      this.setState('connected');
      for (const message of this.subscriptions.values()) this.send(message);
      if (this.quads) this.send({ type: 'quad_statistics', on: true });
      if (this.references) this.send({ type: 'reference_comparison', on: true });
      this.safe(() => this.cb.onOpen?.());
    };
    ws.onmessage = (msg) => this.receive(msg.data);
    // Every failure ends in `close` (an `error` is always followed by one),
    // so retrying there is enough.
    ws.onclose = () => {
      if (this.ws !== ws) return;
      this.ws = null;
      this.retry();
    };
  }

  retry() {
    this.setState(this.everConnected ? 'reconnecting' : 'connecting');
    if (this.timer !== null) return;
    const delay = this.delay;
    this.delay = Math.min(this.delay * 2, BACKOFF_MAX_MS);
    this.timer = setTimeout(() => this.open(), delay);
  }

  receive(data) {
    if (typeof data === 'string') {
      let event;
      try {
        event = JSON.parse(data);
      } catch (err) {
        this.cb.onProblem?.(`invalid JSON event: ${err.message}`);
        return;
      }
      this.safe(() => this.cb.onEvent?.(event));
      return;
    }
    let frame;
    try {
      frame = parseBinaryFrame(data);
    } catch (err) {
      this.cb.onProblem?.(`invalid binary message: ${err.message}`);
      return;
    }
    this.safe(() => this.cb.onBinary?.(frame.header, frame.payload));
  }

  /** A handler bug is reported, not thrown into the socket's event loop. */
  safe(fn) {
    try {
      fn();
    } catch (err) {
      this.cb.onProblem?.(`client error: ${err.message}`);
      console.error(err);
    }
  }

  /** Sends a JSON message; false when not connected (it is not queued). */
  send(message) {
    if (!this.ws || this.ws.readyState !== WebSocket.OPEN) return false;
    this.ws.send(JSON.stringify(message));
    return true;
  }

  /**
   * Asks the server to capture `pass/output` every frame and stream it to
   * this page as binary `capture` messages in `encoding` (`png`, `f32` or
   * `f16`). Returns whether this is a new subscription.
   */
  subscribe(pass, output, encoding = 'png') {
    const key = `${pass}/${output}`;
    if (this.subscriptions.get(key)?.encoding === encoding) return false;
    const message = { type: 'subscribe', pass, output, encoding };
    this.subscriptions.set(key, message);
    this.send(message);
    return true;
  }

  /** Stops the stream of `pass/output` (the server may stop capturing it). */
  unsubscribe(pass, output) {
    const key = `${pass}/${output}`;
    if (!this.subscriptions.delete(key)) return false;
    this.send({ type: 'unsubscribe', pass, output });
    return true;
  }

  /** Asks for quad statistics with every frame, or stops; kept across reconnects. */
  setQuads(on) {
    this.quads = on;
    this.send({ type: 'quad_statistics', on });
  }

  /** Asks for (or stops) the image cases' comparison with their references. */
  setReferences(on) {
    this.references = on;
    this.send({ type: 'reference_comparison', on });
  }

  /**
   * Sets what `owner` (a panel) wants streamed: [{pass, output, encoding}].
   * The server holds one set per connection, so the page subscribes to the
   * union of every owner's; an output two owners want in different
   * encodings comes as f32, the one every consumer can read exactly.
   */
  want(owner, wanted) {
    this.wants.set(owner, wanted);
    const union = new Map();
    for (const list of this.wants.values()) {
      for (const { pass, output, encoding } of list) {
        const key = `${pass}/${output}`;
        if (!union.has(key) || encoding === 'f32') union.set(key, { pass, output, encoding });
      }
    }
    for (const message of [...this.subscriptions.values()]) {
      if (!union.has(`${message.pass}/${message.output}`)) this.unsubscribe(message.pass, message.output);
    }
    for (const { pass, output, encoding } of union.values()) this.subscribe(pass, output, encoding);
  }
}
