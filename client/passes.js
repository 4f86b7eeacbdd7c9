// The pass list: one row per render-graph node with its status, why it is
// culled or failed, and its time as a bar on a frame timeline (each bar
// starts where the previous pass ended, so the list reads as a Gantt chart
// of the frame).

import { el, formatMs, plural } from './util.js';

const STATUS_TEXT = { ok: 'ok', stale: 'stale', failed: 'failed', culled: 'culled' };
const STATUS_HELP = {
  ok: 'rendering with its current pipelines',
  stale: 'its newest source failed; the last good pipeline still renders',
  failed: 'it has never built: it does not render',
  culled: 'not needed by this frame',
};

export class PassList {
  /**
   * @param {HTMLElement} list the `#passes` <ul>
   * @param {HTMLElement} totalEl where the frame total goes
   * @param {(pass: string, output: string) => void} onSelect
   */
  constructor(list, totalEl, onSelect) {
    this.list = list;
    this.totalEl = totalEl;
    this.onSelect = onSelect;
    this.passes = [];
    this.pipelines = new Map();
    this.selected = null;
    /** Newest time per pass: frame events update it between pass lists. */
    this.times = new Map();
    this.timing = '';
    this.totalMs = null;
    this.key = null;
  }

  setPipelines(pipelines) {
    const key = JSON.stringify(pipelines);
    if (key === this.pipelinesKey) return;
    this.pipelinesKey = key;
    this.pipelines = new Map(pipelines.map((p) => [p.name, p]));
    this.render(); // tooltips name pipeline generations
  }

  /**
   * A new pass list. The server sends one with every frame, so when only
   * the times changed the rows are kept (no flicker, no lost hover or
   * focus) and just the times and bars move. Returns whether the
   * structure (names, statuses, outputs...) changed.
   */
  set(passes) {
    this.passes = Array.isArray(passes) ? passes : [];
    for (const p of this.passes) {
      if (Number.isFinite(p.time_ms)) this.times.set(p.name, p.time_ms);
      // A list published between frames has no times: keep the last
      // frame's for passes that still render.
      else if (p.status !== 'ok' && p.status !== 'stale') this.times.delete(p.name);
    }
    const key = JSON.stringify(this.passes.map(({ time_ms, timing, ...rest }) => rest));
    if (key === this.key) {
      this.layoutBars();
      return false;
    }
    this.key = key;
    this.render();
    return true;
  }

  /** The newest quad report (null: off): totals under each raster pass. */
  setQuads(report) {
    this.quads = new Map((report?.passes ?? []).map((p) => [p.pass, p.quads]));
    for (const li of this.list.querySelectorAll('li.pass')) this.showQuads(li);
  }

  showQuads(li) {
    const q = this.quads?.get(li.dataset.pass);
    let node = li.querySelector('.pass-quads');
    if (!q) {
      node?.remove();
      return;
    }
    if (!node) {
      node = el('div', { class: 'pass-quads' });
      li.querySelector('.pass-bar').after(node);
    }
    const eff = q.quad_efficiency === null ? '—' : `${(q.quad_efficiency * 100).toFixed(1)} %`;
    node.textContent = `${q.quads.toLocaleString('en-US')} quads · ${q.helper_lanes.toLocaleString('en-US')} helper lanes · ${eff} efficient`;
    node.dataset.quads = q.quads;
  }

  /** A `frame` event: new times without a new pass list. */
  updateTimings(frame) {
    if (!Array.isArray(frame.passes)) return;
    for (const t of frame.passes) this.times.set(t.name, t.time_ms);
    if (frame.timing) this.timing = frame.timing;
    this.totalMs = Number.isFinite(frame.total_ms) ? frame.total_ms : null;
    this.layoutBars();
  }

  select(passName) {
    this.selected = passName;
    for (const li of this.list.children) {
      const on = li.dataset.pass === passName;
      li.classList.toggle('selected', on);
      li.setAttribute('aria-selected', on ? 'true' : 'false');
    }
  }

  render() {
    const rows = this.passes.map((pass) => this.row(pass));
    if (rows.length === 0) {
      rows.push(el('li', { class: 'empty' }, 'no passes yet'));
    }
    this.list.replaceChildren(...rows);
    for (const li of this.list.querySelectorAll('li.pass')) this.showQuads(li);
    this.layoutBars();
  }

  row(pass) {
    const status = STATUS_TEXT[pass.status] ? pass.status : 'failed';
    const outputs = Array.isArray(pass.writes) ? pass.writes : [];
    const pick = (output) => {
      if (output) this.onSelect(pass.name, output);
    };
    const pipelineInfo = (pass.pipelines || [])
      .map((name) => {
        const p = this.pipelines.get(name);
        return p ? `${name} (${p.shader}, gen ${p.generation}, ${p.status})` : name;
      })
      .join('\n');
    const title = [
      `${pass.name}: ${STATUS_HELP[status] || status}`,
      pipelineInfo && `pipelines:\n${pipelineInfo}`,
      pass.reads?.length ? `reads: ${pass.reads.join(', ')}` : null,
    ]
      .filter(Boolean)
      .join('\n');

    const li = el(
      'li',
      {
        class: `pass status-${status}${this.selected === pass.name ? ' selected' : ''}`,
        dataset: { pass: pass.name, status },
        tabindex: 0,
        role: 'option',
        'aria-selected': this.selected === pass.name ? 'true' : 'false',
        title,
        onclick: () => pick(outputs[0]?.name),
        onkeydown: (e) => {
          if (e.key === 'Enter' || e.key === ' ') {
            e.preventDefault();
            pick(outputs[0]?.name);
          }
        },
      },
      el(
        'div',
        { class: 'pass-row' },
        el('span', { class: `badge ${status}`, title: STATUS_HELP[status] }, status),
        el('span', { class: 'pass-name' }, pass.name),
        pass.diagnostics > 0
          ? el('span', { class: 'pass-diag', title: plural(pass.diagnostics, 'diagnostic') }, `⚠ ${pass.diagnostics}`)
          : null,
        el(
          'span',
          { class: 'pass-time' },
          el('span', { class: 'ms' }, '—'),
          ' ms ',
          el('span', { class: 'timing' }, pass.timing || ''),
        ),
      ),
      el('div', { class: 'pass-bar' }, el('div', { class: 'pass-bar-fill' })),
      pass.reason ? el('div', { class: 'pass-reason' }, pass.reason) : null,
      outputs.length
        ? el(
            'div',
            { class: 'pass-outputs' },
            outputs.map((o) =>
              el(
                'button',
                {
                  type: 'button',
                  class: 'chip',
                  dataset: { output: o.name },
                  title: `inspect ${pass.name}/${o.name}`,
                  onclick: (e) => {
                    e.stopPropagation();
                    pick(o.name);
                  },
                },
                o.name,
                el('span', { class: 'chip-meta' }, o.kind === 'buffer' && Array.isArray(o.shape)
                  ? ` ${o.format} [${o.shape.map((d) => d[1]).join('×')}]${o.history ? ' history' : ''}`
                  : ` ${o.format} ${o.width}×${o.height}`),
              ),
            ),
          )
        : null,
    );
    return li;
  }

  /** Positions the bars on the frame timeline and fills in the times. */
  layoutBars() {
    const rows = [...this.list.querySelectorAll('li.pass')];
    let sum = 0;
    for (const li of rows) {
      const t = this.times.get(li.dataset.pass);
      if (Number.isFinite(t) && li.dataset.status !== 'culled') sum += t;
    }
    const total = Math.max(sum, this.totalMs ?? 0);
    let start = 0;
    for (const li of rows) {
      const t = this.times.get(li.dataset.pass);
      const culled = li.dataset.status === 'culled';
      const ms = li.querySelector('.pass-time .ms');
      const timing = li.querySelector('.pass-time .timing');
      const fill = li.querySelector('.pass-bar-fill');
      const has = Number.isFinite(t) && !culled;
      ms.textContent = has ? formatMs(t) : '—';
      if (this.timing && timing) timing.textContent = this.timing;
      if (has && total > 0) {
        fill.style.left = `${(start / total) * 100}%`;
        fill.style.width = `${(t / total) * 100}%`;
        fill.title = `${formatMs(t)} ms · ${((t / total) * 100).toFixed(1)}% of the frame`;
        start += t;
      } else {
        fill.style.width = '0';
        fill.title = '';
      }
    }
    this.totalEl.textContent = total > 0 ? `${formatMs(total)} ms${this.timing ? ` ${this.timing}` : ''}` : '';
  }
}
