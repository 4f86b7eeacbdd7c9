// The diff rows of the "what changed since the last good source" view
// (client/file_diffs.js): every hunk's lines in order, a gap between hunks.
import { test } from 'node:test';
import assert from 'node:assert/strict';

import { diffRows } from '../../client/file_diffs.js';

test('hunks become rows with a gap between them, failing lines kept', () => {
  const line = (tag, old, now, text, failing = false) => ({ tag, old, new: now, text, failing });
  const diff = {
    file: 'shaders/a.wgsl',
    pipelines: ['a'],
    hunks: [
      { old_start: 1, new_start: 1, lines: [line(' ', 1, 1, 'x'), line('-', 2, null, 'y'), line('+', null, 2, 'Y(', true)] },
      { old_start: 20, new_start: 20, lines: [line('-', 20, null, 'z')] },
    ],
  };
  assert.deepEqual(diffRows(diff), [
    { tag: ' ', old: 1, new: 1, text: 'x', failing: false },
    { tag: '-', old: 2, new: null, text: 'y', failing: false },
    { tag: '+', old: null, new: 2, text: 'Y(', failing: true },
    { gap: true },
    { tag: '-', old: 20, new: null, text: 'z', failing: false },
  ]);
  assert.deepEqual(diffRows({ file: 'b', hunks: [] }), []);
});
