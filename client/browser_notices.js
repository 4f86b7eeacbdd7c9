// Which window 'error' events are the browser's own notices rather than
// script errors: app.js shows every other one as a "client error".
// DOM-free (tests/client/browser_notices.test.mjs).
//
// "ResizeObserver loop completed with undelivered notifications" (and the
// older "ResizeObserver loop limit exceeded") says an observer's callback
// changed a layout it observes; the browser delivers the rest next frame.
// It carries no Error object: nothing in a script threw.
const NOTICES = [/^ResizeObserver loop (completed with undelivered notifications|limit exceeded)/];

/** Whether an ErrorEvent-like `{message, error}` is a browser notice. */
export function isBrowserNotice(event) {
  if (!event || event.error) return false;
  const message = String(event.message ?? '');
  return NOTICES.some((re) => re.test(message));
}
