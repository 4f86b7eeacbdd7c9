// Quad statistics: while the "quads" toggle is on the server computes, for
// every draw of every raster pass, how many 2×2 quads it launched and how
// many of their lanes ran as helpers, and streams them with each frame
// (`quads` events). This panel shows the inspected pass's per-draw table
// with the adapter's own fragment-shader count beside the model's, the pass
// totals in the pass list, and two inspector overlays: quad overdraw (quads
// launched over each 2×2 block) and helper lanes (times each pixel ran as a
// helper), each with its legend; under the cursor (or the pinned pixel)
// the inspector reads the map's own count (`countAt`, `countText`).
//
// The maps' colours, the same in both maps and in `loupe view`, are
// presets.json's `quad_maps`: solid steps for low counts and, from a map's
// top count up, diagonal stripes no flat surface looks like.
//
// Test hooks: #quad-stats (toggle), #quad-panel[data-pass] with
// table#quad-table tr[data-draw] cells td[data-key] (td[data-key=cull_mode]
// states each draw's culling), #quad-overlay (none|overdraw|helpers),
// #quad-legend .legend-item[data-hatched], #passes li .pass-quads.

import TABLE from './presets.json' with { type: 'json' };
import { el } from './util.js';

const { steps: STEPS, hatch: HATCH, top: STEP_COUNT, stripe: STRIPE, alpha: ALPHA } = TABLE.quad_maps;
const KEYS = ['triangles', 'culled_triangles', 'pixels', 'quads', 'helper_lanes', 'quad_efficiency'];

/** A figure as the table shows it: efficiency in percent, counts grouped. */
export function fmt(v, key = '') {
  if (v === null || v === undefined) return '—';
  return key === 'quad_efficiency' ? `${(v * 100).toFixed(1)} %` : Number(v).toLocaleString('en-US');
}

/** The colour of count `n` (≥ 1) at image pixel (x, y) in a `kind` map. */
export function countColor(n, kind, x, y) {
  const top = STEP_COUNT[kind];
  if (n < top) return STEPS[n - 1];
  return HATCH[Math.floor((x + y) / STRIPE) % 2];
}

/**
 * An RGBA8 overlay of a one-channel count map {values, width}, with its
 * legend rows {color (CSS), label, hatched}.
 */
export function paintMap({ values, width }, kind) {
  const rgba = new Uint8ClampedArray(values.length * 4);
  for (let i = 0; i < values.length; i++) {
    const n = values[i];
    if (!(n >= 1)) continue; // 0 (and nothing) stays transparent
    const c = countColor(n, kind, i % width, Math.floor(i / width));
    rgba.set([c[0], c[1], c[2], ALPHA], i * 4);
  }
  const top = STEP_COUNT[kind];
  const rgb = (c) => `rgb(${c.join(',')})`;
  const legend = STEPS.slice(0, top - 1).map((c, i) => ({ color: rgb(c), label: String(i + 1), hatched: false }));
  const [a, b] = HATCH.map(rgb);
  legend.push({ color: `repeating-linear-gradient(45deg, ${a} 0 3px, ${b} 3px 6px)`, label: `${top}+`, hatched: true });
  return { rgba, legend };
}

/** The count a map {values, width, height} holds at pixel (x, y), or null outside it. */
export function countAt(map, x, y) {
  if (!map || !(x >= 0 && y >= 0 && x < map.width && y < map.height)) return null;
  return map.values[y * map.width + x];
}

/** The readout line of count `n` in a `kind` map. */
export function countText(kind, n) {
  return kind === 'overdraw'
    ? `quad overdraw ${n} · quads launched over this pixel's 2×2 block`
    : `helper lanes ${n} · times this pixel ran as a helper lane`;
}

/** A draw's culling as the table states it, from its `cull_mode`. */
export function cullingText(mode) {
  if (mode === null || mode === undefined) return '—';
  return mode === 'none' ? 'off (cull_mode none)' : `on (cull_mode ${mode})`;
}

export class QuadView {
  /**
   * @param {object} els {toggle, panel, overlay, legend}
   * @param {object} hooks {send(on), passList, inspector, fetchMap(pass, kind)}
   */
  constructor(els, hooks) {
    this.els = els;
    this.hooks = hooks;
    this.report = null;
    this.pass = null;
    this.overlayKey = null; // `${frame}/${pass}/${kind}` of the overlay shown
    els.toggle.addEventListener('change', () => this.setOn(els.toggle.checked));
    els.overlay.addEventListener('change', () => this.refreshOverlay(true));
    this.setOn(false);
  }

  setOn(on) {
    this.on = on;
    this.els.toggle.checked = on;
    this.els.overlay.disabled = !on;
    this.hooks.send(on);
    if (!on) {
      this.report = null;
      this.els.overlay.value = 'none';
      this.hooks.passList.setQuads(null);
      this.refreshOverlay(true);
    }
    this.renderPanel();
  }

  /** A `quads` event. */
  setReport(report) {
    if (!this.on) return;
    this.report = report;
    this.hooks.passList.setQuads(report);
    this.renderPanel();
    this.refreshOverlay(false);
  }

  /** The inspector now shows an output of `pass`. */
  setPass(pass) {
    if (pass === this.pass) return;
    this.pass = pass;
    this.renderPanel();
    this.refreshOverlay(true);
  }

  passReport() {
    return this.report?.passes?.find((p) => p.pass === this.pass) ?? null;
  }

  renderPanel() {
    const { panel } = this.els;
    const p = this.passReport();
    panel.hidden = !this.on;
    panel.dataset.pass = p ? p.pass : '';
    const body = panel.querySelector('.quad-body');
    if (!this.on) return;
    if (!p) {
      body.replaceChildren(el('div', { class: 'placeholder' }, this.report ? `${this.pass ?? 'this pass'}: not a raster pass of this frame` : 'waiting for a frame with quad statistics…'));
      return;
    }
    const row = (name, s, cls) =>
      el(
        'tr',
        { dataset: { draw: name }, class: cls || '' },
        el('th', {}, name),
        KEYS.map((k) => el('td', { dataset: { key: k, value: s[k] ?? '' } }, fmt(s[k], k))),
        el('td', { dataset: { key: 'cull_mode', value: s.cull_mode ?? '' } }, cullingText(s.cull_mode)),
      );
    const rows = [];
    for (const d of p.draws) {
      rows.push(row(d.name, d));
      if (d.rasterized) rows.push(row(`${d.name} · before depth test`, d.rasterized, 'sub'));
    }
    rows.push(row('total', p.quads, 'total'));
    if (p.what_if) rows.push(row(`what if ${p.what_if.mode.replace('_', ' ')}`, p.what_if, 'what-if'));
    const lanes = 4 * p.quads.quads;
    const cross =
      p.fragment_invocations === null || p.fragment_invocations === undefined
        ? `${this.report.adapter} cannot count fragment-shader invocations`
        : `${this.report.adapter} counted ${fmt(p.fragment_invocations)} fragment-shader invocations; the model launches ${fmt(lanes)} lanes (${fmt(p.quads.pixels)} pixels + ${fmt(p.quads.helper_lanes)} helpers)`;
    body.replaceChildren(
      el(
        'table',
        { id: 'quad-table' },
        el('thead', {}, el('tr', {}, el('th', {}, 'draw'), KEYS.map((k) => el('th', {}, k.replace('_', ' '))), el('th', { title: "the face the draw's pipeline culls; culled triangles counts face culling only where it is on" }, 'culling'))),
        el('tbody', {}, rows),
      ),
      el('div', { class: 'quad-cross', id: 'quad-cross' }, cross),
    );
  }

  /** Fetches and shows the selected overlay for the inspected pass. */
  async refreshOverlay(force) {
    const kind = this.els.overlay.value;
    const p = this.passReport();
    if (!this.on || kind === 'none' || !p) {
      this.overlayKey = null;
      this.hooks.inspector.setOverlay(null);
      this.els.legend.replaceChildren();
      return;
    }
    const key = `${this.report.frame}/${p.pass}/${kind}`;
    if (!force && key === this.overlayKey) return;
    this.overlayKey = key;
    const map = await this.hooks.fetchMap(p.pass, kind);
    if (this.overlayKey !== key) return; // a newer request won
    const { rgba, legend } = paintMap(map, kind);
    this.hooks.inspector.setOverlay({ width: map.width, height: map.height, rgba, kind, values: map.values });
    this.els.legend.replaceChildren(
      el('span', { class: 'legend-title' }, kind === 'overdraw' ? 'quads per 2×2 block' : 'helper-lane runs per pixel'),
      ...legend.map((l) =>
        el('span', { class: 'legend-item', dataset: { hatched: String(l.hatched) } }, el('i', { class: 'swatch', style: `background:${l.color}` }), l.label),
      ),
    );
  }
}
