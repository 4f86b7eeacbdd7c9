// Typed entry for a slider's value: what a person types beside a slider,
// read and checked against the slider's range before it becomes an
// override. DOM-free, so node --test covers it (tests/client/numeric_entry.test.mjs).

/** The range as the Scene panel shows it: `−24 … 24`. */
export function rangeText({ min, max }) {
  const n = (v) => String(v).replace('-', '−');
  return `${n(min)} … ${n(max)}`;
}

/**
 * Reads `text` for a slider `{min, max, step}`: `{value}` to send, or
 * `{error}` to show beside the entry (and nothing is sent). A slider whose
 * step and minimum are whole numbers takes whole numbers only. A typed
 * minus sign (−) reads as `-`.
 */
export function parseEntry(text, { min, max, step }) {
  const t = String(text).trim().replace('−', '-');
  if (t === '') return { error: `type a number from ${rangeText({ min, max })}` };
  const value = Number(t);
  if (!Number.isFinite(value)) return { error: `“${t}” is not a number: type one from ${rangeText({ min, max })}` };
  if (value < min || value > max) return { error: `${t} is out of range: ${rangeText({ min, max })}` };
  if (Number.isInteger(step) && Number.isInteger(min) && !Number.isInteger(value)) {
    return { error: `${t} is not a whole number` };
  }
  return { value };
}
