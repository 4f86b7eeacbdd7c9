// The selected material full against a budget (`quality.material_bytes`),
// raster and path traced, with their difference: the Materials panel's
// simplification preview. For each renderer three figures: the full
// definition (`?budget=full`), the definition simplified to the budget
// (`?budget=N`) and |full − budget|, the mean over RGB of the tonemapped
// 8-bit images' absolute difference on the inspector's heat ramp
// (difference.js), whose top is DIFF_TOP of the display range (a fixed
// scale, so one budget's difference compares with another's); the caption
// gives the largest and the mean difference in 8-bit levels.
//
// It starts by itself for a material the report says was simplified, on
// request ("full against budget") otherwise. The budget is the scene's
// (it follows a changed `quality.material_bytes`) or one typed in the
// panel, which the server checks against the setting's range.
//
// Test hooks: #material-budget (hidden while off), #material-budget-compare
// (the checkbox), #material-budget-bytes (the budget), figures
// [data-variant="full"|"budget"][data-of="raster"|"path"] (preview_image.js
// hooks) and [data-variant="difference"][data-of] with data-state (idle,
// ready), data-key ("index:budget" it compared), data-max and data-mean
// (8-bit levels).

import { RAMP_CSS, heatMap } from './difference.js';
import { PreviewImage } from './preview_image.js';
import { el } from './util.js';

/** The difference at which the heat ramp tops out, as a share of the
 * display range: 32 levels of 255, so a simplification's small shifts show
 * and a lost lobe saturates. */
export const DIFF_TOP = 1 / 8;

/** |a − b| of two RGBA8 images of one size, as RGBA f32 in display units
 * (0–1) for `heatMap`, with its largest channel difference and its mean
 * over pixels and RGB, both in 8-bit levels. */
export function pixelDifference(a, b) {
  const diff = new Float32Array(a.length);
  let max = 0;
  let sum = 0;
  for (let i = 0; i < a.length; i++) {
    if (i % 4 === 3) continue;
    const d = Math.abs(a[i] - b[i]);
    diff[i] = d / 255;
    max = Math.max(max, d);
    sum += d;
  }
  return { diff, max, mean: sum / ((a.length / 4) * 3) };
}

async function pixels(blob) {
  const bitmap = await createImageBitmap(blob);
  const canvas = new OffscreenCanvas(bitmap.width, bitmap.height);
  const g = canvas.getContext('2d');
  g.drawImage(bitmap, 0, 0);
  return g.getImageData(0, 0, bitmap.width, bitmap.height);
}

export class BudgetPreview {
  /** `renderers`: [renderer, label] pairs. */
  constructor(renderers) {
    this.compare = el('input', { type: 'checkbox', id: 'material-budget-compare', onchange: () => ((this.asked = this.compare.checked), this.render()) });
    this.bytes = el('input', { type: 'number', id: 'material-budget-bytes', class: 'entry', title: 'bytes per pixel (quality.material_bytes)', onchange: () => this.render() });
    this.rows = renderers.map(([renderer, label]) => {
      const landed = () => this.difference(row);
      const row = {
        renderer,
        full: new PreviewImage(`${label}, full`, { 'data-variant': 'full', 'data-of': renderer }, landed),
        budget: new PreviewImage(`${label}, budget`, { 'data-variant': 'budget', 'data-of': renderer }, landed),
        canvas: el('canvas', { width: 128, height: 128 }),
        caption: el('figcaption', {}, '|full − budget|'),
      };
      row.figure = el('figure', { 'data-variant': 'difference', 'data-of': renderer, 'data-state': 'idle' }, row.canvas, row.caption);
      return row;
    });
    const legend = el('span', { class: 'muted', title: 'mean |Δ| over RGB of the 8-bit images' }, el('span', { class: 'ramp', style: `background:${RAMP_CSS}` }), ` 0 … ${Math.round(255 * DIFF_TOP)} levels`);
    this.grid = el('div', { class: 'budget-grid' }, ...this.rows.flatMap((r) => [r.full.figure, r.budget.figure, r.figure]));
    this.root = el(
      'div',
      { id: 'material-budget', hidden: true },
      el('label', {}, this.compare, ' full against budget '),
      this.bytes,
      ' B/px ',
      legend,
      this.grid,
    );
    this.asked = false;
    this.index = 0;
    this.sceneBudget = null;
  }

  /** Material `index`, whose definition's report `budget` (null: none)
   * says the scene's budget and whether it was simplified. */
  show(index, budget) {
    this.root.hidden = false;
    this.index = index;
    if (budget && budget.budget !== this.sceneBudget) {
      // The scene's budget moved (an override, the file): follow it.
      this.sceneBudget = budget.budget;
      this.bytes.value = String(budget.budget);
    }
    this.compare.checked = this.asked || Boolean(budget?.simplified);
    this.render();
  }

  render() {
    this.grid.hidden = !this.compare.checked;
    if (!this.compare.checked || this.bytes.value === '') return;
    for (const row of this.rows) {
      row.full.request(this.index, `renderer=${row.renderer}&budget=full`);
      row.budget.request(this.index, `renderer=${row.renderer}&budget=${encodeURIComponent(this.bytes.value)}`);
    }
  }

  /** Draws a renderer's difference once its full and budget images show
   * the same material. */
  async difference(row) {
    const [full, budget] = [row.full, row.budget];
    if (!full.shown || !budget.shown || full.shown.index !== budget.shown.index) return;
    const key = `${budget.shown.index}:${new URLSearchParams(budget.shown.query).get('budget')}`;
    const [a, b] = await Promise.all([pixels(full.blob), pixels(budget.blob)]);
    if (a.width !== b.width || a.height !== b.height) return;
    const { diff, max, mean } = pixelDifference(a.data, b.data);
    const out = new ImageData(a.width, a.height);
    heatMap(diff, DIFF_TOP, out.data);
    Object.assign(row.canvas, { width: a.width, height: a.height });
    row.canvas.getContext('2d').putImageData(out, 0, 0);
    row.caption.textContent = `|full − budget| · max ${max} · mean ${mean.toFixed(2)} levels`;
    Object.assign(row.figure.dataset, { state: 'ready', key, max: String(max), mean: mean.toFixed(3) });
  }
}
