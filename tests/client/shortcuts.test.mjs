// shortcuts.js's pure parts: which key does what, when keys are typing,
// which choices a select offers, and that docs/serve.md lists every key.
import assert from 'node:assert/strict';
import { readFileSync } from 'node:fs';
import { test } from 'node:test';

import { actionFor, offers, SHORTCUTS, stepValue, typing } from '../../client/shortcuts.js';

const key = (k, extra = {}) => ({ key: k, ctrlKey: false, altKey: false, metaKey: false, target: { tagName: 'BODY' }, ...extra });
const select = (values, value, { disabled = [], hidden = [] } = {}) => ({
  value,
  disabled: false,
  options: values.map((v) => ({ value: v, disabled: disabled.includes(v), hidden: hidden.includes(v) })),
});

test('the inspector keys', () => {
  const want = { r: 'channel:r', g: 'channel:g', b: 'channel:b', a: 'channel:a', l: 'channel:luminance', c: 'channel:rgb' };
  for (const [k, action] of Object.entries(want)) assert.equal(actionFor(key(k)), action, k);
  assert.equal(actionFor(key('f')), 'fit');
  assert.equal(actionFor(key('1')), 'actual');
  assert.equal(actionFor(key('+')), 'zoom-in');
  assert.equal(actionFor(key('=')), 'zoom-in');
  assert.equal(actionFor(key('-')), 'zoom-out');
  assert.equal(actionFor(key(']')), 'next');
  assert.equal(actionFor(key('j')), 'next');
  assert.equal(actionFor(key('[')), 'previous');
  assert.equal(actionFor(key('?')), 'help');
  assert.equal(actionFor(key('Escape')), 'close');
  assert.equal(actionFor(key('x')), null);
  assert.equal(new Set(SHORTCUTS.flatMap((s) => s.keys)).size, SHORTCUTS.flatMap((s) => s.keys).length, 'no key twice');
});

test('no shortcut while typing or with a modifier held', () => {
  for (const target of [{ tagName: 'INPUT', type: 'number' }, { tagName: 'INPUT' }, { tagName: 'TEXTAREA' }, { tagName: 'SELECT' }, { tagName: 'DIV', isContentEditable: true }]) {
    assert.ok(typing(target), JSON.stringify(target));
    assert.equal(actionFor(key('r', { target })), null, JSON.stringify(target));
  }
  for (const target of [{ tagName: 'INPUT', type: 'checkbox' }, { tagName: 'BUTTON' }, { tagName: 'CANVAS' }, null]) {
    assert.ok(!typing(target), JSON.stringify(target));
    assert.equal(actionFor(key('r', { target })), 'channel:r');
  }
  for (const mod of ['ctrlKey', 'altKey', 'metaKey']) assert.equal(actionFor(key('r', { [mod]: true })), null, mod);
});

test('a channel the output lacks is not offered', () => {
  const channels = select(['rgb', 'r', 'g', 'b', 'a', 'luminance'], 'rgb', { disabled: ['g', 'b'], hidden: ['a'] });
  assert.ok(offers(channels, 'r'));
  for (const v of ['g', 'b', 'a', 'nope']) assert.ok(!offers(channels, v), v);
  assert.ok(!offers({ ...channels, disabled: true }, 'r'), 'a disabled select offers nothing');
});

test('next and previous step over what cannot be chosen, wrapping round', () => {
  const outputs = select(['', 'p/a', 'p/b', 'q/c', 'q/d'], 'p/b', { disabled: ['q/c'] });
  assert.equal(stepValue(outputs, 1), 'q/d');
  assert.equal(stepValue(outputs, -1), 'p/a');
  assert.equal(stepValue({ ...outputs, value: 'q/d' }, 1), 'p/a');
  assert.equal(stepValue({ ...outputs, value: '' }, 1), 'p/a', 'nothing chosen: the first');
  assert.equal(stepValue({ ...outputs, value: '' }, -1), 'q/d', 'nothing chosen: backwards, the last');
  assert.equal(stepValue(select(['', 'p/a'], 'p/a'), 1), null, 'no other output');
  assert.equal(stepValue({ ...outputs, disabled: true }, 1), null);
});

test('docs/serve.md lists every shortcut key', () => {
  const docs = readFileSync(new URL('../../docs/serve.md', import.meta.url), 'utf8');
  const table = docs.slice(docs.indexOf('| Key'));
  for (const s of SHORTCUTS) {
    for (const k of s.keys) assert.ok(table.includes(`\`${k === 'Escape' ? 'Esc' : k}\``), `docs/serve.md's shortcut table lacks \`${k}\``);
  }
});
