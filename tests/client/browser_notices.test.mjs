import test from 'node:test';
import assert from 'node:assert/strict';
import { isBrowserNotice } from '../../client/browser_notices.js';

test('the ResizeObserver loop notice is the browser talking', () => {
  assert.equal(isBrowserNotice({ message: 'ResizeObserver loop completed with undelivered notifications.', error: null }), true);
  assert.equal(isBrowserNotice({ message: 'ResizeObserver loop limit exceeded', error: undefined }), true);
});

test('a script error stays an error', () => {
  assert.equal(isBrowserNotice({ message: 'Uncaught TypeError: x is undefined', error: new TypeError('x') }), false);
  // Thrown by a script, even with that text, it is an error.
  assert.equal(isBrowserNotice({ message: 'ResizeObserver loop completed', error: new Error('ResizeObserver loop completed') }), false);
  assert.equal(isBrowserNotice({ message: 'Script error.', error: null }), false);
  assert.equal(isBrowserNotice(null), false);
});
