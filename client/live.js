// The live final frame. Images arrive as PNG bytes over the WebSocket; the
// newest one wins (frames that arrive while one decodes are skipped), and
// the last good image stays up when a shader breaks or the server goes
// away — a blank view would hide what the user was looking at.

export class LiveFrame {
  /**
   * @param {HTMLImageElement} img `#frame`
   * @param {HTMLElement} info caption text
   * @param {HTMLElement} empty placeholder shown until the first image
   * @param {(frame: number) => void} onShown after an image is on screen
   */
  constructor(img, info, empty, onShown) {
    this.img = img;
    this.info = info;
    this.empty = empty;
    this.onShown = onShown;
    this.url = null;
    this.pending = null;
    this.busy = false;
    this.shown = null; // header of the image on screen
    this.received = 0;
    this.skipped = 0;
    this.failed = 0;
    this.arrivals = []; // timestamps, for the image rate
  }

  push(header, bytes) {
    this.received++;
    const now = performance.now();
    this.arrivals.push(now);
    while (this.arrivals.length && now - this.arrivals[0] > 2000) this.arrivals.shift();
    if (this.pending) this.skipped++;
    this.pending = { header, bytes };
    if (!this.busy) this.pump();
  }

  /** Images per second received over the last two seconds. */
  rate() {
    const a = this.arrivals;
    if (a.length < 2 || performance.now() - a[a.length - 1] > 2000) return 0;
    return ((a.length - 1) * 1000) / (a[a.length - 1] - a[0]);
  }

  async pump() {
    this.busy = true;
    try {
      while (this.pending) {
        const { header, bytes } = this.pending;
        this.pending = null;
        await this.showOne(header, bytes);
      }
    } finally {
      this.busy = false;
    }
  }

  async showOne(header, bytes) {
    const url = URL.createObjectURL(new Blob([bytes], { type: header.mime || 'image/png' }));
    try {
      // Decode off-screen first: assigning a corrupt image to the visible
      // element would replace the last good picture with a broken icon.
      const probe = new Image();
      probe.src = url;
      await probe.decode();
      this.img.src = url;
      // The decoded image is cached, so this resolves almost at once; it
      // makes `data-frame` describe what is actually painted.
      await this.img.decode().catch(() => {});
    } catch (err) {
      URL.revokeObjectURL(url);
      this.failed++;
      this.info.textContent = `frame ${header.frame ?? '?'} could not be decoded`;
      this.info.classList.add('warn');
      return;
    }
    if (this.url) URL.revokeObjectURL(this.url);
    this.url = url;
    this.shown = header;
    const frame = Number(header.frame);
    this.img.dataset.frame = String(Number.isFinite(frame) ? frame : '');
    this.img.hidden = false;
    this.empty.hidden = true;
    const size =
      header.width && header.height
        ? `${header.width}×${header.height}`
        : `${this.img.naturalWidth}×${this.img.naturalHeight}`;
    const what = header.pass ? ` · ${header.pass}/${header.output ?? ''}` : '';
    this.info.textContent = `frame ${header.frame ?? '?'} · ${size}${what}`;
    this.info.classList.remove('warn');
    this.onShown?.(frame);
  }
}
