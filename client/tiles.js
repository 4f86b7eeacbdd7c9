// Tile classification in the page (the `frame` event's `tiles`): under the
// pass list, one chip per class (empty, simple, single, complex) in the
// colours of the `tile_class` debug view, so it doubles as that view's
// legend, each with its tiles and pixels, then the material bytes the
// frame wrote. The lighting time per class is the class passes' own
// timings in the list above. Test hooks: #tiles-info is hidden without
// statistics; each chip has data-class, data-tiles and data-pixels, and
// #tiles-info data-bytes. tileChips is DOM-free (tests/client/tiles.test.mjs).

import { el } from './util.js';

/** The classes, cheapest first, with the debug view's colours. */
export const CLASSES = [
  { name: 'empty', color: 'rgb(13, 13, 13)', help: 'no geometry: the environment only' },
  { name: 'simple', color: 'rgb(26, 179, 51)', help: 'one plain closure (16 B)' },
  { name: 'single', color: 'rgb(230, 204, 26)', help: 'one closure with features' },
  { name: 'complex', color: 'rgb(230, 38, 26)', help: 'two or more closures' },
];

/** Bytes as the page shows them: B, KiB or MiB. */
export function formatBytes(n) {
  if (n < 1024) return `${n} B`;
  if (n < 1024 * 1024) return `${(n / 1024).toFixed(1)} KiB`;
  return `${(n / (1024 * 1024)).toFixed(2)} MiB`;
}

/**
 * The chips for `tiles` (the `frame` event's, or null): per class
 * `{ name, color, tiles, pixels, text, title }`, and the bytes line;
 * `null` without statistics.
 */
export function tileChips(tiles) {
  if (!tiles || !tiles.tiles || !tiles.pixels) return null;
  const chips = CLASSES.map((c) => {
    const t = tiles.tiles[c.name] ?? 0;
    const p = tiles.pixels[c.name] ?? 0;
    return { ...c, tiles: t, pixels: p, text: `${c.name} ${t}`, title: `${c.name}: ${c.help}\n${t} tiles (8×8), ${p} pixels` };
  });
  const bytes = tiles.material_bytes_written ?? 0;
  return { chips, bytes, text: `material ${formatBytes(bytes)} written` };
}

/** The element under the pass list, updated by each `frame` event. */
export class TileInfo {
  /** @param {HTMLElement} root #tiles-info */
  constructor(root) {
    this.root = root;
  }

  update(frame) {
    const shown = tileChips(frame?.tiles ?? null);
    this.root.hidden = !shown;
    if (!shown) {
      this.root.replaceChildren();
      return;
    }
    this.root.dataset.bytes = String(shown.bytes);
    const chips = shown.chips.map((c) =>
      el(
        'span',
        { class: 'tile-chip', title: c.title, dataset: { class: c.name, tiles: String(c.tiles), pixels: String(c.pixels) } },
        el('span', { class: 'tile-swatch', style: `background: ${c.color}` }),
        c.text,
      ),
    );
    this.root.replaceChildren(...chips, el('span', { class: 'tile-bytes', text: shown.text }));
  }
}
