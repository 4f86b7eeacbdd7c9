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

import { el, writeButton } from './util.js';

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
    const revert = writeButton({
      cls: 'revert',
      label: 'revert to last good',
      title: 'write the version that last compiled back to the file',
      question: () => `Write the last good version of ${d.file} over the file? Its current text is lost.`,
      run: () => this.hooks.revert(d.file),
      confirm: this.hooks.confirm,
      notify: this.hooks.notify,
    });
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
}
