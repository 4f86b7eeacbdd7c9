// The page's layout, checked in the page (layout.rs runs it): returns the
// list of violations, empty when the layout holds.
//  - the document does not scroll;
//  - every visible panel lies inside the viewport and is at least its
//    minimum height (a declared one, of 40 px or more), or collapsed;
//  - at sample points over each panel, the element on top belongs to that
//    panel, or to an open tooltip, menu or dialog;
//  - no element of a panel lies outside the panel's box unless an ancestor
//    inside the panel (the panel included) clips it;
//  - a panel does not scroll sideways, and nothing lies outside the head
//    (title bar or toolbar) it is in: a head that wraps grows;
//  - the top bar truncates nothing and open tooltips lie inside the viewport.
const floating = '[role=tooltip], [role=dialog], [role=menu], .popup';
const out = [];
const name = (e) => e.id ? `#${e.id}` : `${e.tagName.toLowerCase()}${e.className && typeof e.className === 'string' ? '.' + e.className.trim().split(/\s+/).join('.') : ''}`;
const path = (e, stop) => {
  const parts = [];
  for (let n = e; n && n !== stop && parts.length < 4; n = n.parentElement) parts.unshift(name(n));
  return parts.join(' > ');
};
const shown = (e) => e.getClientRects().length > 0 && getComputedStyle(e).visibility !== 'hidden';
const vw = innerWidth, vh = innerHeight;

for (const root of [document.documentElement, document.body]) {
  if (root.scrollHeight > root.clientHeight + 1 || root.scrollWidth > root.clientWidth + 1) {
    out.push(`the document scrolls: ${name(root)} ${root.scrollWidth}×${root.scrollHeight} in ${root.clientWidth}×${root.clientHeight}`);
  }
}

for (const panel of document.querySelectorAll('main .panel')) {
  if (!shown(panel)) continue;
  const id = name(panel);
  const r = panel.getBoundingClientRect();
  const collapsed = panel.classList.contains('collapsed');
  const min = parseFloat(getComputedStyle(panel).minHeight) || 0;
  if (!collapsed && min < 40) out.push(`${id} declares no minimum height (${getComputedStyle(panel).minHeight})`);
  if (!collapsed && r.height < min - 0.5) out.push(`${id} is ${r.height.toFixed(1)} px tall, under its minimum ${min} px`);
  if (r.left < -0.5 || r.top < -0.5 || r.right > vw + 0.5 || r.bottom > vh + 0.5) {
    out.push(`${id} lies outside the viewport: ${[r.left, r.top, r.right, r.bottom].map(Math.round)} in ${vw}×${vh}`);
  }
  if (!collapsed && panel.scrollWidth > panel.clientWidth + 1) {
    out.push(`${id} scrolls sideways: ${panel.scrollWidth} px of content in ${panel.clientWidth} px`);
  }
  for (const head of panel.querySelectorAll('.panel-head')) {
    if (!shown(head)) continue;
    const h = head.getBoundingClientRect();
    for (const e of head.querySelectorAll('*')) {
      const b = e.getBoundingClientRect();
      if (!shown(e) || e.closest(floating) || (b.width === 0 && b.height === 0)) continue;
      if (b.top < h.top - 1 || b.bottom > h.bottom + 1) {
        out.push(`${path(e, panel)} lies outside its head in ${id}: ${[b.top, b.bottom].map(Math.round)} outside ${[h.top, h.bottom].map(Math.round)}`);
      }
    }
  }
  // What is on top over the panel (inside the viewport).
  const [x0, x1] = [Math.max(r.left, 0) + 2, Math.min(r.right, vw) - 2];
  const [y0, y1] = [Math.max(r.top, 0) + 2, Math.min(r.bottom, vh) - 2];
  const steps = 7;
  for (let i = 0; i < steps && x1 > x0; i++) {
    for (let j = 0; j < steps && y1 > y0; j++) {
      const x = x0 + ((x1 - x0) * i) / (steps - 1);
      const y = y0 + ((y1 - y0) * j) / (steps - 1);
      const top = document.elementFromPoint(x, y);
      if (top && !panel.contains(top) && !top.closest(floating)) {
        out.push(`over ${id} at (${Math.round(x)}, ${Math.round(y)}): ${path(top)} is on top`);
      }
    }
  }
  // Content outside the panel's box, not clipped inside the panel.
  for (const e of panel.querySelectorAll('*')) {
    if (!shown(e) || e.closest(floating)) continue;
    const b = e.getBoundingClientRect();
    if (b.width === 0 && b.height === 0) continue;
    if (b.left >= r.left - 1 && b.top >= r.top - 1 && b.right <= r.right + 1 && b.bottom <= r.bottom + 1) continue;
    let clipped = false;
    if (getComputedStyle(e).position !== 'fixed') {
      for (let n = e.parentElement; n && !clipped; n = n === panel ? null : n.parentElement) {
        const s = getComputedStyle(n);
        clipped = s.overflowX !== 'visible' || s.overflowY !== 'visible';
      }
    }
    if (!clipped) {
      out.push(`${path(e, panel)} spills out of ${id}: ${[b.left, b.top, b.right, b.bottom].map(Math.round)} outside ${[r.left, r.top, r.right, r.bottom].map(Math.round)}`);
    }
  }
}

for (const e of document.querySelectorAll('#topbar, #topbar *')) {
  if (shown(e) && e.scrollWidth > e.clientWidth + 1 && getComputedStyle(e).overflowX !== 'visible') {
    out.push(`${path(e)} in the top bar is truncated: ${e.scrollWidth} px of text in ${e.clientWidth} px`);
  }
}
for (const e of document.querySelectorAll(floating)) {
  if (!shown(e)) continue;
  const b = e.getBoundingClientRect();
  if (b.left < -0.5 || b.top < -0.5 || b.right > vw + 0.5 || b.bottom > vh + 0.5) out.push(`${path(e)} lies outside the viewport`);
}
return out.slice(0, 40);
