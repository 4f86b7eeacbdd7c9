// Draws the inspector's canvas: the tonemapped images with nearest-neighbour
// pixels under the view's zoom and pan (A, A|B split, or |A − B|), the
// overlay map, the pixel grid and the values inside pixels at high zoom,
// the hovered and pinned pixels, and the labels.
//
// A slot's floats are tonemapped into its off-screen canvas only when the
// data or the display options change (tonemapSlot); drawing puts that
// canvas on screen with the view transform, which is cheap.

import * as tex from './texture.js';

const GRID_MIN_SCALE = 16; // pixel grid from this zoom (CSS px per pixel)
const VALUES_MIN_SCALE = 84; // values written inside pixels from this zoom
const FONT = 'ui-monospace, SFMono-Regular, Menlo, Consolas, monospace';

/**
 * Tonemaps a slot's floats (or `src`, what they are shown as: depth as
 * distance) into its off-screen canvas (made on first use).
 */
export function tonemapSlot(slot, opts, src = slot.data) {
  if (!slot.canvas) {
    slot.canvas = document.createElement('canvas');
    slot.canvas.width = slot.width;
    slot.canvas.height = slot.height;
    slot.image = new ImageData(slot.width, slot.height);
  }
  tex.tonemap(src, slot.width, slot.height, opts, slot.image.data);
  slot.canvas.getContext('2d').putImageData(slot.image, 0, 0);
}

/**
 * @param {CanvasRenderingContext2D} ctx
 * @param {{w: number, h: number, dpr: number}} size the canvas in CSS px
 * @param {object} scene
 * @param {import('./inspector_view.js').View} scene.view
 * @param {'off' | 'split' | 'diff'} scene.mode
 * @param {object | null} scene.a slots: {width, height, data, canvas, image, key, lastGood}
 * @param {object | null} scene.b
 * @param {object | null} scene.diff
 * @param {object | null} scene.overlay {canvas, width, height}, drawn over A without a compare
 */
export function draw(ctx, { w, h, dpr }, scene) {
  const { view, mode, a, b, diff, overlay } = scene;
  ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
  ctx.clearRect(0, 0, w, h);
  ctx.imageSmoothingEnabled = false;
  const { scale, tx, ty } = view;
  const put = (slot) => {
    if (slot?.canvas) ctx.drawImage(slot.canvas, tx, ty, slot.width * scale, slot.height * scale);
  };
  const split = mode === 'split' && a && b;
  const splitX = view.split * w;

  if (mode === 'diff' && diff) put(diff);
  else if (split) {
    clipped(ctx, 0, splitX, h, () => put(a));
    clipped(ctx, splitX, w - splitX, h, () => put(b));
  } else put(a);
  if (overlay?.canvas && mode === 'off') put(overlay);

  const shown = mode === 'diff' && diff ? diff : a;
  if (shown) {
    ctx.strokeStyle = 'rgba(255,255,255,0.18)';
    ctx.lineWidth = 1;
    ctx.strokeRect(tx - 0.5, ty - 0.5, shown.width * scale + 1, shown.height * scale + 1);
    const range = view.visible(shown.width, shown.height, w, h);
    if (scale >= GRID_MIN_SCALE) drawGrid(ctx, view, range);
    if (scale >= VALUES_MIN_SCALE) drawValues(ctx, view, range, (cx) => (split && cx >= splitX ? b : shown));
    drawMarker(ctx, view, view.pinned, '#ffd33d');
    const { hover, pinned } = view;
    if (hover && (!pinned || hover.x !== pinned.x || hover.y !== pinned.y)) drawMarker(ctx, view, hover, 'rgba(255,255,255,0.85)');
  }

  if (split) {
    ctx.fillStyle = '#e6e6e6';
    ctx.fillRect(Math.round(splitX) - 1, 0, 2, h);
    ctx.fillStyle = '#2b6fd6';
    ctx.fillRect(Math.round(splitX) - 5, h / 2 - 18, 10, 36);
    label(ctx, 'A', 8, 8, 'left');
    label(ctx, b.lastGood ? 'B · last good' : `B · ${b.key}`, w - 8, 8, 'right');
  } else if (mode === 'diff' && diff) {
    label(ctx, `|A − B|  vs ${b.lastGood ? 'last good' : b.key}`, 8, 8, 'left');
  }
}

function clipped(ctx, x, width, h, paint) {
  ctx.save();
  ctx.beginPath();
  ctx.rect(x, 0, width, h);
  ctx.clip();
  paint();
  ctx.restore();
}

function label(ctx, text, x, y, align) {
  ctx.font = `11px ${FONT}`;
  ctx.textAlign = align;
  ctx.textBaseline = 'top';
  const m = ctx.measureText(text).width;
  ctx.fillStyle = 'rgba(0,0,0,0.65)';
  ctx.fillRect(align === 'right' ? x - m - 6 : x - 2, y - 2, m + 8, 16);
  ctx.fillStyle = '#e6e6e6';
  ctx.fillText(text, align === 'right' ? x - 2 : x + 2, y + 1);
}

function drawGrid(ctx, { scale, tx, ty }, { x0, y0, x1, y1 }) {
  ctx.strokeStyle = 'rgba(128,128,128,0.35)';
  ctx.lineWidth = 1;
  ctx.beginPath();
  for (let x = x0; x <= x1; x++) {
    const sx = Math.round(tx + x * scale) + 0.5;
    ctx.moveTo(sx, ty + y0 * scale);
    ctx.lineTo(sx, ty + y1 * scale);
  }
  for (let y = y0; y <= y1; y++) {
    const sy = Math.round(ty + y * scale) + 0.5;
    ctx.moveTo(tx + x0 * scale, sy);
    ctx.lineTo(tx + x1 * scale, sy);
  }
  ctx.stroke();
}

/** At high zoom, each pixel shows its values, like a spreadsheet. */
function drawValues(ctx, { scale, tx, ty }, { x0, y0, x1, y1 }, slotAt) {
  if ((x1 - x0) * (y1 - y0) > 600) return;
  const fontPx = Math.min(12, Math.floor(scale / 7));
  ctx.font = `${fontPx}px ${FONT}`;
  ctx.textAlign = 'left';
  ctx.textBaseline = 'top';
  for (let y = y0; y < y1; y++) {
    for (let x = x0; x < x1; x++) {
      const slot = slotAt(tx + (x + 0.5) * scale);
      const v = tex.pixel(slot.data, slot.width, slot.height, x, y);
      if (!v) continue;
      const i = (y * slot.width + x) * 4;
      const img = slot.image?.data;
      const lum = img ? 0.2126 * img[i] + 0.7152 * img[i + 1] + 0.0722 * img[i + 2] : 0;
      ctx.fillStyle = lum > 140 ? 'rgba(0,0,0,0.85)' : 'rgba(255,255,255,0.9)';
      const left = tx + x * scale + 3;
      const top = ty + y * scale + 3;
      slot.names.forEach((c, k) => {
        const s = tex.formatF32(v[k]);
        ctx.fillText(`${c} ${s.length > 9 ? Number(v[k]).toPrecision(4) : s}`, left, top + k * (fontPx + 2));
      });
    }
  }
}

function drawMarker(ctx, { scale, tx, ty }, p, color) {
  if (!p || scale < 4) return;
  ctx.strokeStyle = color;
  ctx.lineWidth = 2;
  ctx.strokeRect(tx + p.x * scale, ty + p.y * scale, scale, scale);
}
