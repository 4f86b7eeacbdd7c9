// The pass list: one row per render-graph node with its status, why it is
// culled or failed, and its time as a bar on a frame timeline (each bar
// starts where the previous pass ended, so the list reads as a Gantt chart
// of the frame). Each time shows its clock (GPU, wall) or "n/a" with the
// reason as its title (timings.js); the head's total splits the frame's
// wall time into the passes' sum and the rest.
//
// Test hooks: li[data-timing=gpu|wall|none], .pass-time .ms, .pass-time
// .timing; the total's data-frame-ms, data-passes-ms, data-unattributed-ms.

import { el, formatMs, plural } from './util.js';
import { frameTotal, hasSplit, passTime } from './timings.js';

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
    /** Newest time per pass ({time_ms, timing, timing_reason}): frame
     * events update it between pass lists. */
    this.times = new Map();
    /** The newest frame event carrying the frame's split, or null. */
    this.split = null;
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
    // The server's list carries the newest frame's times (or why not).
    for (const p of this.passes) this.times.set(p.name, p);
    const key = JSON.stringify(this.passes.map(({ time_ms, timing, timing_reason, ...rest }) => rest));
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
    for (const t of frame.passes) this.times.set(t.name, t);
    this.split = hasSplit(frame) ? frame : null;
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
        el('span', { class: 'pass-time' }, el('span', { class: 'ms' }, '—'), ' ', el('span', { class: 'timing' })),
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

  /** The figure a row's bar has: its measured time, or null. */
  figure(li) {
    const t = this.times.get(li.dataset.pass);
    return li.dataset.status !== 'culled' && passTime(t).kind !== 'none' ? t.time_ms : null;
  }

  /** Positions the bars on the frame timeline and fills in the times. */
  layoutBars() {
    const rows = [...this.list.querySelectorAll('li.pass')];
    const sum = rows.reduce((s, li) => s + (this.figure(li) ?? 0), 0);
    // The timeline is the frame's wall time: what no pass accounts for
    // is the space after the last bar.
    const total = Math.max(sum, this.split?.frame_ms ?? 0);
    let start = 0;
    for (const li of rows) {
      const t = this.figure(li);
      const shown = passTime(li.dataset.status === 'culled' ? null : this.times.get(li.dataset.pass));
      const ms = li.querySelector('.pass-time .ms');
      const clock = li.querySelector('.pass-time .timing');
      const fill = li.querySelector('.pass-bar-fill');
      li.dataset.timing = shown.kind;
      ms.textContent = shown.ms;
      ms.title = shown.title;
      clock.textContent = shown.clock;
      clock.title = shown.title;
      if (t !== null && total > 0) {
        fill.style.left = `${(start / total) * 100}%`;
        fill.style.width = `${(t / total) * 100}%`;
        fill.title = `${formatMs(t)} ms · ${((t / total) * 100).toFixed(1)}% of the frame`;
        start += t;
      } else {
        fill.style.width = '0';
        fill.title = '';
      }
    }
    const head = frameTotal(this.split);
    this.totalEl.textContent = head.text;
    this.totalEl.title = head.title;
    for (const [key, k] of [['frameMs', 'frame_ms'], ['passesMs', 'passes_ms'], ['unattributedMs', 'unattributed_ms']]) {
      if (this.split) this.totalEl.dataset[key] = String(this.split[k]);
      else delete this.totalEl.dataset[key];
    }
  }
}
