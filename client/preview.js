// The selected material's preview: a sphere wearing it under the scene's
// sky and directional lights, raster and path traced side by side
// (`GET /api/materials/{index}/preview`), and beneath them the material
// full against its budget (budget_preview.js). Previews start when the user
// asks, by selecting a material or by the "preview" button, not on page
// load: a page that never looks at materials costs the daemon nothing.
// From then on they render again when the selection or the materials
// report changes (a material file saved, an override set). Each image has at most one request in flight and one
// waiting (the newest), so dragging a slider never floods the daemon; a
// failed render keeps the last image and says why in its caption.
//
// Test hooks: #material-preview-start (the button), #material-preview
// figure[data-renderer] with data-state
// (rendering, ready, error), data-index (the material its image shows)
// and data-renders (renders landed so far); its img and figcaption.

import { BudgetPreview } from './budget_preview.js';
import { PreviewImage } from './preview_image.js';
import { el } from './util.js';

const RENDERERS = [
  ['raster', 'raster'],
  ['path', 'path traced'],
];

export class MaterialPreview {
  constructor(root) {
    this.images = RENDERERS.map(([renderer, label]) => Object.assign(new PreviewImage(label, { 'data-renderer': renderer }), { renderer }));
    this.index = 0;
    this.on = false;
    this.button = el('button', { type: 'button', class: 'tool', id: 'material-preview-start', onclick: () => this.start(this.index) }, 'preview');
    this.budget = new BudgetPreview(RENDERERS);
    for (const i of this.images) i.figure.hidden = true;
    root.replaceChildren(this.button, ...this.images.map((i) => i.figure), this.budget.root);
  }

  /** Turns previews on and renders material `index`. */
  start(index) {
    this.on = true;
    this.button.hidden = true;
    for (const i of this.images) i.figure.hidden = false;
    this.show(index);
  }

  /** Renders material `index`, raster and path traced, once previews are
   * on; `budget` is its definition's report `budget` (null: none), which
   * says whether the comparison with the full material starts by itself. */
  show(index, budget = this.budgetReport) {
    this.index = index;
    this.budgetReport = budget;
    if (!this.on) return;
    for (const image of this.images) image.request(index, `renderer=${image.renderer}`);
    this.budget.show(index, budget);
  }
}
