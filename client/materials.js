// The materials panel: the scene's materials (`/api/materials` and the
// `materials` event), and for the selected one its tree after the
// analysis (collapsible, each node with its kind, id, depth, fields as
// text and features), its compile report, live controls for its
// instance's parameters, and its preview (preview.js). A control sends a
// scene override on the parameter's `path`: only the parameter buffer
// changes (no pipeline is rebuilt); the scene panel's "save to file"
// writes it into the scene file's `params` table. Colours get a slider per channel, each sending
// the whole `[r, g, b]`.
//
// Pixel → material: a pixel pinned in the inspector is looked up in
// `gbuffer/material` (z: the material index), subscribed at exact f32
// while a pixel is pinned; the answer names the material and its root node
// (the node a pixel shows is the whole tree: its closures are blended, not
// chosen, per pixel), and selects that material here.
//
// Test hooks: #materials-list [data-index] (aria-selected),
// #material-tree details[data-node][data-kind], #material-report
// [data-key], #material-params [data-path] sliders and [data-entry]
// entries, #pixel-material[data-index][data-name][data-node].

import { controlRow } from './controls.js';
import { MaterialPreview } from './preview.js';
import { $, el } from './util.js';

const MATERIAL = { pass: 'gbuffer', output: 'material', encoding: 'f32' };

/** A slider's bounds for a parameter: its range, or (unbounded above, as
 * a thickness is) up to four times its default, at least 1. */
export function sliderOf(p, value) {
  const min = p.min ?? 0;
  const wide = p.max === null || p.max > 1e6;
  const max = wide ? Math.max(1, 4 * Math.abs(Number(value) || 0), 4 * Math.abs(Number(p.default) || 0)) : p.max;
  return { min, max, step: (max - min) / 1000 };
}

export class MaterialsPanel {
  /** `send(message)` sends a WebSocket message; `want(list)` replaces the
   * outputs this panel subscribes to. */
  constructor({ send, want }) {
    this.send = send;
    this.want = want;
    this.report = null;
    this.selected = 0;
    this.list = $('materials-list');
    this.tree = $('material-tree');
    this.details = $('material-report');
    this.params = $('material-params');
    this.pixel = $('pixel-material');
    this.count = $('materials-count');
    this.preview = new MaterialPreview($('material-preview'));
    this.pinned = null;
  }

  /** Shows a MaterialsReport. */
  apply(report) {
    if (!report || !Array.isArray(report.materials)) return;
    const before = this.report;
    this.report = report;
    this.count.textContent = `${report.materials.length}`;
    this.list.replaceChildren(
      ...report.materials.map((m) =>
        el(
          'li',
          {},
          el(
            'button',
            { type: 'button', class: 'link', 'data-index': m.index, 'aria-selected': String(m.index === this.selected), onclick: () => this.select(m.index) },
            m.name,
            el('span', { class: 'muted' }, ` ${m.file ?? 'scene shorthand'}${m.file ? ` · ${m.material}` : ''}`),
          ),
        ),
      ),
    );
    // Keep the tree's open/closed nodes and a focused control while only
    // values change.
    const key = (r) => JSON.stringify(r?.materials[this.selected] ? [r.materials[this.selected].params.map((p) => p.path), r.definitions[r.materials[this.selected].definition]?.nodes] : null);
    if (key(before) !== key(report)) this.show();
    else {
      this.values();
      this.refreshReport();
    }
    // Any change to a material (its file, an override) changes the report.
    if (JSON.stringify(before) !== JSON.stringify(report)) this.preview.show(this.selected, this.budget());
    this.lookUp();
  }

  select(index) {
    this.selected = index;
    for (const b of this.list.querySelectorAll('[data-index]')) b.setAttribute('aria-selected', String(Number(b.dataset.index) === index));
    this.show();
    // A material chosen (a click, a pinned pixel) turns previews on.
    this.preview.budgetReport = this.budget();
    this.preview.start(index);
  }

  /** The selected material's definition's report `budget` (null: none). */
  budget() {
    const m = this.report?.materials[this.selected];
    return (m && this.report.definitions[m.definition]?.budget) ?? null;
  }

  show() {
    const m = this.report?.materials[this.selected];
    const def = m && this.report.definitions[m.definition];
    if (!m || !def) {
      this.tree.replaceChildren();
      this.details.replaceChildren();
      this.params.replaceChildren();
      return;
    }
    const byId = new Map(def.nodes.map((n) => [n.id, n]));
    this.tree.replaceChildren(node(byId, def.root));
    this.details.replaceChildren(...reportRows(def));
    this.params.replaceChildren(...m.params.flatMap((p) => this.rows(p)));
    this.values();
  }

  /** The selected material's report rows alone: what a changed budget
   *  (`quality.material_bytes`) changes without touching the tree. */
  refreshReport() {
    const m = this.report?.materials[this.selected];
    const def = m && this.report.definitions[m.definition];
    if (def) this.details.replaceChildren(...reportRows(def));
  }

  /** A parameter's rows: one slider, or one per colour channel; or one
   * read-only line. */
  rows(p) {
    // A texture (its image path) and a glTF's own material (no override
    // path: its values live in the glTF) are shown, not edited.
    if (p.type === 'texture' || p.path === null) {
      return [el('div', { class: 'readonly-param', 'data-readonly': p.name }, `${p.name}: `, el('code', {}, JSON.stringify(p.value)))];
    }
    const { min, max, step } = sliderOf(p, p.value);
    const title = [p.doc, p.unit ? `unit: ${p.unit}` : null, `default ${JSON.stringify(p.default)}`].filter(Boolean).join(' · ');
    const label = p.unit ? `${p.name} (${p.unit})` : p.name;
    if (!Array.isArray(p.value)) {
      return [controlRow({ path: p.path, label, kind: 'slider', min, max, step, title }, (value) => this.send({ type: 'set_override', path: p.path, value }))];
    }
    return ['r', 'g', 'b'].map((c, k) =>
      controlRow({ path: `${p.path}[${k}]`, label: `${label} ${c}`, kind: 'slider', min, max, step, title }, (value) => {
        const now = this.param(p.path)?.value ?? p.value;
        this.send({ type: 'set_override', path: p.path, value: now.map((x, i) => (i === k ? value : x)) });
      }),
    );
  }

  param(path) {
    return this.report?.materials[this.selected]?.params.find((p) => p.path === path);
  }

  /** The selected instance's values into its controls (not a focused one). */
  values() {
    for (const p of this.report?.materials[this.selected]?.params ?? []) {
      if (p.type === 'texture' || p.path === null) continue;
      const parts = Array.isArray(p.value) ? p.value.map((v, k) => [`${p.path}[${k}]`, v]) : [[p.path, p.value]];
      for (const [path, v] of parts) {
        const input = this.params.querySelector(`[data-path="${CSS.escape(path)}"]`);
        const entry = this.params.querySelector(`[data-entry="${CSS.escape(path)}"]`);
        if (entry && document.activeElement !== entry) entry.value = String(v);
        if (input && document.activeElement !== input) input.value = String(v);
      }
    }
  }

  /** The inspector pinned pixel `p` of an image `size` big (null: unpinned). */
  pin(p, size) {
    this.pinned = p && size ? { p, size } : null;
    this.want(this.pinned ? [MATERIAL] : []);
    if (!this.pinned) this.showPixel(null);
    this.lookUp();
  }

  onCapture(header, bytes) {
    if (header.pass !== MATERIAL.pass || header.output !== MATERIAL.output || header.encoding !== 'f32') return;
    if (bytes.byteLength !== header.width * header.height * 16) return;
    this.material = { data: new Float32Array(bytes.buffer, bytes.byteOffset, bytes.byteLength / 4), width: header.width, height: header.height };
    this.lookUp();
  }

  /** The pinned pixel's material, once both it and the G-buffer are here. */
  lookUp() {
    const g = this.material;
    if (!this.pinned || !g || !this.report) return;
    const { p, size } = this.pinned;
    // The inspected image may be another size than the G-buffer.
    const x = Math.min(g.width - 1, Math.floor(((p.x + 0.5) * g.width) / size.width));
    const y = Math.min(g.height - 1, Math.floor(((p.y + 0.5) * g.height) / size.height));
    const base = (y * g.width + x) * 4;
    // w = 0: no surface drew here (the sky).
    const index = g.data[base + 3] > 0 ? Math.round(g.data[base + 2]) : null;
    this.showPixel(index === null ? { x, y } : { x, y, index });
  }

  showPixel(at) {
    const node = this.pixel;
    for (const k of ['index', 'name', 'node']) delete node.dataset[k];
    node.hidden = !at;
    if (!at) return;
    const m = at.index === undefined ? null : this.report.materials[at.index];
    if (!m) {
      node.textContent = `(${at.x}, ${at.y}) no material: background`;
      return;
    }
    const root = this.report.definitions[m.definition]?.root;
    Object.assign(node.dataset, { index: String(m.index), name: m.name, node: String(root) });
    node.replaceChildren(
      `(${at.x}, ${at.y}) material `,
      el('button', { type: 'button', class: 'link', onclick: () => this.select(m.index) }, m.name),
      ` · ${m.material} · node #${root} (root)`,
    );
    if (this.selected !== m.index) this.select(m.index);
  }
}

/** Node `id` and its subtree, as nested <details> (open). */
function node(byId, id) {
  const n = byId.get(id);
  if (!n) return el('div', { class: 'muted' }, `node #${id} missing`);
  const summary = el(
    'summary',
    {},
    el('b', {}, n.kind),
    ` #${n.id} · depth ${n.depth}`,
    n.features.length ? el('span', { class: 'muted' }, ` · ${n.features.join(', ')}`) : null,
  );
  const fields = n.fields.map((f) => el('div', { class: 'field' }, el('span', { class: 'muted' }, `${f.field}: `), el('code', {}, f.value_text)));
  return el('details', { open: true, 'data-node': n.id, 'data-kind': n.kind }, summary, ...fields, ...n.children.map((c) => node(byId, c)));
}

/** What `quality.material_bytes` did to the material: bytes and storage
 *  class before → after, the rules applied (each at the node of the full
 *  tree above that it collapsed or trimmed), the closures the raster keeps. */
function budgetRows(b, row) {
  if (!b) return [];
  const rules = b.rules.map((r) => `${r.rule} #${r.node} → ${r.bytes} B`).join(', ');
  return [
    ...row('budget', 'budget', `${b.bytes_before} → ${b.bytes_after} B/px of ${b.budget} (${b.class_before} → ${b.class_after})`),
    ...row('simplified', 'simplified', b.simplified ? `yes: ${rules}` : 'no (fits)'),
    ...row('closures_kept', 'closures kept', `${b.closures_kept}`),
  ];
}

function reportRows(def) {
  const row = (key, label, value) => [el('dt', {}, label), el('dd', { 'data-key': key }, value)];
  const energy = def.energy_conserving ? 'yes' : `no: ${def.energy_reasons.join('; ')}`;
  return [
    ...row('closures', 'closures', `${def.closures.length} (${def.closures.map((c) => `#${c}`).join(', ')})`),
    ...row('features', 'features', def.features.join(', ') || 'none'),
    ...row('energy', 'energy-conserving', energy),
    ...row('gbuffer', 'G-buffer', def.gbuffer_bytes_per_pixel === null ? '—' : `${def.gbuffer_bytes_per_pixel} B/px (material words and inspection targets)`),
    ...budgetRows(def.budget, row),
    ...row('wgsl', 'WGSL', def.wgsl_bytes === null ? '—' : `${def.wgsl_bytes} bytes`),
    ...row('compile', 'compile', def.compile_ms === null ? '—' : `${def.compile_ms.toFixed(2)} ms`),
  ];
}
