// "Against reference": loupe.toml's image cases of this scene (the ones
// `loupe check` gates on, docs/images.md) compared with their reviewed
// references after every save, so a developer sees an edit fail the gate
// before pushing. While the toggle is on the server renders the cases on a
// thread of its own (`reference_comparison`) and sends a `references` event
// when a comparison starts and when it ends; each case shows its verdict,
// FLIP's figures against its thresholds, and per output the actual image,
// the reference and FLIP's error map. "bless this" writes what is shown as
// the case's references after a confirmation; it is offered only on a page
// served from loopback (the server refuses others).
//
// Test hooks: #reference-on (toggle), #reference-body[data-generation]
// [data-comparing], .reference-case[data-case][data-verdict], its
// img.reference-image[data-kind=actual|reference|flip], .reference-figures,
// button.bless.

import { el, writeButton } from './util.js';

/** A case's figures in one line: each output's FLIP mean and p99 against the thresholds, and relMSE. */
export function figures(c) {
  const fmt = (v) => (v === null || v === undefined ? '—' : Number(v).toFixed(4));
  return (c.outputs ?? []).map((o) => {
    const f = o.flip;
    const mse = o.relative_mse === null || o.relative_mse === undefined ? '—' : Number(o.relative_mse).toExponential(2);
    return f
      ? `${o.output}: FLIP mean ${fmt(f.mean)} (≤ ${c.flip_mean}) · p99 ${fmt(f.p99)} (≤ ${c.flip_p99}) · relMSE ${mse}`
      : `${o.output}: nothing to compare with`;
  });
}

export class ReferenceView {
  /**
   * @param {object} els {toggle, body, meta}
   * @param {object} hooks {send(on), bless(case) → Promise, confirm(text) → bool, notify(text, kind)}
   */
  constructor(els, hooks) {
    this.els = els;
    this.hooks = hooks;
    els.toggle.addEventListener('change', () => this.setOn(els.toggle.checked));
    this.setOn(false);
  }

  setOn(on) {
    this.on = on;
    this.els.toggle.checked = on;
    this.hooks.send(on);
    this.els.body.hidden = !on;
    if (!on) this.els.meta.textContent = 'off';
    else this.els.meta.textContent = 'comparing…';
  }

  /** A `references` event or `GET /api/references`. */
  apply(report) {
    if (!this.on || !report) return;
    const body = this.els.body;
    body.dataset.generation = String(report.generation ?? 0);
    body.dataset.comparing = String(!!report.comparing);
    const cases = report.cases ?? [];
    const failed = cases.filter((c) => c.verdict !== 'passed').length;
    this.els.meta.textContent = report.comparing
      ? 'comparing…'
      : cases.length
        ? `${cases.length - failed} of ${cases.length} pass`
        : 'no case';
    if (report.config_error) {
      body.replaceChildren(el('div', { class: 'placeholder' }, `loupe.toml: ${report.config_error.message}`));
      return;
    }
    if (report.comparing && body.querySelector('.reference-case')) return; // keep the last results until new ones
    if (!cases.length) {
      body.replaceChildren(
        el('div', { class: 'placeholder' }, report.generation ? 'loupe.toml has no image case for this scene (docs/images.md).' : 'comparing…'),
      );
      return;
    }
    body.replaceChildren(...cases.map((c) => this.caseNode(c, report.generation)));
  }

  caseNode(c, generation) {
    const images = (c.outputs ?? []).map((o, i) =>
      el(
        'div',
        { class: 'reference-output' },
        el('div', { class: 'reference-output-name' }, o.output),
        el(
          'div',
          { class: 'reference-images' },
          ['actual', 'reference', 'flip'].map((kind) => {
            const shown = kind === 'actual' || o.flip;
            return shown
              ? el('figure', {},
                  el('img', {
                    class: 'reference-image',
                    dataset: { kind },
                    alt: `${c.name} ${o.output} ${kind}`,
                    src: `/api/references/${encodeURIComponent(c.name)}/${i}/${kind}.png?g=${generation}`,
                  }),
                  el('figcaption', {}, kind === 'flip' ? 'FLIP error' : kind))
              : null;
          }),
        ),
      ),
    );
    const bless = writeButton({
      cls: 'bless',
      label: 'bless this',
      title: "write the images shown as this case's references",
      question: () => `Write the images shown as the references of ${c.name}? Review and commit them after.`,
      run: () => this.hooks.bless(c.name),
      confirm: this.hooks.confirm,
      notify: this.hooks.notify,
    });
    return el(
      'div',
      { class: 'reference-case', dataset: { case: c.name, verdict: c.verdict } },
      el('div', { class: 'diag-head' }, el('span', { class: `verdict ${c.verdict}` }, c.verdict), ` ${c.name} `, bless),
      el('div', { class: 'reference-figures' }, figures(c).map((line) => el('div', {}, line))),
      (c.diagnostics ?? []).map((d) => el('div', { class: 'reference-problem' }, d.message)),
      images,
    );
  }
}
