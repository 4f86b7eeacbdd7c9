// The problems panel: every diagnostic as `file:line:col: severity[code]:
// message`, with the source lines around it (fetched from /api/sources),
// the error line highlighted and carets under the column range.
//
// Locations are 1-based; columns count Unicode scalar values, which is
// what Array.from(string) splits into, so carets line up with the text.

import { el, errorText, plural } from './util.js';

const CONTEXT = 2; // lines shown before and after a label
const MAX_LINE = 400; // characters shown of a very long source line

export class DiagnosticsPanel {
  /**
   * @param {HTMLElement} container `#diagnostics`
   * @param {HTMLElement} countEl summary in the panel header
   * @param {(path: string) => Promise<string>} fetchSource
   */
  constructor(container, countEl, fetchSource) {
    this.container = container;
    this.countEl = countEl;
    this.fetchSource = fetchSource;
    /** path → Promise<string>; cleared on reload, when files change. */
    this.sources = new Map();
    this.key = null;
    this.list = [];
    this.render();
  }

  /** Forgets cached sources (all, or the files a reload touched). */
  invalidate(files) {
    if (!Array.isArray(files) || files.length === 0) this.sources.clear();
    else for (const f of files) this.sources.delete(f);
  }

  source(path) {
    let p = this.sources.get(path);
    if (!p) {
      p = this.fetchSource(path);
      this.sources.set(path, p);
      // A failed fetch must not be cached: the next render retries it.
      p.catch(() => {
        if (this.sources.get(path) === p) this.sources.delete(path);
      });
    }
    return p;
  }

  /**
   * Shows a new set. Unchanged sets are not re-rendered, so the several
   * events of one reload do not make the panel flicker.
   */
  set(diagnostics, { force = false } = {}) {
    const list = Array.isArray(diagnostics) ? diagnostics : [];
    const key = JSON.stringify(list);
    if (!force && key === this.key) return;
    this.key = key;
    this.list = list;
    this.render();
  }

  render() {
    const list = this.list;
    const errors = list.filter((d) => d.severity === 'error').length;
    const warnings = list.filter((d) => d.severity === 'warning').length;
    const others = list.length - errors - warnings;
    const parts = [];
    if (errors) parts.push(plural(errors, 'error'));
    if (warnings) parts.push(plural(warnings, 'warning'));
    if (others) parts.push(plural(others, 'note'));
    this.countEl.textContent = parts.length ? parts.join(', ') : 'no problems';
    this.countEl.dataset.errors = String(errors);
    this.countEl.dataset.warnings = String(warnings);
    this.container.dataset.count = String(list.length);
    this.container.closest('.panel')?.classList.toggle('has-problems', list.length > 0);

    if (list.length === 0) {
      this.container.replaceChildren(el('div', { class: 'empty' }, 'No problems. Every shader compiled.'));
      return;
    }
    this.container.replaceChildren(...list.map((d) => this.item(d)));
  }

  item(d) {
    const loc = d.location || null;
    const severity = ['error', 'warning', 'note'].includes(d.severity) ? d.severity : 'error';
    const where = loc ? `${loc.file}:${loc.line}:${loc.column}` : null;
    const excerpt = el('div', { class: 'excerpt-holder' });
    const node = el(
      'div',
      {
        class: `diagnostic ${severity}`,
        dataset: loc
          ? {
              file: loc.file,
              line: String(loc.line),
              column: String(loc.column),
              severity,
              code: d.code || '',
            }
          : { severity, code: d.code || '' },
      },
      el(
        'div',
        { class: 'diag-head' },
        where ? el('span', { class: 'diag-loc', title: 'click to copy' }, where) : null,
        where ? ': ' : null,
        el('span', { class: `diag-sev ${severity}` }, `${severity}[${d.code || '?'}]`),
        ': ',
        el('span', { class: 'diag-msg' }, d.message || ''),
      ),
      excerpt,
      Array.isArray(d.notes) && d.notes.length
        ? el(
            'ul',
            { class: 'diag-notes' },
            d.notes.map((n) => el('li', {}, el('span', { class: 'note-tag' }, 'note: '), n)),
          )
        : null,
    );
    const locEl = node.querySelector('.diag-loc');
    if (locEl) {
      // Copying `file:line:col` is the quickest way into an editor.
      locEl.addEventListener('click', () => {
        navigator.clipboard?.writeText(where).catch(() => {});
      });
    }
    if (loc) this.fillExcerpt(excerpt, d, loc);
    return node;
  }

  /** Spans to draw: the labels, or the bare location when there are none. */
  spans(d, loc) {
    const labels = Array.isArray(d.labels) ? d.labels.filter((l) => l && l.file) : [];
    if (labels.length === 0) return [{ ...loc, message: '', primary: true }];
    if (!labels.some((l) => l.primary)) labels.unshift({ ...loc, message: '', primary: true });
    return labels;
  }

  async fillExcerpt(holder, d, loc) {
    const spans = this.spans(d, loc);
    // Primary file first, then any other file a label points into.
    const files = [loc.file, ...new Set(spans.map((s) => s.file).filter((f) => f !== loc.file))];
    holder.replaceChildren(el('div', { class: 'excerpt-loading' }, `loading ${loc.file}…`));
    const blocks = [];
    for (const file of files) {
      let text;
      try {
        text = await this.source(file);
      } catch (err) {
        blocks.push(el('div', { class: 'excerpt-error' }, `source unavailable: ${errorText(err)}`));
        continue;
      }
      const fileSpans = spans.filter((s) => s.file === file);
      if (file !== loc.file) blocks.push(el('div', { class: 'excerpt-file' }, `--> ${file}`));
      blocks.push(renderExcerpt(text, fileSpans));
    }
    holder.replaceChildren(...blocks);
  }
}

/**
 * Renders the lines of `text` around `spans` (same file), merging nearby
 * windows. Exported for reuse by anything that wants an excerpt.
 */
export function renderExcerpt(text, spans) {
  const lines = text.split(/\r?\n/);
  // A trailing newline does not make an extra line worth showing.
  if (lines.length > 1 && lines[lines.length - 1] === '') lines.pop();
  const last = lines.length;

  const beyond = spans.filter((s) => s.line > last);
  const shown = spans.filter((s) => s.line <= last);
  const windows = [];
  for (const s of [...shown].sort((a, b) => a.line - b.line)) {
    const from = Math.max(1, s.line - CONTEXT);
    const to = Math.min(last, Math.max(s.line, Math.min(s.end_line || s.line, last)) + CONTEXT);
    const prev = windows[windows.length - 1];
    if (prev && from <= prev.to + 1) prev.to = Math.max(prev.to, to);
    else windows.push({ from, to });
  }

  const width = String(windows.length ? windows[windows.length - 1].to : 1).length;
  const rows = [];
  windows.forEach((w, wi) => {
    if (wi > 0) rows.push(el('div', { class: 'src-gap' }, el('span', { class: 'ln' }, '…'.padStart(width)), ''));
    for (let n = w.from; n <= w.to; n++) {
      const line = lines[n - 1] ?? '';
      const chars = Array.from(line);
      const shownChars = chars.length > MAX_LINE ? chars.slice(0, MAX_LINE).join('') + '…' : line;
      const covering = spans.filter((s) => n >= s.line && n <= Math.max(s.line, s.end_line || s.line));
      const primary = covering.some((s) => s.primary);
      const secondary = !primary && covering.length > 0;
      rows.push(
        el(
          'div',
          {
            class: `src-line${primary ? ' hl' : ''}${secondary ? ' hl-secondary' : ''}`,
            dataset: { line: String(n) },
          },
          el('span', { class: 'ln' }, String(n).padStart(width)),
          el('span', { class: 'code' }, shownChars),
        ),
      );
      // Markers only under the line where a span starts: it carries the
      // label's message; continuation lines are just highlighted.
      for (const s of spans.filter((s) => s.line === n)) rows.push(markerRow(chars, s, width));
    }
  });
  for (const s of beyond) {
    rows.push(
      el(
        'div',
        { class: 'src-gap' },
        `line ${s.line} is past the end of the file (${last} lines): the file changed since`,
      ),
    );
  }
  return el('div', { class: 'excerpt' }, rows);
}

/**
 * A row of carets (primary) or dashes (secondary) under columns
 * [column, end_column) of `chars`. Tabs before the span are copied so the
 * marker lines up with tab-indented code.
 */
function markerRow(chars, span, width) {
  const start = Math.max(1, span.column || 1);
  const sameLine = !span.end_line || span.end_line === span.line;
  let end = sameLine ? span.end_column || start : chars.length + 1;
  if (end <= start) end = start + 1; // a point location still gets one caret
  const prefix = chars
    .slice(0, start - 1)
    .map((c) => (c === '\t' ? '\t' : ' '))
    .join('');
  // Past the end of the line (a missing `;` at EOL) pad with spaces.
  const pad = ' '.repeat(Math.max(0, start - 1 - chars.length));
  const mark = (span.primary ? '^' : '-').repeat(Math.min(end - start, MAX_LINE));
  return el(
    'div',
    { class: `src-mark ${span.primary ? 'primary' : 'secondary'}` },
    el('span', { class: 'ln' }, ' '.repeat(width)),
    el('span', { class: 'code' }, prefix + pad, el('span', { class: 'caret' }, mark), span.message ? ` ${span.message}` : ''),
  );
}
