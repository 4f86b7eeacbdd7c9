// The denoiser's tensors at a glance: while a denoiser tensor is open,
// every `denoise.*` buffer is captured, and a table lists each one's shape,
// layout and statistics (over all channels, from the server's per-channel
// ones), its NaN / Inf counts and, with f16 storage, how many values its
// layer stored as Inf for being beyond f16's range (the pass's `overflow`
// buffer). Rows are in network order (the order of `/api/passes`), under a
// sticky header. Clicking a row opens that tensor.
//
// Test hooks: #tensor-list[data-count], rows tr[data-key="pass/output"].

import * as api from './api.js';
import { $, el } from './util.js';

/** A connection subscribes to at most 64 outputs (PROTOCOL.md, "Limits"),
 * the open tensor and the path view's among them: a larger network than
 * OIDN's has its first ones listed. */
const MAX_LISTED = 56;

export class TensorList {
  /** `subscribe(wanted)` captures these outputs; `open(pass, output)` shows one. */
  constructor(subscribe, open) {
    this.subscribe = subscribe;
    this.open = open;
    this.root = $('tensor-list');
    this.passes = [];
    this.on = false;
  }

  /** The newest pass list: what there is to capture. */
  setPasses(passes) {
    this.passes = passes;
    if (this.on) this.subscribe(this.wanted());
  }

  /** Lists the denoiser's tensors when `pass` is one of its passes, else
   * nothing; `pass/output` is the row marked as shown. */
  follow(pass, output) {
    this.on = pass?.startsWith('denoise') ?? false;
    this.shown = `${pass}/${output}`;
    this.root.hidden = !this.on;
    this.subscribe(this.on ? this.wanted() : []);
    if (this.on) this.refresh();
  }

  wanted() {
    return this.passes
      .filter((p) => p.name.startsWith('denoise') && p.status !== 'culled')
      .flatMap((p) => (p.writes || []).filter((w) => w.kind === 'buffer').map((w) => ({ pass: p.name, output: w.name })))
      .slice(0, MAX_LISTED);
  }

  async refresh() {
    if (!this.on) return;
    const all = await api.getJson('/api/tensors');
    const found = new Map(all.map((t) => [`${t.pass}/${t.output}`, t]));
    // In network order: the pass list's (graph) order, not the server's
    // alphabetical one.
    const rows = this.wanted()
      .map((w) => found.get(`${w.pass}/${w.output}`))
      .filter((t) => t && t.output !== 'overflow')
      .map((t) => this.row(t, found.get(`${t.pass}/overflow`)));
    this.root.dataset.count = String(rows.length);
    const head = ['tensor', 'shape', 'layout', 'min', 'max', 'mean', 'NaN', 'Inf', 'f16 overflow'];
    this.root.replaceChildren(el('table', {}, el('thead', {}, el('tr', {}, ...head.map((h) => el('th', { text: h })))), el('tbody', {}, ...rows)));
  }

  row(t, overflow) {
    const { dims, element } = t.layout;
    const s = t.stats;
    const cells = [
      `${t.pass}/${t.output}`,
      dims.map(([, n]) => n).join(' × '),
      `[${dims.map(([name]) => name).join(', ')}] ${element}`,
      fmt(Math.min(...s.min)),
      fmt(Math.max(...s.max)),
      // Every channel has as many elements: while all are finite (the
      // server's means are over finite values) the mean of means is the mean.
      fmt(s.mean.reduce((a, b) => a + b, 0) / s.mean.length),
      String(s.nan),
      String(s.inf),
      overflow ? String(overflow.stats.max[0]) : '—',
    ];
    const key = `${t.pass}/${t.output}`;
    return el('tr', { dataset: { key }, class: key === this.shown && 'selected', onclick: () => this.open(t.pass, t.output) }, ...cells.map((text) => el('td', { text })));
  }
}

function fmt(v) {
  return Number.isInteger(v) ? String(v) : v.toPrecision(4);
}
