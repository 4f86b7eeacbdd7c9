// The page's layout: two columns of panels that hold at any ordinary window
// size. Each panel scrolls inside itself (style.css); this module adds
//   - a splitter between the columns and one between each two visible panels
//     of a column, dragged to resize and double-clicked to go back to the
//     default sizes (of that column, or the columns' widths);
//   - collapsing: a chevron in each panel's head (or a click on its title)
//     folds the panel to its head;
//   - memory: the left column's width, the panels' sizes and which panels
//     are collapsed, per browser (localStorage, key STORE);
//   - placeBeside / float: a floating tip placed inside the viewport, beside
//     (never over) the element that opened it.
//
// Panel sizes are flex weights in pixels: dragging first pins every open
// panel of the column at its current height (flex-grow = height, basis 0, so
// nothing moves), then moves the boundary between the two panels beside the
// splitter. A window resize keeps the proportions.
//
// Test hooks: .splitter (between columns .splitter.columns; in a column
// .splitter[data-above][data-below]), .panel.collapsed, .panel[data-sized],
// button.collapse[aria-expanded], localStorage['loupe.layout'].

const STORE = 'loupe.layout';
/** The narrowest a column may be dragged to, in CSS pixels. */
const MIN_COLUMN = 260;

/** Where a box of `size` ({width, height}) goes beside `anchor` (a rect:
 * left, top, right, bottom) inside `view` ({width, height}): the first side,
 * of right, left, below and above, where it fits whole, `gap` away; failing
 * all, the side with the most room, clamped into the view. Returns
 * {left, top}. */
export function placeBeside(anchor, size, view, gap = 8) {
  const clamp = (v, lo, hi) => Math.max(lo, Math.min(v, Math.max(lo, hi)));
  const middleY = clamp((anchor.top + anchor.bottom) / 2 - size.height / 2, 0, view.height - size.height);
  const middleX = clamp((anchor.left + anchor.right) / 2 - size.width / 2, 0, view.width - size.width);
  const sides = [
    { room: view.width - anchor.right - gap, need: size.width, at: { left: anchor.right + gap, top: middleY } },
    { room: anchor.left - gap, need: size.width, at: { left: anchor.left - gap - size.width, top: middleY } },
    { room: view.height - anchor.bottom - gap, need: size.height, at: { left: middleX, top: anchor.bottom + gap } },
    { room: anchor.top - gap, need: size.height, at: { left: middleX, top: anchor.top - gap - size.height } },
  ];
  const fits = sides.find((s) => s.room >= s.need);
  if (fits) return fits.at;
  const best = sides.reduce((a, b) => (b.room / b.need > a.room / a.need ? b : a));
  return { left: clamp(best.at.left, 0, view.width - size.width), top: clamp(best.at.top, 0, view.height - size.height) };
}

/** Shows `popup` (position: fixed) beside `anchor`, inside the viewport. */
export function float(popup, anchor) {
  popup.hidden = false;
  const size = popup.getBoundingClientRect();
  const at = placeBeside(anchor.getBoundingClientRect(), size, { width: innerWidth, height: innerHeight });
  popup.style.left = `${Math.round(at.left)}px`;
  popup.style.top = `${Math.round(at.top)}px`;
}

function load() {
  try {
    const saved = JSON.parse(localStorage.getItem(STORE) ?? '{}');
    return { left: saved.left ?? null, sizes: saved.sizes ?? {}, collapsed: saved.collapsed ?? [] };
  } catch {
    return { left: null, sizes: {}, collapsed: [] };
  }
}

export class Layout {
  /** `main`: the element holding the columns and their splitter. */
  constructor(main) {
    this.main = main;
    this.saved = load();
    this.columns = [...main.querySelectorAll(':scope > .column')];
    this.panels = this.columns.flatMap((c) => [...c.querySelectorAll(':scope > .panel')]);
    this.columnSplitter = main.querySelector(':scope > .splitter.columns');
    this.setLeft(this.saved.left);
    this.drag(this.columnSplitter, (e, start) => this.setLeft(start.left + e.clientX - start.x), () => ({
      x: 0,
      left: this.columns[0].getBoundingClientRect().width,
    }));
    this.columnSplitter.addEventListener('dblclick', () => {
      this.saved.left = null;
      this.setLeft(null);
      this.save();
    });
    for (const panel of this.panels) {
      this.addCollapse(panel);
      const px = this.saved.sizes[panel.id];
      if (px) this.size(panel, px);
    }
    // A panel shown or hidden (the tensor view, the quad table…) moves the
    // splitters.
    const watch = new MutationObserver(() => this.placeSplitters());
    for (const panel of this.panels) watch.observe(panel, { attributes: true, attributeFilter: ['hidden'] });
    this.placeSplitters();
  }

  save() {
    try {
      localStorage.setItem(STORE, JSON.stringify(this.saved));
    } catch {
      // Storage refused (private mode, quota): the layout holds for this page.
    }
  }

  setLeft(px) {
    if (px === null) {
      this.main.style.removeProperty('--left-width');
      return;
    }
    const max = this.main.getBoundingClientRect().width - MIN_COLUMN;
    const width = Math.round(Math.max(MIN_COLUMN, Math.min(px, max)));
    this.main.style.setProperty('--left-width', `${width}px`);
    this.saved.left = width;
  }

  /** A chevron in the panel's first head; a click on it or on the head's
   * title (or bare head) folds the panel to its head. */
  addCollapse(panel) {
    const head = panel.querySelector(':scope > .panel-head');
    if (!head) return;
    const button = document.createElement('button');
    button.type = 'button';
    button.className = 'collapse';
    head.prepend(button);
    this.setCollapsed(panel, this.saved.collapsed.includes(panel.id));
    head.addEventListener('click', (e) => {
      // A toolbar's bare background is not a title: a click between its
      // controls must not fold the inspector.
      const title = e.target === button || e.target.closest('h2') || (e.target === head && !head.classList.contains('toolbar'));
      if (!title) return;
      this.setCollapsed(panel, !panel.classList.contains('collapsed'));
      this.saved.collapsed = this.panels.filter((p) => p.classList.contains('collapsed')).map((p) => p.id);
      this.save();
    });
  }

  setCollapsed(panel, collapsed) {
    panel.classList.toggle('collapsed', collapsed);
    const button = panel.querySelector(':scope > .panel-head > button.collapse');
    const name = panel.querySelector('h2')?.textContent.trim() || panel.id;
    button.setAttribute('aria-expanded', String(!collapsed));
    button.setAttribute('aria-label', `${collapsed ? 'expand' : 'collapse'} ${name}`);
    button.title = collapsed ? 'expand' : 'collapse to the title';
  }

  size(panel, px) {
    panel.style.flex = `${Math.round(px)} 1 0px`;
    panel.dataset.sized = '';
  }

  /** One splitter between each two visible panels of a column. A column
   * whose visible panels did not change keeps its splitters: the page sets
   * `hidden` again on every update, and a drag holds its splitter. */
  placeSplitters() {
    for (const column of this.columns) {
      const shown = [...column.querySelectorAll(':scope > .panel')].filter((p) => !p.hidden);
      const splitters = [...column.querySelectorAll(':scope > .splitter')];
      const have = splitters.map((s) => `${s.dataset.above}/${s.dataset.below}`).join();
      const want = shown.slice(1).map((p, i) => `${shown[i].id}/${p.id}`).join();
      if (have === want) continue;
      for (const s of splitters) s.remove();
      for (let i = 1; i < shown.length; i++) {
        const splitter = document.createElement('div');
        splitter.className = 'splitter';
        splitter.setAttribute('role', 'separator');
        splitter.setAttribute('aria-orientation', 'horizontal');
        splitter.title = 'drag to resize · double-click for the default sizes';
        Object.assign(splitter.dataset, { above: shown[i - 1].id, below: shown[i].id });
        shown[i].before(splitter);
        this.rowSplitter(splitter, column);
      }
    }
  }

  rowSplitter(splitter, column) {
    const open = () => [...column.querySelectorAll(':scope > .panel')].filter((p) => !p.hidden && !p.classList.contains('collapsed'));
    this.drag(
      splitter,
      (e, start) => {
        if (!start.above || !start.below) return;
        const total = start.heights.get(start.above) + start.heights.get(start.below);
        const lo = parseFloat(getComputedStyle(start.above).minHeight) || 0;
        const hi = total - (parseFloat(getComputedStyle(start.below).minHeight) || 0);
        const above = Math.max(lo, Math.min(start.heights.get(start.above) + e.clientY - start.y, hi));
        this.size(start.above, above);
        this.size(start.below, total - above);
      },
      () => {
        // The nearest open panels on either side of the splitter.
        const panels = open();
        const before = (p) => splitter.compareDocumentPosition(p) & Node.DOCUMENT_POSITION_PRECEDING;
        const heights = new Map(panels.map((p) => [p, p.getBoundingClientRect().height]));
        for (const [p, h] of heights) this.size(p, h);
        return { y: 0, heights, above: panels.filter(before).at(-1), below: panels.find((p) => !before(p)) };
      },
      () => {
        for (const p of open()) this.saved.sizes[p.id] = Number(p.style.flexGrow);
      },
    );
    splitter.addEventListener('dblclick', () => {
      for (const p of column.querySelectorAll(':scope > .panel')) {
        p.style.removeProperty('flex');
        delete p.dataset.sized;
        delete this.saved.sizes[p.id];
      }
      this.save();
    });
  }

  /** Pointer dragging on `handle`: `begin()` returns the starting state
   * (its x, y are filled in), `move(event, start)` applies a position,
   * `end()` records the result before it is saved. */
  drag(handle, move, begin, end = () => {}) {
    handle.addEventListener('pointerdown', (e) => {
      if (e.button !== 0) return;
      e.preventDefault();
      const start = { ...begin(), x: e.clientX, y: e.clientY };
      handle.setPointerCapture?.(e.pointerId);
      document.body.classList.add('dragging');
      const onMove = (ev) => move(ev, start);
      const onUp = (ev) => {
        move(ev, start);
        handle.removeEventListener('pointermove', onMove);
        handle.removeEventListener('pointerup', onUp);
        handle.removeEventListener('pointercancel', onUp);
        document.body.classList.remove('dragging');
        end();
        this.save();
      };
      handle.addEventListener('pointermove', onMove);
      handle.addEventListener('pointerup', onUp);
      handle.addEventListener('pointercancel', onUp);
    });
  }
}
