// Small DOM and formatting helpers shared by the panels. No dependencies:
// the page is embedded in the loupe binary and must work offline.

/**
 * Creates an element. `attrs` keys: `class`, `text`, `dataset` (object),
 * `on<event>` (listener), anything else becomes an attribute. Children may
 * be nodes, strings, or null/false (skipped), so callers can write
 * conditional children inline.
 */
export function el(tag, attrs = {}, ...children) {
  const node = document.createElement(tag);
  for (const [key, value] of Object.entries(attrs)) {
    if (value === undefined || value === null || value === false) continue;
    if (key === 'class') node.className = value;
    else if (key === 'text') node.textContent = value;
    else if (key === 'dataset') Object.assign(node.dataset, value);
    else if (key.startsWith('on') && typeof value === 'function') node.addEventListener(key.slice(2), value);
    else node.setAttribute(key, value === true ? '' : String(value));
  }
  append(node, children);
  return node;
}

function append(node, children) {
  for (const child of children) {
    if (child === null || child === undefined || child === false) continue;
    if (Array.isArray(child)) append(node, child);
    else node.append(child instanceof Node ? child : String(child));
  }
}

export function $(id) {
  const node = document.getElementById(id);
  if (!node) throw new Error(`index.html lacks #${id}`);
  return node;
}

/** Milliseconds with a precision that suits their size. */
export function formatMs(ms) {
  if (ms === null || ms === undefined || !Number.isFinite(ms)) return '—';
  if (ms >= 100) return ms.toFixed(0);
  if (ms >= 10) return ms.toFixed(1);
  if (ms >= 1) return ms.toFixed(2);
  return ms.toFixed(3);
}

export function plural(n, word) {
  return `${n} ${word}${n === 1 ? '' : 's'}`;
}

/** Encodes a relative path for a URL, segment by segment, keeping slashes. */
export function encodePath(path) {
  return String(path).split('/').map(encodeURIComponent).join('/');
}

/** Message of anything thrown, for display. */
export function errorText(err) {
  if (err && typeof err.message === 'string') return err.message;
  return String(err);
}

/**
 * Wraps an async function so that only the newest call's result is
 * delivered: responses of overlapping requests can arrive out of order, and
 * an older snapshot must never overwrite a newer one.
 */
export function latestOnly(fn, deliver, onError) {
  let seq = 0;
  return async (...args) => {
    const mine = ++seq;
    try {
      const result = await fn(...args);
      if (mine === seq) deliver(result);
    } catch (err) {
      if (mine === seq) onError(err);
    }
  };
}

/**
 * Coalesces bursts of calls into one, `delay` ms after the first: a reload
 * emits several events that each ask for the same refetch.
 */
export function coalesce(fn, delay = 30) {
  let timer = null;
  return () => {
    if (timer !== null) return;
    timer = setTimeout(() => {
      timer = null;
      fn();
    }, delay);
  };
}

/** Host names of a page served from this machine. */
const LOOPBACK = new Set(['127.0.0.1', 'localhost', '[::1]', '::1']);

/**
 * A button for an action that writes project files. It is offered only on
 * a page served from loopback (the server refuses any other client): null
 * elsewhere. A click asks `confirm(question)` first; the button is disabled
 * while `run()` goes, and a failure goes to `notify` and enables it again.
 */
export function writeButton({ cls, label, title, question, run, confirm, notify }) {
  if (!LOOPBACK.has(location.hostname)) return null;
  const button = el('button', { class: cls, type: 'button', title }, label);
  button.addEventListener('click', async () => {
    if (!confirm(question())) return;
    button.disabled = true;
    try {
      await run();
    } catch (err) {
      notify(`${label} failed: ${err.message ?? err}`, 'error');
      button.disabled = false;
    }
  });
  return button;
}
