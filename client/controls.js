// The scene panel: live controls for scene and quality values. A change is
// sent as an override (the scene re-renders with it; the file is not
// touched); "save to file" writes the overrides into the scene file, keeping
// its comments and layout; "reset" drops them.
//
// Each row's title lists the render passes the control affects. A slider
// has a typed entry beside it, with its range: a value typed in range is
// sent as the override (Enter or leaving the field); anything else gets an
// inline message and sends nothing (numeric_entry.js reads it). A save
// answers with the file it wrote, or the file and why not (`scene_saved`).
//
// Test hooks: #controls [data-path] inputs (data-overridden when set),
// #controls [data-entry] typed entries and their .entry-error messages,
// #save-scene, #save-status, #reset-overrides, #overrides-count.

import { el } from './util.js';
import { parseEntry, rangeText } from './numeric_entry.js';

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
    this.status = el('div', { id: 'save-status', role: 'status', hidden: true });
    this.form.before(this.status);
    this.save.addEventListener('click', () => {
      this.status.hidden = true;
      this.send({ type: 'save_scene' });
    });
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
      const entry = input.parentElement.querySelector('[data-entry]');
      if (entry && document.activeElement !== entry) entry.value = String(c.value);
      if (document.activeElement === input) continue;
      if (c.kind === 'toggle') input.checked = Boolean(c.value);
      else input.value = String(c.value);
    }
  }

  /** A `scene_saved` event: the file written, or the file and why not. */
  saved({ file, error }) {
    this.status.hidden = false;
    this.status.className = error ? 'error' : 'ok';
    this.status.textContent = error ? `could not save ${file}: ${error}` : `saved to ${file}`;
  }

  row(c) {
    return controlRow(c, (value) => this.send({ type: 'set_override', path: c.path, value }));
  }
}

/**
 * One control's row: a slider with its typed entry, a toggle or a choice,
 * `c` a control as `/api/controls` gives it; `send(value)` sends a new
 * value. The materials panel builds its parameters' rows with it too.
 */
export function controlRow(c, send) {
  let input;
  if (c.kind === 'slider') {
    const integer = Number.isInteger(c.step) && Number.isInteger(c.min);
    input = el('input', { type: 'range', min: c.min, max: c.max, step: c.step, 'data-path': c.path });
    input.addEventListener('change', () => send(integer ? Math.round(Number(input.value)) : Number(input.value)));
    input.addEventListener('input', () => {
      input.parentElement.querySelector('[data-entry]').value = input.value;
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
  return el('label', { class: 'control', title: c.title ?? affects }, el('span', { class: 'control-label', text: c.label }), input, c.kind === 'slider' ? entry(c, send) : null);
}

/** The typed entry beside slider `c`, sending through `send`. */
function entry(c, send) {
  const input = el('input', { type: 'text', inputmode: 'decimal', class: 'num entry', 'data-entry': c.path, 'aria-label': `${c.label}, ${rangeText(c)}` });
  const message = el('span', { class: 'entry-error', role: 'alert', hidden: true });
  input.addEventListener('change', () => {
    const read = parseEntry(input.value, c);
    message.hidden = read.error === undefined;
    message.textContent = read.error ?? '';
    input.toggleAttribute('aria-invalid', read.error !== undefined);
    if (read.error === undefined) send(read.value);
  });
  return [input, el('span', { class: 'range', text: rangeText(c) }), message];
}
