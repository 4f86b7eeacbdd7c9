// The scene panel: live controls for scene and quality values. A change is
// sent as an override (the scene re-renders with it; the file is not
// touched); "save to file" writes the overrides into the scene file, keeping
// its comments and layout; "reset" drops them.
//
// Each row's title lists the render passes the control affects.
//
// Test hooks: #controls [data-path] inputs (data-overridden when set),
// #save-scene, #reset-overrides, #overrides-count.

import { el } from './util.js';

export class ControlsPanel {
  /** `send(message)` sends a WebSocket message. */
  constructor(root, send) {
    this.root = root;
    this.send = send;
    this.report = null;
    this.form = root.querySelector('#controls');
    this.save = root.querySelector('#save-scene');
    this.reset = root.querySelector('#reset-overrides');
    this.count = root.querySelector('#overrides-count');
    this.save.addEventListener('click', () => this.send({ type: 'save_scene' }));
    this.reset.addEventListener('click', () => this.send({ type: 'clear_overrides' }));
  }

  /** Shows a `ControlsReport` (from `/api/controls` or a `controls` event). */
  apply(report) {
    if (!report || !Array.isArray(report.controls)) return;
    this.report = report;
    const overrides = report.overrides || {};
    const n = Object.keys(overrides).length;
    this.count.textContent = n ? `${n} unsaved` : 'as in the file';
    this.save.disabled = n === 0;
    this.reset.disabled = n === 0;
    // Rebuild only when the set of controls changed, so a slider being
    // dragged keeps its focus.
    const key = report.controls.map((c) => `${c.path}:${c.kind}`).join('|');
    if (key !== this.key) {
      this.key = key;
      this.form.replaceChildren(...report.controls.map((c) => this.row(c)));
    }
    for (const c of report.controls) {
      const input = this.form.querySelector(`[data-path="${CSS.escape(c.path)}"]`);
      if (!input) continue;
      input.toggleAttribute('data-overridden', c.path in overrides);
      if (document.activeElement === input) continue;
      if (c.kind === 'toggle') input.checked = Boolean(c.value);
      else input.value = String(c.value);
      const out = input.parentElement.querySelector('output');
      if (out) out.textContent = String(c.value);
    }
  }

  row(c) {
    const send = (value) => this.send({ type: 'set_override', path: c.path, value });
    let input;
    if (c.kind === 'slider') {
      const integer = Number.isInteger(c.step) && Number.isInteger(c.min);
      input = el('input', { type: 'range', min: c.min, max: c.max, step: c.step, 'data-path': c.path });
      input.addEventListener('change', () => send(integer ? Math.round(Number(input.value)) : Number(input.value)));
      input.addEventListener('input', () => {
        input.parentElement.querySelector('output').textContent = input.value;
      });
    } else if (c.kind === 'toggle') {
      input = el('input', { type: 'checkbox', 'data-path': c.path });
      input.addEventListener('change', () => send(input.checked));
    } else {
      input = el('select', { 'data-path': c.path }, ...c.options.map((o) => el('option', { value: o }, o)));
      input.addEventListener('change', () => send(input.value));
    }
    // The passes a control changes, on hover: what to watch in the pass list.
    const affects = Array.isArray(c.affects) && c.affects.length ? `affects: ${c.affects.join(', ')}` : null;
    return el('label', { class: 'control', title: affects }, el('span', { class: 'control-label', text: c.label }), input, c.kind === 'slider' ? el('output', { class: 'num' }) : null);
  }
}
