// layout.js's placement of floating tips (the rest needs a document).
import assert from 'node:assert/strict';
import { test } from 'node:test';

import { placeBeside } from '../../client/layout.js';

const view = { width: 1280, height: 720 };
const size = { width: 300, height: 200 };
const rect = (left, top, w = 10, h = 10) => ({ left, top, right: left + w, bottom: top + h });
const inside = (at) => at.left >= 0 && at.top >= 0 && at.left + size.width <= view.width && at.top + size.height <= view.height;
const covers = (at, a) => at.left < a.right && a.left < at.left + size.width && at.top < a.bottom && a.top < at.top + size.height;

test('a tip goes to the right of its anchor, centred on it, where it fits', () => {
  const a = rect(100, 300);
  assert.deepEqual(placeBeside(a, size, view), { left: 118, top: 205 });
});

test('near an edge it goes to the other side, and stays in the viewport', () => {
  for (const a of [rect(1200, 300), rect(1270, 0), rect(1270, 710), rect(0, 710), rect(640, 0)]) {
    const at = placeBeside(a, size, view);
    assert.ok(inside(at), `${JSON.stringify(a)} → ${JSON.stringify(at)}`);
    assert.ok(!covers(at, a), `${JSON.stringify(a)} → ${JSON.stringify(at)} covers its anchor`);
  }
});

test('a wide anchor (a row) gets the tip below or above it', () => {
  const a = rect(0, 100, 1280, 20);
  const at = placeBeside(a, size, view);
  assert.equal(at.top, 128);
  assert.ok(inside(at) && !covers(at, a));
});

test('with no room anywhere it is clamped into the viewport', () => {
  const at = placeBeside(rect(0, 0, 1280, 720), size, view);
  assert.ok(inside(at), JSON.stringify(at));
});
