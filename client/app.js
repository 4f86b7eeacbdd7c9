// loupe's browser UI: wires the WebSocket stream and the HTTP API to the
// panels (header, live frame, passes, problems, inspector) and exposes
// `window.loupe` so browser tests can drive the page deterministically.
//
// Stable hooks for tests (keep them when restyling):
//   #connection        text "connecting" | "connected" | "reconnecting" (+ data-state)
//   #frame             live <img>; data-frame = frame number of the image shown
//   #frame-counter     newest rendered frame number; #fps
//   #passes li[data-pass][data-status=ok|stale|failed|culled], .selected when inspected
//   #diagnostics .diagnostic[data-file][data-line][data-column][data-severity][data-code],
//                      its text holds "file:line:col: severity[code]: message";
//                      excerpt lines .src-line[data-line], the error line(s) .hl
//   #file-diffs        see file_diffs.js
//   #reference-on, #reference-body: see references.js
//   #inspector canvas, #pixel-value[data-x][data-y][data-r][data-g][data-b][data-a]
//                      (#pixel-value-b, #pixel-value-diff when comparing)
//   #inspect-a, #channel (rgb|r|g|b|a|luminance), #exposure (EV), #range-min,
//   #range-max, #auto-fit, #overlay-nan, #overlay-inf, #overlay-neg, #srgb,
//   #compare-mode (off|split|diff), #compare-b (last_good | "pass/output"), #live
//   #linearize (depth as distance), #inspector[data-meaning]: see presets.js
//   #renderer-raster, #renderer-path, #path-samples, #path-rate,
//                      #path-difference, #path-difference-open,
//                      #path-difference-stats: see path.js
//   #diff-scale, #mask-emitters, #mask-background, #compare-stats:
//                      see inspector_compare.js
//   window.loupe       see the end of this file
//
// Source of truth: the HTTP API. Events say *that* something changed (and
// carry what is cheap to carry); the panels refetch the authoritative
// snapshot, newest response wins. After a reconnect everything is
// refetched, since the server may have restarted with a different state.

import * as api from './api.js';
import { Connection } from './ws.js';
import { PassList } from './passes.js';
import { DiagnosticsPanel } from './diagnostics.js';
import { FileDiffs } from './file_diffs.js';
import { ReferenceView } from './references.js';
import { Inspector } from './inspector.js';
import { LiveFrame } from './live.js';
import { TensorView } from './tensor.js';
import { ControlsPanel } from './controls.js';
import { MaterialsPanel } from './materials.js';
import { QuadView } from './quads.js';
import { PrintsPanel } from './prints.js';
import { HistoryPanel } from './pixel_history.js';
import { PathView, TRACED } from './path.js';
import { TradeoffsView } from './tradeoffs.js';
import { awaitListed } from './capture_wait.js';
import { bindShortcuts } from './shortcuts.js';
import { Layout } from './layout.js';
import { isBrowserNotice } from './browser_notices.js';
import * as tex from './texture.js';
import { fpsTitle } from './timings.js';
import { TileInfo } from './tiles.js';
import { $, el, errorText, formatMs, coalesce, latestOnly } from './util.js';

/** The protocol version this client speaks (protocol.rs `VERSION`). */
const PROTOCOL = 3;
/** How many frames, and how long at most, the inspector waits for a newly
 * subscribed output's capture: the server captures it from the next frame
 * on; a slow adapter (seconds a frame on lavapipe) needs the time. */
const CAPTURE_WAIT_FRAMES = 3;
const CAPTURE_WAIT_MS = 20000;

const state = {
  connection: 'connecting',
  connections: 0, // WebSocket connections opened so far (reconnects + 1)
  protocol: null,
  status: null,
  frame: null, // newest `frame` event
  shownFrame: null, // frame number of the image in #frame
  nan: null, // the newest NaN report (`/api/nan`)
  fps: 0,
  frameSplit: null, // the newest `frame` event: its wall time and how it splits (timings.js)
  passes: [],
  pipelines: [],
  diagnostics: [],
  captures: [],
  reload: null, // {id, state: 'reloading'|'ok'|'failed', files, timings, frame}
  deviceLost: null,
  dropped: { frames: 0, events: 0 }, // totals of the `dropped` events
  problems: [], // client-side problems (malformed messages, script errors)
};

// ---- notices: one line per problem source, replaced, never stacked -------

const noticesEl = $('notices');
const notices = new Map();

function notify(key, text, kind = 'warn', timeoutMs = 0) {
  let entry = notices.get(key);
  if (!entry) {
    const node = el('div', { class: `notice ${kind}`, dataset: { key } });
    const close = el('button', { type: 'button', class: 'notice-close', title: 'dismiss', onclick: () => clearNotice(key) }, '×');
    entry = { node, textNode: el('span', { class: 'notice-text' }), timer: null };
    node.append(entry.textNode, close);
    noticesEl.append(node);
    notices.set(key, entry);
  }
  entry.node.className = `notice ${kind}`;
  entry.textNode.textContent = text;
  clearTimeout(entry.timer);
  if (timeoutMs) entry.timer = setTimeout(() => clearNotice(key), timeoutMs);
}

function clearNotice(key) {
  const entry = notices.get(key);
  if (!entry) return;
  clearTimeout(entry.timer);
  entry.node.remove();
  notices.delete(key);
}

function recordProblem(message) {
  state.problems.push(message);
  if (state.problems.length > 50) state.problems.shift();
  notify('client', message, 'warn', 15000);
}

// Safety net: anything that escapes a handler is shown, not lost in the
// console (handlers catch what they expect).
window.addEventListener('error', (e) => {
  if (!isBrowserNotice(e)) recordProblem(`client error: ${e.message}`);
});
window.addEventListener('unhandledrejection', (e) => {
  e.preventDefault();
  recordProblem(`client error: ${errorText(e.reason)}`);
});

/** Reports a failed fetch unless the server is simply away (the
 * connection indicator already says so). */
function fetchFailed(what) {
  return (err) => {
    if (err instanceof api.ApiError && err.unreachable && state.connection !== 'connected') return;
    notify(`fetch:${what}`, `could not load ${what}: ${errorText(err)}`, 'error');
  };
}

function fetched(what, fn) {
  return (value) => {
    clearNotice(`fetch:${what}`);
    fn(value);
  };
}

// ---- header --------------------------------------------------------------

const header = {
  adapter: $('adapter'),
  cpuFlag: $('cpu-flag'),
  degraded: $('degraded'),
  scene: $('scene'),
  pipelines: $('pipelines-summary'),
  mode: $('render-mode'),
  frame: $('frame-counter'),
  fps: $('fps'),
  reload: $('reload-status'),
  connection: $('connection'),
};

function applyStatus(status) {
  if (!status || typeof status !== 'object') return;
  state.status = status;
  header.adapter.textContent = status.adapter || 'no adapter';
  header.adapter.title = [
    status.adapter,
    status.version && `loupe ${status.version}`,
    status.features?.length ? `features: ${status.features.join(', ')}` : null,
    status.device_resets ? `device resets: ${status.device_resets}` : null,
  ]
    .filter(Boolean)
    .join('\n');
  header.cpuFlag.hidden = !status.cpu_adapter;
  const degraded = Array.isArray(status.degraded) ? status.degraded : [];
  header.degraded.hidden = degraded.length === 0;
  header.degraded.textContent = `degraded: ${degraded.length}`;
  header.degraded.title = degraded.join('\n');
  header.scene.textContent = status.scene || '';
  header.scene.hidden = !status.scene;
  header.mode.textContent = status.render_mode || '';
  header.mode.hidden = !status.render_mode;
  header.pipelines.replaceChildren(
    el('span', { class: 'count ok', title: 'pipelines ok' }, `${status.pipelines_ok ?? 0} ok`),
    el('span', { class: `count stale${status.pipelines_stale ? '' : ' zero'}`, title: 'pipelines stale (last good still renders)' }, `${status.pipelines_stale ?? 0} stale`),
    el('span', { class: `count failed${status.pipelines_failed ? '' : ' zero'}`, title: 'pipelines failed (never built)' }, `${status.pipelines_failed ?? 0} failed`),
  );
  if (state.frame === null && Number.isFinite(status.frame)) header.frame.textContent = String(status.frame);
}

function setConnection(s) {
  state.connection = s;
  header.connection.textContent = s;
  header.connection.dataset.state = s;
  document.body.dataset.connection = s;
}

// ---- frame rate ----------------------------------------------------------

const frameTimes = [];

function countFrame() {
  const now = performance.now();
  frameTimes.push(now);
  while (frameTimes.length && now - frameTimes[0] > 2000) frameTimes.shift();
  showFps();
}

/** Frames per second over the last two seconds; "idle" when nothing is
 * rendering (on-change mode between edits). */
function showFps() {
  const now = performance.now();
  while (frameTimes.length && now - frameTimes[0] > 2000) frameTimes.shift();
  const n = frameTimes.length;
  if (n >= 2 && now - frameTimes[n - 1] < 1000) {
    state.fps = ((n - 1) * 1000) / (frameTimes[n - 1] - frameTimes[0]);
    header.fps.textContent = state.fps >= 10 ? state.fps.toFixed(0) : state.fps.toFixed(1);
  } else {
    state.fps = 0;
    header.fps.textContent = 'idle';
  }
  header.fps.title = [
    fpsTitle(state.fps, state.frameSplit) || null,
    state.dropped.frames ? `${state.dropped.frames} frame(s) skipped while this tab was busy` : null,
    state.dropped.events ? `${state.dropped.events} event(s) missed while this tab was busy` : null,
  ]
    .filter(Boolean)
    .join('\n');
}
setInterval(showFps, 500);

// ---- reload status -------------------------------------------------------

function setReload(reload) {
  state.reload = reload;
  const r = header.reload;
  r.dataset.state = reload.state;
  const files = reload.files?.length ? reload.files.join(', ') : '';
  if (reload.state === 'reloading') {
    r.textContent = 'reloading…';
  } else if (reload.state === 'ok') {
    const t = reload.timings;
    const total = t ? t.watch_ms + t.compose_ms + t.pipeline_ms + t.render_ms : null;
    r.textContent = total !== null && Number.isFinite(total) ? `reloaded · ${formatMs(total)} ms` : 'reloaded';
  } else {
    r.textContent = 'reload failed';
  }
  const t = reload.timings;
  r.title = [
    files && `files: ${files}`,
    t && `watch ${formatMs(t.watch_ms)} ms · compose ${formatMs(t.compose_ms)} ms · pipeline ${formatMs(t.pipeline_ms)} ms · render ${formatMs(t.render_ms)} ms`,
  ]
    .filter(Boolean)
    .join('\n');
}

// ---- panels --------------------------------------------------------------

const live = new LiveFrame($('frame'), $('frame-info'), $('frame-empty'), (frame) => {
  state.shownFrame = frame;
});

/** The `writes[]` entry of /api/passes for `pass/output`, or undefined. */
const outputInfo = (pass, output) => state.passes.find((p) => p.name === pass)?.writes?.find((w) => w.name === output);

const passList = new PassList($('passes'), $('passes-total'), (pass, output) => {
  const info = outputInfo(pass, output);
  if (info?.kind === 'buffer') {
    // Buffers are tensors, not images: the tensor view takes the
    // inspector's place until a texture is picked again.
    $('inspector').hidden = true;
    tensors.show(pass, output);
    passList.select(pass);
  } else {
    tensors.hide();
    $('inspector').hidden = false;
    inspector.inspect(pass, output);
  }
});

// Tile classification's counts under the pass list (tiles.js).
const tileInfo = new TileInfo($('tiles-info'));

const diagnostics = new DiagnosticsPanel($('diagnostics'), $('diag-count'), (path) => api.source(path));

// Each broken file's diff against its last good version, with a revert.
const fileDiffs = new FileDiffs($('file-diffs'), {
  revert: (file) => api.revertFile(file),
  confirm: (text) => window.confirm(text),
  notify: (text, kind) => notify('revert', text, kind, 10000),
});

let conn = null; // created below; the inspector's hooks reach it lazily

/** Streams exactly `wanted` ([{pass, output}]) as f32 for `owner`. */
const streamF32 = (owner) => (wanted) => conn?.want(owner, wanted.map(({ pass, output }) => ({ pass, output, encoding: 'f32' })));

const inspector = new Inspector({
  fetchCaptures: () => loadCaptures(),
  onTarget: (pass) => {
    passList.select(pass);
    quadView.setPass(pass);
  },
  // The inspector streams exact floats of what it shows.
  subscribeOnly: streamF32('inspector'),
  awaitCapture,
  outputInfo,
  // The path view's raster reference is a B, with its masks (path.js).
  reference: () => pathView.referenceSlot(),
  maskFor: (width, height) => pathView.chosenMask(width, height),
  masksChanged: () => pathView.showDifference(),
});

// The tensor view takes the inspector's place: one set of outputs for both.
const tensors = new TensorView(streamF32('inspector'), streamF32('tensor-list'));
$('tensor-close').addEventListener('click', () => {
  tensors.hide();
  $('inspector').hidden = false;
  autoInspect(true);
});

/** Returns whether the pass structure changed (not just the times). */
function applyPasses(passes) {
  state.passes = Array.isArray(passes) ? passes : [];
  pathView.setPasses(state.passes);
  tensors.setPasses(state.passes);
  if (!passList.set(state.passes)) return false;
  const broken = state.passes.filter((p) => p.status === 'stale' || p.status === 'failed');
  const badge = $('frame-badge');
  badge.hidden = broken.length === 0;
  badge.textContent = broken.some((p) => p.status === 'failed')
    ? `${broken.length} pass${broken.length === 1 ? '' : 'es'} broken`
    : 'stale: last good pipelines';
  badge.title = broken.map((p) => `${p.name}: ${p.status}${p.reason ? ` (${p.reason})` : ''}`).join('\n');
  autoInspect();
  return true;
}

/** Once captures are known, inspect the final output (the capture marked
 * `final`): a debugger that opens on an empty canvas wastes the user's
 * first click. */
function autoInspect(force = false) {
  if (inspector.target && !force) return;
  const final = state.captures.find((c) => c.final);
  if (final) {
    inspector.inspect(final.pass, final.output);
    return;
  }
  // Before the first capture list: the last pass that writes an image.
  const images = (p) => (p.writes || []).filter((w) => w.kind !== 'buffer');
  const running = state.passes.filter((p) => (p.status === 'ok' || p.status === 'stale') && images(p).length);
  const last = running[running.length - 1];
  if (last) inspector.inspect(last.name, images(last)[0].name);
}

function applyDiagnostics(list) {
  state.diagnostics = Array.isArray(list) ? list : [];
  diagnostics.set(state.diagnostics);
}

function applyCaptures(list) {
  state.captures = Array.isArray(list) ? list : [];
  inspector.setCaptures(state.captures);
  pathView.setCaptures(state.captures);
  autoInspect();
}

function applyPipelines(list) {
  state.pipelines = Array.isArray(list) ? list : [];
  passList.setPipelines(state.pipelines);
}

// Newest-wins fetchers: overlapping refetches cannot apply out of order.
const refetchStatus = latestOnly(api.status, fetched('status', applyStatus), fetchFailed('status'));
const refetchPasses = latestOnly(api.passes, fetched('passes', applyPasses), fetchFailed('passes'));
const refetchPipelines = latestOnly(api.pipelines, fetched('pipelines', applyPipelines), fetchFailed('pipelines'));
const refetchMaterials = latestOnly(() => api.getJson('/api/materials'), fetched('materials', (r) => materials.apply(r)), fetchFailed('materials'));
const refetchControls = latestOnly(() => api.getJson('/api/controls'), fetched('controls', applyControls), fetchFailed('controls'));
const refetchDiagnostics = latestOnly(
  api.diagnostics,
  fetched('diagnostics', applyDiagnostics),
  fetchFailed('diagnostics'),
);
const loadCaptures = latestOnly(api.captures, fetched('captures', applyCaptures), fetchFailed('captures'));
const refetchFiles = latestOnly(api.files, fetched('files', (f) => fileDiffs.set(f)), fetchFailed('files'));

const refetchNan = latestOnly(() => api.getJson('/api/nan'), fetched('nan', (r) => applyNan(r?.report)), fetchFailed('nan'));

const resyncAll = coalesce(() => {
  refetchNan();
  refetchStatus();
  refetchPasses();
  refetchPipelines();
  refetchDiagnostics();
  refetchFiles();
  refetchControls();
  refetchMaterials();
  loadCaptures();
});
const refetchCapturesSoon = coalesce(() => loadCaptures(), 100);
const resyncSlowly = coalesce(resyncAll, 1000);

// ---- waiting for captures ------------------------------------------------

const frameWaiters = new Set();

/** Resolves true at the next `frame` event, false after `timeoutMs`. */
function nextFrame(timeoutMs) {
  return new Promise((resolve) => {
    const waiter = (ok) => {
      clearTimeout(timer);
      frameWaiters.delete(waiter);
      resolve(ok);
    };
    const timer = setTimeout(() => waiter(false), Math.max(0, timeoutMs));
    frameWaiters.add(waiter);
  });
}

/** Waits until `pass/output` appears in the capture list after a
 * subscribe (capture_wait.js): CAPTURE_WAIT_FRAMES frames, at most
 * CAPTURE_WAIT_MS in all. */
async function awaitCapture(pass, output) {
  // A failed or culled pass does not render: nothing will be captured.
  const info = state.passes.find((p) => p.name === pass);
  if (info && (info.status === 'failed' || info.status === 'culled')) return false;
  const deadline = performance.now() + CAPTURE_WAIT_MS;
  return awaitListed({
    frames: CAPTURE_WAIT_FRAMES,
    nextFrame: () => nextFrame(deadline - performance.now()),
    listed: async () => {
      const list = await api.captures();
      applyCaptures(list);
      return list.some((c) => c.pass === pass && c.output === output);
    },
  });
}

// ---- events --------------------------------------------------------------

function onEvent(ev) {
  if (!ev || typeof ev.type !== 'string') {
    recordProblem('event without a type');
    return;
  }
  switch (ev.type) {
    case 'controls':
      applyControls(ev);
      break;
    case 'materials':
      materials.apply(ev);
      break;
    case 'hello':
      state.protocol = ev.protocol;
      if (ev.protocol !== PROTOCOL) {
        notify('protocol', `server speaks protocol ${ev.protocol}, this page ${PROTOCOL}: reload the page`, 'error');
      } else clearNotice('protocol');
      applyStatus(ev.status);
      break;
    case 'reload_started':
      setReload({ id: ev.id, state: 'reloading', files: ev.files, pipelines: ev.pipelines });
      diagnostics.invalidate(ev.files);
      prints.invalidate(ev.files);
      break;
    case 'reload_succeeded':
      setReload({ id: ev.id, state: 'ok', files: ev.files, pipelines: ev.pipelines, timings: ev.timings });
      diagnostics.invalidate(ev.files);
      resyncAll();
      break;
    case 'reload_failed':
      setReload({ id: ev.id, state: 'failed', files: ev.files, pipelines: ev.pipelines });
      diagnostics.invalidate(ev.files);
      resyncAll();
      break;
    case 'frame':
      state.frame = ev.frame;
      state.frameSplit = ev;
      header.frame.textContent = String(ev.frame);
      countFrame();
      passList.updateTimings(ev);
      tileInfo.update(ev);
      if (ev.reload !== null && ev.reload !== undefined && state.reload?.id === ev.reload) {
        state.reload.frame = ev.frame;
        header.reload.title += `\nvisible in frame ${ev.frame}`;
      }
      for (const w of [...frameWaiters]) w(true);
      inspector.onFrame();
      tensors.onFrame();
      pathView.onFrame(ev.frame);
      break;
    case 'passes':
      // Sent when the pass list or a status changed; a new structure can
      // mean new outputs.
      if (applyPasses(ev.passes)) refetchCapturesSoon();
      break;
    case 'diagnostics':
      applyDiagnostics(ev.diagnostics);
      break;
    case 'files':
      fileDiffs.set(ev.files);
      break;
    case 'references':
      referenceView.apply(ev);
      break;
    case 'device_lost':
      state.deviceLost = { message: ev.message, recovered: !!ev.recovered };
      notify(
        'device',
        ev.recovered ? `GPU device lost and recreated: ${ev.message}` : `GPU device lost: ${ev.message}`,
        ev.recovered ? 'warn' : 'error',
        ev.recovered ? 20000 : 0,
      );
      resyncAll();
      break;
    case 'dropped':
      // This tab fell behind. Skipped frames are harmless (the newest frame
      // always arrives); missed events leave the snapshots stale: resync,
      // at most once a second.
      state.dropped.frames += Number(ev.frames) || 0;
      state.dropped.events += Number(ev.events) || 0;
      if (Number(ev.events) > 0) resyncSlowly();
      break;
    case 'error':
      notify('server', `server: ${ev.message}`, 'error', 20000);
      break;
    case 'scene_saved':
      controls.saved(ev);
      break;
    case 'nan':
      applyNan(ev.report);
      break;
    case 'quads':
      quadView.setReport(ev);
      break;
    case 'prints':
      prints.set(ev);
      break;
    case 'pixel_history':
      pixelHistory.set(ev);
      break;
    default:
      // A newer server may send events this page does not know: ignore.
      break;
  }
}

function onBinary(hdr, bytes) {
  // `frame`: the final output, for the live view; `capture`: an output the
  // inspector or the path view subscribed to. Other kinds are for newer
  // pages.
  if (hdr.kind === 'frame') {
    live.push(hdr, bytes);
    prints.frameSize(hdr.width, hdr.height);
  }
  else if (hdr.kind === 'capture') {
    inspector.onCapture(hdr, bytes);
    pathView.onCapture(hdr, bytes);
    materials.onCapture(hdr, bytes);
  }
}

// Clicking the live frame inspects the final output.
$('frame').addEventListener('click', () => autoInspect(true));

// ---- NaN origin ----------------------------------------------------------
// A traced frame names the pass that first made a NaN/Inf; one click opens
// that output at that pixel with the NaN overlay on. Test hooks:
// #nan-notice[data-pass][data-output], #nan-open, #trace.

function applyNan(report) {
  state.nan = report ?? null;
  const box = $('nan-notice');
  const o = report?.origin;
  box.hidden = !o;
  if (!o) {
    delete box.dataset.pass;
    delete box.dataset.output;
    return;
  }
  box.dataset.pass = o.pass;
  box.dataset.output = o.output;
  const others = (report.outputs || []).length;
  $('nan-text').textContent =
    `NaN/Inf first made by ${o.pass}/${o.output} at (${o.pixel[0]}, ${o.pixel[1]}): ${o.nan} NaN, ${o.inf} Inf` +
    ` · ${others} output${others === 1 ? '' : 's'} affected · frame ${report.frame}`;
}

$('nan-open').addEventListener('click', async () => {
  const o = state.nan?.origin;
  if (!o) return;
  tensors.hide();
  $('inspector').hidden = false;
  const overlay = $('overlay-nan');
  if (!overlay.checked) {
    overlay.checked = true;
    overlay.dispatchEvent(new Event('change'));
  }
  await inspector.inspect(o.pass, o.output);
  inspector.goTo(o.pixel[0], o.pixel[1]);
});

$('trace').addEventListener('click', async () => {
  try {
    const response = await fetch('/api/frame/trace', { method: 'POST' });
    if (!response.ok) throw new Error(`${response.status} ${response.statusText}`);
  } catch (err) {
    notify('trace', `trace request failed: ${errorText(err)}`, 'error', 10000);
  }
});

// ---- rebuild button ------------------------------------------------------

$('rebuild').addEventListener('click', async () => {
  try {
    const response = await fetch('/api/reload', { method: 'POST' });
    if (!response.ok) throw new Error(`${response.status} ${response.statusText}`);
    clearNotice('rebuild');
  } catch (err) {
    notify('rebuild', `rebuild request failed: ${errorText(err)}`, 'error', 10000);
  }
});

// Temporal passes and the path tracer's accumulation start over
// (`reset_history`, a daemon command like `rebuild`).
$('reset-history').addEventListener('click', () => conn.send({ type: 'reset_history' }));

// ---- against reference ---------------------------------------------------

const referenceView = new ReferenceView(
  { toggle: $('reference-on'), body: $('reference-body'), meta: $('reference-meta') },
  {
    send: (on) => {
      conn?.setReferences(on);
      // What an earlier comparison found, until the next one ends.
      if (on) api.getJson('/api/references').then((r) => referenceView.apply(r), () => {});
    },
    bless: (name) => api.blessReference(name),
    confirm: (text) => window.confirm(text),
    notify: (text, kind) => notify('bless', text, kind, 10000),
  },
);

// ---- quad statistics -----------------------------------------------------

const quadView = new QuadView(
  { toggle: $('quad-stats'), panel: $('quad-panel'), overlay: $('quad-overlay'), legend: $('quad-legend') },
  {
    send: (on) => conn?.setQuads(on),
    passList,
    inspector,
    fetchMap: api.quadMap,
  },
);

// ---- keyboard shortcuts (and the ? overlay) -------------------------------

bindShortcuts(inspector);

// ---- scene controls ------------------------------------------------------

const controls = new ControlsPanel($('scene-panel'), (message) => conn.send(message));

// ---- materials: tree, report, parameters; the pinned pixel's material -----

const materials = new MaterialsPanel({ send: (message) => conn.send(message), want: (wanted) => conn?.want('materials', wanted) });
const pixelHistory = new HistoryPanel($('history-panel'));
const prints = new PrintsPanel($('pixel-prints'), { send: (message) => conn.send(message), source: api.source });
inspector.onPin = (p, a) => {
  const size = a && { width: a.width, height: a.height };
  materials.pin(p, size);
  prints.pin(p, size);
  pixelHistory.select(prints.selected);
};

// ---- renderer switch, samples, path − raster -----------------------------

const pathView = new PathView({
  send: (message) => conn.send(message),
  want: (wanted) => conn?.want('path', wanted),
  refreshCaptures: refetchCapturesSoon,
  maskChoice: () => inspector.compareTools.maskChoice(),
  referenceChanged: () => inspector.referenceChanged(),
  open: () => inspector.compareWithReference(TRACED.pass, TRACED.output),
});

// ---- accuracy against time ------------------------------------------------

const tradeoffs = new TradeoffsView(
  {
    chart: $('tradeoffs-chart'),
    tip: $('tradeoffs-tip'),
    text: $('tradeoffs-text'),
    image: $('tradeoffs-image'),
    meta: $('tradeoffs-meta'),
    empty: $('tradeoffs-empty'),
    refresh: $('tradeoffs-refresh'),
  },
  { send: (message) => conn.send(message), fetch: api.tradeoffs },
);

function applyControls(report) {
  controls.apply(report);
  pathView.setControls(report);
  tradeoffs.setControls(report);
}

// ---- layout: splitters, collapsing, remembered sizes ---------------------

new Layout(document.querySelector('main'));

// ---- start ---------------------------------------------------------------

const wsUrl = `${location.protocol === 'https:' ? 'wss:' : 'ws:'}//${location.host}/ws`;
conn = new Connection(wsUrl, {
  onState: setConnection,
  onOpen: () => {
    state.connections++;
    for (const key of [...notices.keys()]) if (key.startsWith('fetch:')) clearNotice(key);
    resyncAll();
    // A restarted server may render another scene: whose results are
    // current is its answer.
    tradeoffs.load();
    // A restarted server has none of the old captures in memory.
    if (inspector.target) inspector.load();
  },
  onEvent,
  onBinary,
  onProblem: recordProblem,
});
setConnection('connecting');
conn.start();
// Do not wait for the socket to show what the API already knows.
resyncAll();

// ---- test hooks ----------------------------------------------------------

/**
 * `window.loupe`: a stable surface for browser tests (and the console).
 * Values are plain data so WebDriver can return them; note that JSON has no
 * NaN/Infinity, so `valueAt` shows them as null there: use `valueText`.
 */
window.loupe = {
  /** Inspects pass/output; resolves true once its data is displayed. */
  inspect: (pass, output) => inspector.inspect(pass, output),
  /** Exact float RGBA at image pixel (x, y) of 'a' (default), 'b' or 'diff'. */
  valueAt: (x, y, which = 'a') => inspector.valueAt(x, y, which),
  /** Like valueAt, as strings ("NaN", "Infinity", "0.5"). */
  valueText: (x, y, which = 'a') => inspector.valueAt(x, y, which)?.map(String) ?? null,
  /** Display RGBA8 at (x, y) after exposure, range, channel and overlays. */
  displayedAt: (x, y, which) => inspector.displayedAt(x, y, which),
  /** Centres and pins pixel (x, y), as a click does. */
  pin: (x, y) => inspector.goTo(x, y),
    /** Puts the readout on pixel (x, y), as the mouse would. */
  hover: (x, y) => inspector.hoverPixel(x, y),
  /** Compare mode 'off' | 'split' | 'diff' against B ('last_good', 'raster_reference' or 'pass/output'). */
  compare: (mode, b = 'last_good') => {
    const modeSel = $('compare-mode');
    const bSel = $('compare-b');
    if (![...bSel.options].some((o) => o.value === b)) bSel.append(el('option', { value: b }, b));
    bSel.value = b;
    modeSel.value = mode;
    inspector.root.dataset.compare = mode;
    return inspector.compareChanged();
  },
  /** Opens |path − raster| in the inspector, as the path panel's button. */
  openDifference: () => inspector.compareWithReference(TRACED.pass, TRACED.output),
  autoFit: () => inspector.autoFit(),
  refresh: () => inspector.load(),
  fit: () => inspector.fit(),
  /** Everything the page knows, as plain data. */
  get state() {
    return {
      ...state,
      liveFrame: live.shown ? { ...live.shown } : null,
      liveImages: { received: live.received, skipped: live.skipped, failed: live.failed, rate: live.rate() },
      inspector: inspector.snapshot(),
      path: pathView.snapshot(),
      tradeoffs: tradeoffs.snapshot(),
    };
  },
  tex,
};
