// The text beside the inspected image: the exact values of the hovered or
// pinned pixel in A, B and their difference, the count of the quad map laid
// over A at that pixel, and the info line with A's size, format, frame and
// statistics.
//
// Test hooks: #quad-value[data-kind][data-x][data-y][data-count].

import { countAt, countText } from './quads.js';
import * as tex from './texture.js';
import { $, el } from './util.js';

export class Readout {
  constructor() {
    this.a = $('pixel-value');
    this.b = $('pixel-value-b');
    this.diff = $('pixel-value-diff');
    this.count = $('quad-value');
    this.info = $('image-info');
    this.stats = $('stats');
  }

  /**
   * Values of pixel `p` (or a hint without one) in A and, when comparing,
   * in B and (diff mode) the difference.
   */
  values({ mode, a, b, diff, p, pinned }) {
    const compare = mode !== 'off';
    writeValues(this.a, { label: 'A', slot: a, p, compare, pinned });
    this.b.hidden = !compare;
    this.diff.hidden = mode !== 'diff';
    if (compare) writeValues(this.b, { label: 'B', slot: b, p, compare });
    if (mode === 'diff') writeValues(this.diff, { label: '|A−B|', slot: diff, p, compare });
    this.a.classList.toggle('pinned', pinned);
  }

  /**
   * The count of quad map `overlay` ({kind, values, width, height} or
   * null) at pixel `p`; hidden without a map or while comparing (the map
   * is drawn only over A alone).
   */
  overlayCount({ mode, overlay, p }) {
    const node = this.count;
    for (const k of ['kind', 'x', 'y', 'count']) delete node.dataset[k];
    node.hidden = !overlay || mode !== 'off';
    if (node.hidden) return;
    node.dataset.kind = overlay.kind;
    const n = p ? countAt(overlay, p.x, p.y) : null;
    if (n === null) {
      node.replaceChildren(el('span', { class: 'muted' }, `${overlay.kind === 'overdraw' ? 'quad overdraw' : 'helper lanes'}: hover the image to read the count`));
      return;
    }
    Object.assign(node.dataset, { x: String(p.x), y: String(p.y), count: String(n) });
    node.replaceChildren(el('span', { class: 'coord' }, `(${p.x}, ${p.y})`), ' ', el('span', { class: 'quad-count' }, countText(overlay.kind, n)));
  }

  /**
   * The info line of slot `a` (null clears it), `meta` its entry in the
   * capture list; `goTo(x, y)` opens the first NaN/Inf pixel.
   */
  describe(a, meta, goTo) {
    if (!a) {
      this.info.textContent = '';
      this.stats.replaceChildren();
      return;
    }
    const format = a.format || meta?.format || '';
    const frame = a.frame ?? meta?.frame;
    this.info.textContent = `${a.key} · ${a.width}×${a.height}${format ? ` · ${format}` : ''}${frame != null ? ` · frame ${frame}` : ''}`;

    const s = a.stats;
    const badge = (n, cls, word) => el('span', { class: `stat ${n ? cls : 'zero'}`, dataset: { stat: cls } }, `${n} ${word}`);
    const items = [badge(s.nan, 'nan', 'NaN')];
    if (s.first_nan && (s.nan || s.inf)) {
      const [x, y] = s.first_nan;
      items.push(
        el(
          'button',
          { type: 'button', class: 'link', title: 'centre and pin the first pixel holding a NaN or Inf', onclick: () => goTo(x, y) },
          `first at ${x},${y}`,
        ),
      );
    }
    items.push(badge(s.inf, 'inf', 'Inf'));
    items.push(badge(s.negative, 'neg', 'negative'));
    const fmt = (x) => (Number.isFinite(x) ? tex.formatF32(Math.fround(x)) : '—');
    items.push(
      el(
        'span',
        { class: 'stat range', title: 'finite min / max per channel (R G B A)' },
        `min ${s.min.map(fmt).join(' ')}  max ${s.max.map(fmt).join(' ')}`,
      ),
    );
    this.stats.replaceChildren(...items);
  }
}

function writeValues(node, { label, slot, p, compare, pinned = false }) {
  for (const k of ['x', 'y', 'r', 'g', 'b', 'a']) delete node.dataset[k];
  const v = slot && p ? tex.pixel(slot.data, slot.width, slot.height, p.x, p.y) : null;
  if (!v) {
    node.replaceChildren(
      ...(compare ? [el('span', { class: 'ro-label' }, label), ' '] : []),
      el('span', { class: 'muted' }, slot ? 'hover the image to read a pixel · click to pin · wheel zooms · drag pans' : '—'),
    );
    return;
  }
  node.dataset.x = String(p.x);
  node.dataset.y = String(p.y);
  // Attributes hold the exact value (the float32 widened to a double,
  // as JS prints it): a test can parse them back bit-exactly.
  ['r', 'g', 'b', 'a'].forEach((c, i) => (node.dataset[c] = String(v[i])));
  const cls = (x) => (x !== x ? 'nan' : x === Infinity || x === -Infinity ? 'inf' : x < 0 ? 'neg' : '');
  // Real spaces between the parts, so the element's text reads well when
  // copied or asserted on: "(3, 2) R 0.5 G 1 B 0 A 1".
  const parts = [];
  if (compare) parts.push(el('span', { class: 'ro-label' }, label));
  parts.push(el('span', { class: 'coord' }, `(${p.x}, ${p.y})`));
  ['R', 'G', 'B', 'A'].forEach((c, i) =>
    parts.push(
      el(
        'span',
        { class: `ch ch-${c.toLowerCase()} ${cls(v[i])}`, title: `${c} = ${String(v[i])} (${tex.f32Bits(v[i])})` },
        el('span', { class: 'ch-name' }, c),
        ' ',
        tex.formatF32(v[i]),
      ),
    ),
  );
  if (pinned) parts.push(el('span', { class: 'pin-tag', title: 'Esc or click again to unpin' }, 'pinned'));
  node.replaceChildren(...parts.flatMap((part, i) => (i ? [' ', part] : [part])));
}
