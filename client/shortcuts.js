// Keyboard shortcuts of the inspector, and the `?` overlay that lists them.
//
// Each shortcut acts through the control it stands for (the channel
// select, the A select, the quad-map select, the fit and 1:1 buttons), so
// it does what that control does and nothing it cannot: a channel the
// output lacks (a disabled or hidden option, as a format's preset leaves
// it) or a disabled control makes the key do nothing. Keys are ignored
// while typing (a text field, a select, a textarea), with Ctrl, Alt or
// Meta held, while the list is open (only ? and Esc work then) and while
// the inspector is hidden (the tensor view has its place).
//
// SHORTCUTS is the one list: the overlay is built from it, and a node test
// checks that docs/serve.md's table names every key.
//
// Test hooks: #shortcuts-help (the overlay; [hidden] when closed) with one
// tr[data-action] per shortcut, #shortcuts-open (the toolbar's ? button).

import { $, el } from './util.js';

/** Every shortcut: the keys (as `KeyboardEvent.key`) and what it does. */
export const SHORTCUTS = [
  { keys: ['c'], action: 'channel:rgb', text: 'all channels (RGB, colour)' },
  { keys: ['r'], action: 'channel:r', text: 'red channel only' },
  { keys: ['g'], action: 'channel:g', text: 'green channel only' },
  { keys: ['b'], action: 'channel:b', text: 'blue channel only' },
  { keys: ['a'], action: 'channel:a', text: 'alpha channel only' },
  { keys: ['l'], action: 'channel:luminance', text: 'luminance' },
  { keys: ['f'], action: 'fit', text: 'fit the image to the view' },
  { keys: ['1'], action: 'actual', text: '1:1, one image pixel per device pixel' },
  { keys: ['+', '='], action: 'zoom-in', text: 'zoom in (×2 about the centre)' },
  { keys: ['-'], action: 'zoom-out', text: 'zoom out (÷2 about the centre)' },
  { keys: [']', 'j'], action: 'next', text: 'next output' },
  { keys: ['[', 'k'], action: 'previous', text: 'previous output' },
  { keys: ['o'], action: 'overlay', text: 'next quad map: none, quad overdraw, helper lanes (with quads on)' },
  { keys: ['?'], action: 'help', text: 'show or hide this list' },
  { keys: ['Escape'], action: 'close', text: 'close this list (on the image: unpin the pixel)' },
];

const BY_KEY = new Map(SHORTCUTS.flatMap((s) => s.keys.map((k) => [k, s.action])));

/** Input types a key press does not type into. */
const NOT_TEXT = new Set(['checkbox', 'radio', 'button', 'submit', 'reset', 'range', 'color', 'file', 'image']);

/** Whether key presses at `target` (an element or null) are typing. */
export function typing(target) {
  if (!target) return false;
  if (target.isContentEditable) return true;
  const tag = String(target.tagName || '').toUpperCase();
  if (tag === 'TEXTAREA' || tag === 'SELECT') return true;
  return tag === 'INPUT' && !NOT_TEXT.has(String(target.type || 'text').toLowerCase());
}

/** The action of a keydown event (or null): see the header for what is ignored. */
export function actionFor(e) {
  if (e.ctrlKey || e.altKey || e.metaKey || typing(e.target)) return null;
  return BY_KEY.get(e.key) ?? null;
}

/** Whether `select` offers `value` as a choice the user could make. */
export function offers(select, value) {
  if (select.disabled) return false;
  return Array.from(select.options).some((o) => o.value === value && !o.disabled && !o.hidden);
}

/**
 * The value `step` (+1 or −1) choices away from the selected one among the
 * options that can be chosen (enabled, shown, with a value), wrapping
 * round; null when there is no other.
 */
export function stepValue(select, step) {
  const choices = Array.from(select.options).filter((o) => o.value !== '' && !o.disabled && !o.hidden);
  if (select.disabled || !choices.length) return null;
  const at = choices.findIndex((o) => o.value === select.value);
  // Nothing chosen yet: the first choice forwards, the last backwards.
  const from = at >= 0 ? at : step > 0 ? -1 : choices.length;
  const next = choices[(from + step + choices.length) % choices.length];
  return next.value === select.value ? null : next.value;
}

/** Sets `select` to `value` as the user would: its change listeners run. */
function choose(select, value) {
  if (value === null || !offers(select, value)) return false;
  select.value = value;
  select.dispatchEvent(new Event('change'));
  return true;
}

function press(button) {
  if (button.disabled) return false;
  button.click();
  return true;
}

/**
 * Binds the shortcuts to the document; `inspector` is the Inspector
 * (zoomBy for + and −).
 */
export function bindShortcuts(inspector) {
  const help = helpOverlay();
  document.body.append(help.root);
  $('shortcuts-open')?.addEventListener('click', () => help.toggle());

  const run = {
    fit: () => press($('fit')),
    actual: () => press($('zoom-1')),
    'zoom-in': () => inspector.zoomBy(2),
    'zoom-out': () => inspector.zoomBy(0.5),
    next: () => choose($('inspect-a'), stepValue($('inspect-a'), 1)),
    previous: () => choose($('inspect-a'), stepValue($('inspect-a'), -1)),
    overlay: () => choose($('quad-overlay'), stepValue($('quad-overlay'), 1)),
  };
  document.addEventListener('keydown', (e) => {
    const action = actionFor(e);
    if (!action) return;
    let done = false;
    if (action === 'help') done = help.toggle();
    else if (action === 'close') done = help.close();
    else if (help.root.hidden && !$('inspector').hidden) {
      done = action.startsWith('channel:') ? choose($('channel'), action.slice('channel:'.length)) : run[action]() !== false;
    }
    if (done) e.preventDefault();
  });
}

/** The `?` overlay: a modal listing SHORTCUTS; Esc, ?, its button or a click outside closes it. */
function helpOverlay() {
  const name = (k) => (k === 'Escape' ? 'Esc' : k);
  const rows = SHORTCUTS.map((s) =>
    el(
      'tr',
      { dataset: { action: s.action } },
      el('td', {}, ...s.keys.flatMap((k, i) => [...(i ? [' or '] : []), el('kbd', {}, name(k))])),
      el('td', {}, s.text),
    ),
  );
  const closeButton = el('button', { type: 'button', class: 'tool', title: 'close (Esc)' }, 'close');
  const dialog = el(
    'div',
    { class: 'shortcuts-dialog', role: 'dialog', 'aria-modal': 'true', 'aria-labelledby': 'shortcuts-title', tabindex: '-1' },
    el('div', { class: 'shortcuts-head' }, el('h2', { id: 'shortcuts-title' }, 'Inspector shortcuts'), closeButton),
    el('table', {}, el('tbody', {}, rows)),
    el('p', { class: 'muted' }, 'Keys do nothing while typing in a field, and a channel the output lacks stays unselected.'),
  );
  const root = el('div', { id: 'shortcuts-help', class: 'shortcuts-backdrop', hidden: true }, dialog);
  let before = null; // focus to give back on closing
  const overlay = {
    root,
    open() {
      before = document.activeElement;
      root.hidden = false;
      dialog.focus();
      return true;
    },
    close() {
      if (root.hidden) return false;
      root.hidden = true;
      before?.focus?.();
      return true;
    },
    toggle: () => (root.hidden ? overlay.open() : overlay.close()),
  };
  closeButton.addEventListener('click', () => overlay.close());
  root.addEventListener('click', (e) => e.target === root && overlay.close());
  return overlay;
}
