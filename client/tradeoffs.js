// Accuracy against time: the newest `loupe bench tradeoffs` results for the
// project (`/api/tradeoffs`) as a Pareto chart, error (relative MSE against
// each series' reference) over time (the passes the setting affects), both
// axes logarithmic, one line per series; a point equal to its reference
// (no error to put on a log axis) sits hollow on the bottom edge. Hovering a point shows its
// settings, figures and image; clicking it applies its settings as
// overrides (one `set_override` per setting). The tip floats beside the
// point (layout.js `float`). The points whose settings
// are the scene's current values are marked.
//
// Whose results they are is the server's answer (X-Loupe-State, by the
// scene and a hash of the scene file and shader sources they measured):
// `current` ones are plotted and marked; `stale` ones (this scene, changed
// since) are plotted, said to be stale and never marked current;
// `other-scene` ones are not plotted, only named.
//
// Test hooks: #tradeoffs-panel, #tradeoffs-chart circle[data-series]
// [data-index][data-current], #tradeoffs-tip, #tradeoffs-text,
// #tradeoffs-image, #tradeoffs-meta, #tradeoffs-empty; snapshot().state.

import { el } from './util.js';
import { float } from './layout.js';

const SVG = 'http://www.w3.org/2000/svg';
const WIDTH = 520;
const HEIGHT = 300;
const PAD = { left: 52, right: 12, top: 12, bottom: 36 };
const RUN = 'run `loupe bench tradeoffs --scene <this scene>` in the project';
const COLORS = ['#4e9fff', '#ff6b6b', '#51cf66', '#fcc419', '#cc5de8', '#ff922b', '#22b8cf', '#adb5bd', '#94d82d', '#f783ac', '#748ffc', '#e8590c'];

function svg(tag, attrs = {}, text = null) {
  const node = document.createElementNS(SVG, tag);
  for (const [k, v] of Object.entries(attrs)) node.setAttribute(k, String(v));
  if (text !== null) node.textContent = text;
  return node;
}

/** A point's settings: the series' shared ones and its own value. */
export function pointOverrides(series, point) {
  return { ...series.with, [series.setting]: point.value };
}

/** Decades spanning the positive values, at least one. */
function decades(values) {
  const logs = values.filter((v) => v > 0 && Number.isFinite(v)).map(Math.log10);
  if (logs.length === 0) return [0, 1];
  const lo = Math.floor(Math.min(...logs));
  return [lo, Math.max(Math.ceil(Math.max(...logs)), lo + 1)];
}

export class TradeoffsView {
  /**
   * `hooks.send(message)`: a WebSocket command; `hooks.fetch()`: `{state,
   * results}` (api.tradeoffs: rejects with state `not-written` when there
   * are none).
   */
  constructor(elements, hooks) {
    Object.assign(this, elements);
    this.hooks = hooks;
    this.results = null;
    /** The server's word on whose the results are (null: none loaded). */
    this.state = null;
    /** Current value of each control, by path, as JSON. */
    this.current = new Map();
    this.refresh.addEventListener('click', () => this.load());
    this.chart.addEventListener('mouseleave', () => this.hideTip());
  }

  async load() {
    let message = null;
    try {
      const { state, results } = await this.hooks.fetch();
      this.state = state;
      this.results = state === 'other-scene' ? null : results;
      if (state === 'other-scene') message = `These results are for ${results?.scene ?? 'another scene'}, not this one: ${RUN}.`;
    } catch (e) {
      this.state = e?.state ?? null;
      this.results = null;
      message = e?.state === 'not-written' ? `No results yet: ${RUN}.` : (e?.message ?? String(e));
    }
    this.empty.hidden = message === null;
    this.empty.textContent = message ?? '';
    this.render();
  }

  /** The controls report: which points are the scene's current settings. */
  setControls(report) {
    if (!report || !Array.isArray(report.controls)) return;
    this.current = new Map(report.controls.map((c) => [c.path, JSON.stringify(c.value)]));
    this.mark();
  }

  isCurrent(series, point) {
    if (this.state !== 'current') return false;
    return Object.entries(pointOverrides(series, point)).every(([path, v]) => this.current.get(path) === JSON.stringify(v));
  }

  mark() {
    for (const c of this.chart.querySelectorAll('circle[data-series]')) {
      const series = this.results.series[Number(c.dataset.series)];
      const current = this.isCurrent(series, series.points[Number(c.dataset.index)]);
      c.dataset.current = String(current);
      c.setAttribute('r', current ? 6 : 4);
      c.setAttribute('stroke-width', current ? 2.5 : 1);
      c.setAttribute('fill', current && c.dataset.fill === 'none' ? '#fff' : c.dataset.fill);
    }
  }

  render() {
    this.chart.replaceChildren();
    const r = this.results;
    if (!r) {
      this.meta.textContent = '';
      return;
    }
    const stale = this.state === 'stale' ? ' · stale: the scene file or a shader changed since; run the sweep again' : '';
    this.meta.textContent = `${r.scene} · ${r.width}×${r.height} · ${r.adapter} (${r.timing} timing)${stale}`;
    this.meta.classList.toggle('stale', stale !== '');
    const plotted = (p) => p.time_ms > 0;
    const all = r.series.flatMap((s) => s.points.filter(plotted));
    const [x0, x1] = decades(all.map((p) => p.time_ms));
    const [y0, y1] = decades(all.map((p) => p.relative_mse));
    const error = (p) => (p.relative_mse > 0 ? p.relative_mse : 10 ** y0);
    const w = WIDTH - PAD.left - PAD.right;
    const h = HEIGHT - PAD.top - PAD.bottom;
    const x = (t) => PAD.left + ((Math.log10(t) - x0) / (x1 - x0)) * w;
    const y = (e) => PAD.top + ((y1 - Math.log10(e)) / (y1 - y0)) * h;
    const root = svg('svg', { viewBox: `0 0 ${WIDTH} ${HEIGHT}`, width: '100%', role: 'img', 'aria-label': 'relative MSE against time' });
    for (let d = x0; d <= x1; d++) {
      root.append(svg('line', { x1: x(10 ** d), x2: x(10 ** d), y1: PAD.top, y2: PAD.top + h, class: 'grid' }));
      root.append(svg('text', { x: x(10 ** d), y: PAD.top + h + 14, 'text-anchor': 'middle', class: 'tick' }, `1e${d}`));
    }
    for (let d = y0; d <= y1; d++) {
      root.append(svg('line', { x1: PAD.left, x2: PAD.left + w, y1: y(10 ** d), y2: y(10 ** d), class: 'grid' }));
      root.append(svg('text', { x: PAD.left - 4, y: y(10 ** d) + 4, 'text-anchor': 'end', class: 'tick' }, `1e${d}`));
    }
    root.append(svg('text', { x: PAD.left + w / 2, y: HEIGHT - 4, 'text-anchor': 'middle', class: 'axis' }, 'time of the affected passes (ms)'));
    const legend = el('div', { class: 'legend' });
    r.series.forEach((series, si) => {
      const color = COLORS[si % COLORS.length];
      const points = series.points.map((p, i) => [p, i]).filter(([p]) => plotted(p));
      if (points.length === 0) return;
      root.append(svg('polyline', { points: points.map(([p]) => `${x(p.time_ms)},${y(error(p))}`).join(' '), fill: 'none', stroke: color, 'stroke-width': 1.5 }));
      for (const [p, i] of points) {
        const exact = p.relative_mse === 0;
        const c = svg('circle', { cx: x(p.time_ms), cy: y(error(p)), r: 4, fill: exact ? 'none' : color, stroke: color, tabindex: 0 });
        c.dataset.fill = exact ? 'none' : color;
        c.dataset.series = String(si);
        c.dataset.index = String(i);
        c.addEventListener('mouseenter', () => this.showTip(series, p, c));
        c.addEventListener('focus', () => this.showTip(series, p, c));
        c.addEventListener('click', () => this.apply(series, p));
        root.append(c);
      }
      legend.append(el('span', { class: 'key' }, el('span', { class: 'swatch', style: `background:${color}` }), series.name));
    });
    this.chart.append(root, legend);
    this.mark();
  }

  showTip(series, point, circle) {
    const settings = Object.entries(pointOverrides(series, point)).map(([k, v]) => `${k} = ${JSON.stringify(v)}`);
    // JSON has no infinity: an image equal to its reference has no PSNR.
    const psnr = Number.isFinite(point.psnr_db) ? `${point.psnr_db.toFixed(1)} dB` : '∞';
    const error = point.relative_mse > 0 ? `relative MSE ${point.relative_mse.toExponential(2)}` : 'equal to the reference';
    this.text.replaceChildren(
      el('div', { class: 'tip-title', text: `${series.name}: ${JSON.stringify(point.value)}` }),
      el('div', { text: `${point.time_ms.toFixed(2)} ms (×${point.time_ratio.toFixed(2)} of the most accurate) · ${error} · PSNR ${psnr} · SSIM ${point.ssim.toFixed(4)}` }),
      el('div', { class: 'tip-settings', text: settings.join(' · ') }),
      el('div', { class: 'tip-hint', text: `reference: ${series.reference} · click to apply` }),
    );
    // A floating tip beside the point, inside the viewport; placed again
    // once the image has its size.
    this.image.onload = () => !this.tip.hidden && float(this.tip, circle);
    this.image.src = `/api/tradeoffs/${point.image}`;
    float(this.tip, circle);
    this.tip.dataset.series = circle.dataset.series;
    this.tip.dataset.index = circle.dataset.index;
  }

  hideTip() {
    this.tip.hidden = true;
  }

  apply(series, point) {
    for (const [path, value] of Object.entries(pointOverrides(series, point))) {
      this.hooks.send({ type: 'set_override', path, value });
    }
  }

  snapshot() {
    const circles = [...this.chart.querySelectorAll('circle[data-series]')];
    return {
      state: this.state,
      loaded: this.results !== null,
      points: circles.length,
      current: circles.filter((c) => c.dataset.current === 'true').map((c) => [Number(c.dataset.series), Number(c.dataset.index)]),
    };
  }
}
