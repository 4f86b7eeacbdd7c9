// The pinned pixel's debugPrintf lines (the `prints` event) under the
// inspector's pixel readout: pinning a pixel selects it on the server
// (`debug_pixel`), unpinning clears it. Lines are grouped by pass, then by
// the call that printed them, each call with its source line and what it
// printed this frame, in order (docs/printf.md).

import { el } from './util.js';

/** Lines shown per call; a loop that prints more says how many it left out. */
export const MAX_PER_CALL = 64;

/**
 * Groups `lines` by pass, then by call (`file:line:column`), both in the
 * order first printed: [{ pass, calls: [{ at, file, line, texts }] }].
 */
export function groupPrints(lines) {
  const passes = [];
  for (const l of lines || []) {
    let pass = passes.find((p) => p.pass === l.pass);
    if (!pass) passes.push((pass = { pass: l.pass, calls: [] }));
    const at = `${l.file}:${l.line}:${l.column}`;
    let call = pass.calls.find((c) => c.at === at);
    if (!call) pass.calls.push((call = { at, file: l.file, line: l.line, texts: [] }));
    call.texts.push(l.text);
  }
  return passes;
}

/**
 * The frame pixel under pixel `p` of an inspected image of `size`, for a
 * frame of `frame` size (a pass may render at another size than the
 * frame); null without both sizes.
 */
export function framePixel(p, size, frame) {
  if (!p || !size?.width || !size?.height || !frame?.width || !frame?.height) return null;
  const x = Math.min(frame.width - 1, Math.floor(((p.x + 0.5) * frame.width) / size.width));
  const y = Math.min(frame.height - 1, Math.floor(((p.y + 0.5) * frame.height) / size.height));
  return { x, y };
}

export class PrintsPanel {
  /**
   * `node`: where the lines go; `send(message)` reaches the server;
   * `source(file)` resolves to a file's text.
   */
  constructor(node, { send, source }) {
    this.node = node;
    this.send = send;
    this.source = source;
    this.frame = null;
    this.selected = null;
    this.sources = new Map();
    this.last = '';
  }

  /** The frame's size, from the live frame. */
  frameSize(width, height) {
    this.frame = { width, height };
  }

  /** The inspector pinned `p` of an image of `size`, or unpinned (null). */
  pin(p, size) {
    const at = framePixel(p, size, this.frame);
    if (at?.x === this.selected?.x && at?.y === this.selected?.y) return;
    this.selected = at;
    this.send(at ? { type: 'debug_pixel', x: at.x, y: at.y } : { type: 'debug_pixel', x: null, y: null });
    this.last = '';
    this.node.hidden = !at;
    this.node.replaceChildren();
  }

  /** Forgets the cached text of `files` (a reload changed them). */
  invalidate(files) {
    for (const f of files || []) this.sources.delete(f);
  }

  /** A `prints` event: shown if it is for the pixel selected now. */
  set(ev) {
    const s = this.selected;
    if (!s || ev.pixel?.[0] !== s.x || ev.pixel?.[1] !== s.y) return;
    const key = JSON.stringify([ev.lines, ev.dropped]);
    if (key === this.last) return;
    this.last = key;
    const groups = groupPrints(ev.lines);
    const head = el('div', { class: 'prints-head', text: `prints at (${s.x}, ${s.y})${groups.length ? '' : ': none this frame'}` });
    const body = groups.map((g) =>
      el(
        'div',
        { class: 'prints-pass' },
        el('div', { class: 'prints-pass-name', text: g.pass }),
        g.calls.map((c) => this.call(c)),
      ),
    );
    const dropped = ev.dropped > 0 && el('div', { class: 'prints-dropped', text: `${ev.dropped} more did not fit the buffer` });
    this.node.replaceChildren(head, ...body, dropped || '');
  }

  call(c) {
    const src = el('code', { class: 'prints-source' });
    this.lineOf(c.file, c.line).then((text) => {
      src.textContent = text ?? '';
    });
    const shown = c.texts.slice(0, MAX_PER_CALL);
    const more = c.texts.length - shown.length;
    return el(
      'div',
      { class: 'prints-call' },
      el('div', { class: 'prints-at' }, el('span', { class: 'num', text: c.at }), ' ', src),
      el('pre', { class: 'prints-lines', text: shown.join('\n') + (more > 0 ? `\n… ${more} more` : '') }),
    );
  }

  /** Line `line` of `file`, trimmed; null when it cannot be read. */
  async lineOf(file, line) {
    if (!this.sources.has(file)) this.sources.set(file, this.source(file).catch(() => null));
    const text = await this.sources.get(file);
    return text?.split('\n')[line - 1]?.trim() ?? null;
  }
}
