// Where the inspected image sits on the canvas (zoom and pan), where the
// split divider is, and which pixel is selected (hovered or pinned); and
// the pointer and keys that change them. Positions are in the canvas's
// CSS pixels, pixels of the image are integers.

const MIN_SCALE = 1 / 64;
const MAX_SCALE = 512;
const DIVIDER_GRAB_PX = 6;

const clampScale = (s) => Math.min(MAX_SCALE, Math.max(MIN_SCALE, s));

export class View {
  scale = 1; // CSS px per image pixel
  tx = 0; // where the image's top-left corner is
  ty = 0;
  auto = true; // refit on resize until the user pans or zooms
  split = 0.5; // the split divider, a fraction of the width
  hover = null; // {x, y} image pixel under the mouse
  pinned = null; // {x, y} image pixel clicked

  /** Centres a width×height image in a w×h canvas, as large as fits. */
  fit(width, height, w, h) {
    let scale = Math.min(w / width, h / height) * 0.96;
    // Upscaled images get an integer zoom so pixels stay equal in size.
    if (scale > 1) scale = Math.floor(scale);
    this.scale = clampScale(scale);
    this.tx = Math.round((w - width * this.scale) / 2);
    this.ty = Math.round((h - height * this.scale) / 2);
    this.auto = true;
  }

  /** Zooms to `scale` keeping the image point under (ax, ay) fixed. */
  zoomAt(scale, ax, ay) {
    const s = clampScale(scale);
    this.tx = ax - ((ax - this.tx) * s) / this.scale;
    this.ty = ay - ((ay - this.ty) * s) / this.scale;
    this.scale = s;
    this.auto = false;
  }

  panBy(dx, dy) {
    this.tx += dx;
    this.ty += dy;
    this.auto = false;
  }

  /** Centres pixel (x, y) of a w×h canvas at a zoom of at least `minScale`. */
  centreOn(x, y, w, h, minScale) {
    this.scale = Math.max(this.scale, minScale);
    this.tx = w / 2 - (x + 0.5) * this.scale;
    this.ty = h / 2 - (y + 0.5) * this.scale;
    this.auto = false;
  }

  toPixel(p) {
    return { x: Math.floor((p.x - this.tx) / this.scale), y: Math.floor((p.y - this.ty) / this.scale) };
  }

  /** The range of pixels of a width×height image a w×h canvas shows. */
  visible(width, height, w, h) {
    const { scale, tx, ty } = this;
    return {
      x0: Math.max(0, Math.floor(-tx / scale)),
      y0: Math.max(0, Math.floor(-ty / scale)),
      x1: Math.min(width, Math.ceil((w - tx) / scale)),
      y1: Math.min(height, Math.ceil((h - ty) / scale)),
    };
  }

  /** Whether a canvas point of a canvas `w` wide grabs the split divider. */
  onDivider(p, w) {
    return Math.abs(p.x - this.split * w) <= DIVIDER_GRAB_PX;
  }
}

/**
 * Wheel zooms, drag pans (or moves the divider), a click pins a pixel,
 * arrows step the pinned pixel, Esc unpins; a double click fits (the
 * other keys are shortcuts.js's).
 *
 * @param {HTMLCanvasElement} canvas
 * @param {View} view
 * @param {object} host
 * @param {() => {w: number, h: number}} host.size the canvas in CSS px
 * @param {() => boolean} host.splitShown whether the divider is drawn
 * @param {(p: {x: number, y: number}) => boolean} host.inside whether an image pixel exists
 * @param {(p: {x: number, y: number} | null) => void} host.setHover
 * @param {() => void} host.selected the pinned pixel changed
 * @param {() => void} host.draw the view changed
 * @param {() => void} host.fit
 */
export function bindPointer(canvas, view, host) {
  const local = (e) => {
    const r = canvas.getBoundingClientRect();
    return { x: e.clientX - r.left, y: e.clientY - r.top };
  };
  const grabsDivider = (p) => host.splitShown() && view.onDivider(p, host.size().w);
  let drag = null;

  canvas.addEventListener(
    'wheel',
    (e) => {
      e.preventDefault();
      const p = local(e);
      const lines = e.deltaMode === 1 ? 33 : e.deltaMode === 2 ? 400 : 1;
      view.zoomAt(view.scale * Math.pow(2, (-e.deltaY * lines) / 240), p.x, p.y);
      host.draw();
      host.setHover(view.toPixel(p));
    },
    { passive: false },
  );
  canvas.addEventListener('pointerdown', (e) => {
    if (e.button !== 0) return;
    const p = local(e);
    drag = { kind: grabsDivider(p) ? 'split' : 'pan', start: p, last: p, moved: false };
    canvas.setPointerCapture(e.pointerId);
    canvas.focus({ preventScroll: true });
  });
  canvas.addEventListener('pointermove', (e) => {
    const p = local(e);
    if (drag) {
      if (Math.abs(p.x - drag.start.x) + Math.abs(p.y - drag.start.y) > 3) drag.moved = true;
      if (drag.kind === 'split') view.split = Math.min(1, Math.max(0, p.x / host.size().w));
      else if (drag.moved) view.panBy(p.x - drag.last.x, p.y - drag.last.y);
      drag.last = p;
      host.draw();
    }
    canvas.style.cursor = grabsDivider(p) || drag?.kind === 'split' ? 'ew-resize' : drag?.moved ? 'grabbing' : 'crosshair';
    host.setHover(view.toPixel(p));
  });
  const end = (e) => {
    const d = drag;
    drag = null;
    if (canvas.hasPointerCapture?.(e.pointerId)) canvas.releasePointerCapture(e.pointerId);
    // A click without a drag pins the pixel (or unpins it).
    if (d && d.kind === 'pan' && !d.moved && e.type === 'pointerup') {
      const px = view.toPixel(local(e));
      const same = view.pinned && view.pinned.x === px.x && view.pinned.y === px.y;
      view.pinned = same || !host.inside(px) ? null : px;
      host.selected();
    }
  };
  canvas.addEventListener('pointerup', end);
  canvas.addEventListener('pointercancel', end);
  canvas.addEventListener('pointerleave', () => {
    if (!drag) host.setHover(null);
  });
  canvas.addEventListener('dblclick', () => host.fit());
  canvas.addEventListener('keydown', (e) => {
    // f, 1 and the other inspector keys are document-wide (shortcuts.js).
    if (e.key === 'Escape') {
      view.pinned = null;
      host.selected();
    } else if (e.key.startsWith('Arrow') && view.pinned) {
      // Step the pinned pixel: reading neighbours without a steady hand.
      const d = { ArrowLeft: [-1, 0], ArrowRight: [1, 0], ArrowUp: [0, -1], ArrowDown: [0, 1] }[e.key];
      const next = { x: view.pinned.x + d[0], y: view.pinned.y + d[1] };
      if (host.inside(next)) view.pinned = next;
      e.preventDefault();
      host.selected();
    }
  });
}
