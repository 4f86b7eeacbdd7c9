// The pinned pixel's history through the frame (the `pixel_history` event,
// docs/pixel-history.md): every pass that wrote or read the pixel, in frame
// order, with each output's value there before and after the pass, each
// fragment the raster passes' draws launched at it (depth, depth-test
// verdict, helper lane), the invocation of a per-pixel compute pass, and
// the denoiser's tensors there.
//
// DOM (tests read it): #history-panel .history-pass[data-pass] holding
// tr[data-output] (td.before, td.after), tr[data-fragment] with
// data-draw, data-primitive, data-verdict, data-helper, and
// tr[data-tensor].

import { el } from './util.js';
import { formatF32 } from './texture.js';

/** Channels shown per tensor row before "… N more". */
export const MAX_CHANNELS = 16;

/** An RGBA value as the panel shows it: exact, channels separated. */
export function formatValue(v) {
  return v ? v.map(formatF32).join(', ') : 'not read';
}

/** What an output held before the pass (`origin`, `before`), in words or numbers. */
export function formatBefore(o) {
  switch (o?.origin) {
    case 'read':
      return formatValue(o.before);
    case 'cleared':
      return 'cleared';
    case 'undefined':
      return 'undefined (first write)';
    default:
      return 'not read';
  }
}

/**
 * The fragments of a raster pass's draws as rows, in submission order:
 * [{ draw, primitive, depth, verdict, helper }].
 */
export function fragmentRows(draws) {
  return (draws || []).flatMap((d) =>
    d.fragments.map((f) => ({ draw: d.name, primitive: f.primitive, depth: f.depth, verdict: f.verdict, helper: f.helper })),
  );
}

/** A verdict as the table says it. */
export function verdictText(f) {
  const words = { passed: 'passed', failed_depth: 'failed depth', not_tested: 'not tested', culled: 'culled' };
  return (words[f.verdict] ?? f.verdict) + (f.helper ? ' (helper lane)' : '');
}

/** Whether fragment row `f` is the pass's survivor (its output is `after`). */
export function isSurvivor(survivor, f) {
  return !!survivor && !f.helper && survivor.draw === f.draw && survivor.primitive === f.primitive;
}

export class HistoryPanel {
  /** `panel`: the section; its `.history-body` receives the passes. */
  constructor(panel) {
    this.panel = panel;
    this.body = panel.querySelector('.history-body');
    this.meta = panel.querySelector('.panel-meta');
    this.selected = null;
    this.last = '';
  }

  /** The pixel the server now records the history of (null: none). */
  select(at) {
    this.selected = at;
    this.last = '';
    this.panel.hidden = !at;
    this.body.replaceChildren();
    this.meta.textContent = at ? `(${at.x}, ${at.y}): waiting for a frame` : '';
  }

  /** A `pixel_history` event: shown when it is for the selected pixel. */
  set(ev) {
    const s = this.selected;
    if (!s || ev.pixel?.[0] !== s.x || ev.pixel?.[1] !== s.y) return;
    this.meta.textContent = `(${s.x}, ${s.y}) through frame ${ev.frame}`;
    const key = JSON.stringify(ev.passes);
    if (key === this.last) return;
    this.last = key;
    this.body.replaceChildren(...ev.passes.map((p) => this.pass(p)));
  }

  pass(p) {
    const head = el(
      'div',
      { class: 'history-pass-head' },
      el('span', { class: 'history-pass-name', text: p.pass }),
      el('span', { class: 'history-kind', text: p.kind }),
      p.invocation ? el('span', { class: 'num', text: `invocation (${p.invocation.join(', ')})` }) : '',
      p.inputs.length ? el('span', { class: 'history-inputs', text: `reads ${p.inputs.join(', ')}` }) : '',
    );
    const outputs = p.outputs.length
      ? el(
          'table',
          { class: 'history-table' },
          el('tr', {}, el('th', { text: 'output' }), el('th', { text: 'before' }), el('th', { text: 'after' })),
          p.outputs.map((o) =>
            el(
              'tr',
              { 'data-output': o.output },
              el('td', { text: `${o.output} [${o.texel[0]}, ${o.texel[1]}]` }),
              el('td', { class: 'before num', text: formatBefore(o) }),
              el('td', { class: 'after num', text: formatValue(o.after) }),
            ),
          ),
        )
      : '';
    const rows = fragmentRows(p.draws);
    const fragments =
      p.draws === null
        ? ''
        : rows.length
          ? el(
              'table',
              { class: 'history-table' },
              el('tr', {}, el('th', { text: 'draw' }), el('th', { text: 'primitive' }), el('th', { text: 'depth' }), el('th', { text: 'verdict' })),
              rows.map((f) =>
                el(
                  'tr',
                  {
                    class: isSurvivor(p.survivor, f) ? 'survivor' : '',
                    'data-fragment': '',
                    'data-draw': f.draw,
                    'data-primitive': String(f.primitive),
                    'data-verdict': f.verdict,
                    'data-helper': String(f.helper),
                  },
                  el('td', { text: f.draw }),
                  el('td', { class: 'num', text: String(f.primitive) }),
                  el('td', { class: 'num', text: f.depth === null ? '—' : formatF32(f.depth) }),
                  el('td', { class: `verdict ${f.verdict}`, text: verdictText(f) + (isSurvivor(p.survivor, f) ? ' → wrote the pixel' : '') }),
                ),
              ),
            )
          : el('div', { class: 'history-none', text: 'no draw launched a fragment here' });
    const tensors = p.tensors.length
      ? el(
          'table',
          { class: 'history-table' },
          el('tr', {}, el('th', { text: 'tensor' }), el('th', { text: 'channel → value' })),
          p.tensors.map((t) => {
            const shown = t.channels.slice(0, MAX_CHANNELS).map((v, c) => `${c}: ${formatF32(v)}`);
            const more = t.channels.length - shown.length;
            return el(
              'tr',
              { 'data-tensor': t.output },
              el('td', { text: `${t.output} [${t.at[0]}, ${t.at[1]}]` }),
              el('td', { class: 'num', text: shown.join('  ') + (more > 0 ? `  … ${more} more` : '') }),
            );
          }),
        )
      : '';
    return el('div', { class: 'history-pass', 'data-pass': p.pass }, head, outputs, fragments, tensors);
  }
}
