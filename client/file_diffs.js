// What changed since the last good source: under the problems, each file
// that broke a pass (`GET /api/files`, the `files` event) with its diff
// against the version that last compiled, the failing lines marked, and a
// "revert to last good" button that writes that version back after a
// confirmation. The daemon refuses a revert from any address but loopback;
// the button is offered only on a page served from loopback.
//
// Test hooks: #file-diffs .file-diff[data-file], its rows
// .diff-line[data-tag= |-|+][data-old][data-new] (.failing where an error
// points), button.revert.

import { el } from './util.js';

/** Host names a page served on this machine has. */
const LOOPBACK = new Set(['127.0.0.1', 'localhost', '[::1]', '::1']);

/** The rows of a FileDiff: each hunk's lines, a gap between hunks. */
export function diffRows(diff) {
  const rows = [];
  (diff.hunks ?? []).forEach((h, i) => {
    if (i > 0) rows.push({ gap: true });
    for (const l of h.lines ?? []) rows.push({ tag: l.tag, old: l.old, new: l.new, text: l.text, failing: !!l.failing });
  });
  return rows;
}

export class FileDiffs {
  /**
   * @param {HTMLElement} container `#file-diffs`
   * @param {object} hooks {revert(file) → Promise, confirm(text) → bool, notify(text, kind)}
   */
  constructor(container, hooks) {
    this.container = container;
    this.hooks = hooks;
    this.key = null;
    this.canRevert = LOOPBACK.has(location.hostname);
    this.set([]);
  }

  /** Shows a new list of FileDiffs; an unchanged one is not redrawn. */
  set(files) {
    const list = Array.isArray(files) ? files : [];
    const key = JSON.stringify(list);
    if (key === this.key) return;
    this.key = key;
    this.container.hidden = list.length === 0;
    this.container.replaceChildren(...list.map((d) => this.file(d)));
  }

  file(d) {
    const width = String(Math.max(0, ...diffRows(d).map((r) => Math.max(r.old ?? 0, r.new ?? 0)))).length;
    const num = (n) => (n === null || n === undefined ? '' : String(n)).padStart(width);
    const rows = diffRows(d).map((r) =>
      r.gap
        ? el('div', { class: 'src-gap' }, '…')
        : el(
            'div',
            {
              class: `diff-line${r.tag === '-' ? ' del' : r.tag === '+' ? ' ins' : ''}${r.failing ? ' failing' : ''}`,
              dataset: { tag: r.tag, old: r.old ?? '', new: r.new ?? '' },
            },
            el('span', { class: 'ln' }, num(r.old)),
            el('span', { class: 'ln' }, num(r.new)),
            el('span', { class: 'code' }, `${r.tag} ${r.text}`),
          ),
    );
    const pipelines = (d.pipelines ?? []).join(', ');
    const revert = this.canRevert
      ? el('button', { class: 'revert', type: 'button', title: 'write the version that last compiled back to the file' }, 'revert to last good')
      : null;
    revert?.addEventListener('click', () => this.revert(d.file, revert));
    return el(
      'div',
      { class: 'file-diff', dataset: { file: d.file } },
      el(
        'div',
        { class: 'diag-head' },
        el('span', { class: 'diag-loc' }, d.file),
        ` changed since it last compiled${pipelines ? ` (not running: ${pipelines})` : ''} `,
        revert,
      ),
      el('div', { class: 'excerpt diff' }, rows),
    );
  }

  async revert(file, button) {
    if (!this.hooks.confirm(`Write the last good version of ${file} over the file? Its current text is lost.`)) return;
    button.disabled = true;
    try {
      await this.hooks.revert(file);
    } catch (err) {
      this.hooks.notify(`revert of ${file} failed: ${err.message ?? err}`, 'error');
      button.disabled = false;
    }
  }
}
