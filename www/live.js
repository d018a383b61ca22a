// navguard live session (main thread): the operator streams rows into a
// Detector running in live-worker.js, watches status / F / R / C and a rolling
// 60 s plot, and the detector's snapshot is kept in IndexedDB (live-store.js)
// every few seconds and on visibilitychange / pagehide, so a reload offers to
// resume the session with the learned model instead of starting from zero.
//
// The replay (of a simulated scenario or of an opened log, at 1x or faster)
// stands in for a telemetry link: a real source (a WebSocket/MAVLink bridge)
// would start a session with source {kind:'link'} and call `live.feed(rows)`,
// which reaches the same pushRow() in the worker as the replay does.
import uPlot from './vendor/uPlot.esm.js';
import * as store from './live-store.js';

const $ = (sel) => document.querySelector(sel);
const WINDOW_S = 60;                   // rolling plot span (source seconds)
const DRAW_MS = 250;                   // at most 4 redraws a second
const FILE_LIMIT = 50 * 1024 * 1024;   // keep replayed logs under 50 MB in IndexedDB
const KIND_NAME = { 0: 'normal', 1: 'residual fault', 2: 'GPS outage', 3: 'no GPS yet', 4: 'GPS output frozen' };
const KIND_FILL = { 1: 'rgba(220,38,38,0.13)', 2: 'rgba(217,119,6,0.16)', 3: 'rgba(156,163,175,0.18)' };

let ui = null; // {showError, hideError, readConfig, scenario}

const L = {
  worker: null,
  ready: false,
  phase: 'idle',        // idle | starting | running | paused | ended
  source: null,         // source description (what is stored)
  speed: 20,
  config: null,         // the detector's checked config (from the worker)
  startRow: 0,          // source row the session (re)started at
  startRowCount: 0,     // detector rowCount right after start / restore
  startStats: null,     // detector stats right after start / restore
  resumed: false,
  totalRows: null,
  nextRow: 0,
  rowCount: 0,
  stats: null,
  last: null,
  rowErrors: 0,
  lastRowError: '',
  info: null,           // snapshotInfo of the latest snapshot
  lastSnap: null,       // latest snapshot message
  lastSnapSaved: false,
  saves: 0,
  lastSaved: null,      // {savedAt, nextRow, rowCount, stats, reason}
  persist: true,
  persistError: '',
  offer: null,          // saved record offered for resume
  buf: { t: [], f: [], r: [], c: [], kind: [] },
  tNow: 0,
  plot: null,
  drawTimer: 0,
  lastDraw: 0,
};

// ------------------------------------------------------------- worker link

let nextId = 1;
const pending = new Map();

function startWorker() {
  const w = new Worker(new URL('./live-worker.js', import.meta.url), { type: 'module' });
  w.onmessage = (ev) => onMessage(ev.data);
  w.onerror = (ev) => {
    ev.preventDefault();
    ui.showError(`Live worker failed: ${ev.message || 'could not start (is the wasm build in www/pkg/?)'}`);
    for (const [, p] of pending) p.reject(new Error('live worker failed'));
    pending.clear();
    setPhase('idle');
  };
  L.worker = w;
}

function request(msg, transfer) {
  const id = nextId++;
  return new Promise((resolve, reject) => {
    pending.set(id, { resolve, reject });
    L.worker.postMessage({ ...msg, id }, transfer || []);
  });
}

function onMessage(m) {
  const p = m.id != null ? pending.get(m.id) : null;
  if (p) pending.delete(m.id);
  if (m.type === 'error') {
    if (p) p.reject(new Error(m.message));
    else ui.showError(`Live session: ${m.message}`);
    return;
  }
  switch (m.type) {
    case 'ready':
      L.ready = true;
      $('#live-start').disabled = L.phase === 'running' || L.phase === 'paused' || L.phase === 'starting';
      break;
    case 'started': onStarted(m); break;
    case 'tick': onTick(m); break;
    case 'snapshot': onSnapshot(m); break;
    case 'ended': onEnded(m); break;
    default: break;
  }
  if (p) p.resolve(m);
}

// ---------------------------------------------------------------- sessions

function readSpeed() {
  const v = Number($('#live-speed').value);
  return Number.isFinite(v) && v >= 0 ? v : 1;
}

function scenarioSource() {
  const { name, seed } = ui.scenario();
  return { kind: 'sim', scenario: name, seed, name: `${name}-seed${seed}.csv` };
}

async function startNew() {
  if (!L.ready || L.phase === 'starting') return;
  ui.hideError();
  let source, bytes = null;
  if ($('#live-source').value === 'file') {
    const f = $('#live-file').files[0];
    if (!f) { ui.showError('Live session: choose a log file to replay first.'); return; }
    bytes = new Uint8Array(await f.arrayBuffer());
    source = { kind: 'file', name: f.name, size: f.size, lastModified: f.lastModified, fileStored: false };
  } else {
    source = scenarioSource();
  }
  // a new session replaces whatever was saved
  hideOffer();
  await discardSaved();
  if (bytes && L.persist && bytes.length < FILE_LIMIT) {
    try {
      await store.put(store.FILE, { name: source.name, size: source.size, lastModified: source.lastModified, bytes: bytes.slice().buffer });
      source.fileStored = true;
    } catch (e) {
      source.fileStored = false;
    }
  }
  await launch(source, bytes, ui.readConfig(), readSpeed(), null);
}

async function launch(source, bytes, config, speed, resume) {
  setPhase('starting');
  L.source = source;
  L.speed = speed;
  L.saves = 0;
  L.lastSaved = null;
  L.lastSnap = null;
  L.lastSnapSaved = false;
  L.rowErrors = 0;
  L.lastRowError = '';
  L.buf = { t: [], f: [], r: [], c: [], kind: [] };
  const { kind, name, size, scenario, seed } = source;
  const msgSource = kind === 'sim' ? { kind, scenario, seed } : kind === 'file' ? { kind, name, size, bytes } : { kind, name };
  try {
    await request({ type: 'start', source: msgSource, config, speed, resume });
    return true;
  } catch (e) {
    setPhase('idle');
    if (resume) {
      ui.showError(`Could not resume the saved live session, so it was discarded: ${e.message}`);
      await discardSaved();
    } else {
      ui.showError(`Live session: ${e.message}`);
    }
    render();
    return false;
  }
}

function onStarted(m) {
  L.startRow = m.startRow;
  L.startRowCount = m.rowCount;
  L.startStats = m.stats;
  L.resumed = m.resumed;
  L.totalRows = m.totalRows;
  if (m.totalRows != null) L.source = { ...L.source, rows: m.totalRows };
  L.nextRow = m.startRow;
  L.rowCount = m.rowCount;
  L.stats = m.stats;
  L.info = m.info;
  L.config = m.config;
  L.last = null;
  L.tNow = m.tStart != null && m.startRow === 0 ? m.tStart : L.tNow;
  setPhase('running');
  $('#live-panel').hidden = false;
  ensurePlot();
  render();
}

function onTick(m) {
  if (L.phase !== 'running' && L.phase !== 'paused' && L.phase !== 'ended') return;
  L.nextRow = m.nextRow;
  L.totalRows = m.totalRows;
  L.rowCount = m.rowCount;
  L.stats = m.stats;
  L.rowErrors = m.rowErrors;
  L.lastRowError = m.lastRowError;
  if (m.last) L.last = m.last;
  const p = m.plot;
  const b = L.buf;
  for (let i = 0; i < p.t.length; i++) {
    b.t.push(p.t[i]); b.f.push(num(p.f[i])); b.r.push(num(p.r[i])); b.c.push(num(p.c[i])); b.kind.push(p.kind[i]);
  }
  if (b.t.length) L.tNow = b.t[b.t.length - 1];
  trimBuf();
  scheduleDraw();
}

function onSnapshot(m) {
  if (L.phase !== 'running' && L.phase !== 'paused') return; // in flight when the session stopped
  L.lastSnap = m;
  L.lastSnapSaved = false;
  L.info = m.info;
  save(m, m.reason);
  scheduleDraw();
}

async function onEnded(m) {
  L.nextRow = m.nextRow;
  L.rowCount = m.rowCount;
  L.stats = m.stats;
  setPhase('ended');
  // nothing is left to resume
  await discardSaved();
  render();
}

function record(m, reason) {
  const source = { ...L.source };
  return {
    schema: 1,
    snapshot: m.snapshot,
    info: m.info,
    source,
    nextRow: m.nextRow,
    rowCount: m.rowCount,
    stats: m.stats,
    config: L.config,
    speed: L.speed,
    savedAt: Date.now(),
    reason,
  };
}

async function save(m, reason) {
  if (!L.persist) return;
  const rec = record(m, reason);
  try {
    await store.put(store.SESSION, rec);
    // A save still in flight when the session stopped must not outlive the
    // stop's discard.
    if (L.phase !== 'running' && L.phase !== 'paused') {
      await discardSaved();
      return;
    }
    if (L.lastSnap === m) L.lastSnapSaved = true;
    L.saves++;
    L.lastSaved = { savedAt: rec.savedAt, nextRow: rec.nextRow, rowCount: rec.rowCount, stats: rec.stats, reason };
    L.persistError = '';
  } catch (e) {
    L.persistError = e.message || String(e);
  }
  scheduleDraw();
}

// pagehide: the worker cannot answer in time, so store the latest snapshot
// it sent (at most one save interval old), in a transaction started now.
function onPageHide() {
  if ((L.phase !== 'running' && L.phase !== 'paused') || !L.lastSnap || L.lastSnapSaved || !L.persist) return;
  store.putNow(store.SESSION, record(L.lastSnap, 'pagehide'));
}

function onVisibility() {
  if (document.visibilityState !== 'hidden') return;
  if (L.phase !== 'running' && L.phase !== 'paused') return;
  // the page is still alive while hidden: ask for a fresh snapshot
  L.worker.postMessage({ type: 'snapshot', reason: 'hidden' });
}

function togglePause() {
  if (L.phase === 'running') {
    L.worker.postMessage({ type: 'pause' });
    setPhase('paused');
  } else if (L.phase === 'paused') {
    L.worker.postMessage({ type: 'play' });
    setPhase('running');
  }
  render();
}

async function stop() {
  if (L.phase === 'idle') return;
  setPhase('idle');
  L.stopping = true;
  try { await request({ type: 'stop' }); } catch { /* the worker reports nothing useful here */ }
  await discardSaved();
  L.stopping = false;
  render();
}

// ------------------------------------------------------------------- saved

function describeSource(s) {
  if (!s) return '';
  if (s.kind === 'sim') return `simulated “${s.scenario}”, seed ${s.seed}`;
  if (s.kind === 'file') return `${s.name} (${fmtBytes(s.size)})`;
  return s.name || 'live link';
}

function recordProblem(r) {
  if (typeof r !== 'object' || r === null) return 'not an object';
  if (r.schema !== 1) return `unknown record schema ${r.schema}`;
  if (!(r.snapshot instanceof Uint8Array)) return 'the stored snapshot is not a byte array';
  if (!r.source || !['sim', 'file', 'link'].includes(r.source.kind)) return 'unknown source';
  if (!Number.isInteger(r.nextRow) || r.nextRow < 0) return 'bad row index';
  return '';
}

async function checkSaved() {
  let rec;
  try {
    rec = await store.get(store.SESSION);
  } catch (e) {
    L.persist = false;
    L.persistError = e.message || String(e);
    render();
    return;
  }
  if (rec === undefined) return;
  const problem = recordProblem(rec);
  if (problem) {
    await discardSaved();
    ui.showError(`The saved live session was discarded: ${problem}.`);
    return;
  }
  try {
    const m = await request({ type: 'inspect', snapshot: rec.snapshot });
    rec.info = m.info;
  } catch (e) {
    await discardSaved();
    ui.showError(`The saved live session was discarded: ${e.message}`);
    return;
  }
  if (L.phase !== 'idle') return; // the operator started something meanwhile
  L.offer = rec;
  showOffer(rec);
}

function showOffer(rec) {
  const st = rec.stats || {};
  const rows = Number(rec.rowCount ?? st.rows ?? rec.nextRow);
  const retr = Number(st.retrains || 0);
  const when = new Date(rec.savedAt).toLocaleTimeString('en-GB', { hour12: false });
  $('#live-resume').textContent = `Resume live session (saved ${when}, ${rows.toLocaleString('en-US')} rows, ${retr} ${retr === 1 ? 'retrain' : 'retrains'})`;
  const total = rec.source.rows ? ` of ${Number(rec.source.rows).toLocaleString('en-US')}` : '';
  $('#live-offer-detail').textContent = `${describeSource(rec.source)} · next row ${rec.nextRow.toLocaleString('en-US')}${total} · snapshot ${fmtBytes(rec.info.bytes)}, format v${rec.info.version} (navguard ${rec.info.crateVersion})`;
  $('#live-reopen').hidden = true;
  $('#live-offer').hidden = false;
}

function hideOffer() {
  L.offer = null;
  $('#live-offer').hidden = true;
}

async function discardSaved() {
  if (!L.persist) return;
  try {
    await store.del(store.SESSION);
    await store.del(store.FILE);
  } catch (e) {
    L.persistError = e.message || String(e);
  }
}

async function resumeSaved(file) {
  const rec = L.offer;
  if (!rec || !L.ready || L.phase === 'starting') return;
  ui.hideError();
  let bytes = null;
  if (rec.source.kind === 'file') {
    const s = rec.source;
    if (file) {
      if (file.name !== s.name || file.size !== s.size) {
        ui.showError(`That is not the log of the saved live session: expected ${s.name} (${s.size.toLocaleString('en-US')} bytes), got ${file.name} (${file.size.toLocaleString('en-US')} bytes).`);
        return;
      }
      bytes = new Uint8Array(await file.arrayBuffer());
    } else {
      let f = null;
      if (s.fileStored) {
        try { f = await store.get(store.FILE); } catch { f = null; }
      }
      if (!f || f.name !== s.name || f.size !== s.size || !(f.bytes instanceof ArrayBuffer)) {
        // ask the operator for the same file again
        $('#live-reopen-name').textContent = `${s.name} (${fmtBytes(s.size)})`;
        $('#live-reopen').hidden = false;
        $('#live-offer-detail').textContent = `The log is not stored in this browser: re-open ${s.name} (${s.size.toLocaleString('en-US')} bytes) to resume.`;
        return;
      }
      bytes = new Uint8Array(f.bytes);
    }
  }
  const speed = Number.isFinite(rec.speed) ? rec.speed : readSpeed();
  setSpeedSelect(speed);
  $('#live-offer').hidden = true;
  L.offer = null;
  const ok = await launch(rec.source, bytes, rec.config, speed, { snapshot: rec.snapshot, nextRow: rec.nextRow });
  if (!ok) hideOffer();
}

async function discardOffer() {
  hideOffer();
  await discardSaved();
  render();
}

function setSpeedSelect(v) {
  const sel = $('#live-speed');
  if (![...sel.options].some((o) => Number(o.value) === v)) {
    const o = document.createElement('option');
    o.value = String(v);
    o.textContent = `${v}×`;
    sel.append(o);
  }
  sel.value = String(v);
}

// ------------------------------------------------------------------- view

function setPhase(p) {
  L.phase = p;
  document.body.dataset.live = p;
  const active = p === 'running' || p === 'paused' || p === 'starting';
  $('#live-start').disabled = !L.ready || active;
  $('#live-pause').disabled = !(p === 'running' || p === 'paused');
  $('#live-pause').textContent = p === 'paused' ? 'Continue' : 'Pause';
  $('#live-stop').disabled = p === 'idle';
  $('#live-stop').textContent = p === 'ended' ? 'Close' : 'Stop';
  if (p === 'idle') $('#live-panel').hidden = true;
}

function num(x) { return Number.isFinite(x) ? x : null; }
const fmt = (x, d = 2) => (x == null || !Number.isFinite(x) ? '—' : x.toFixed(d));
const int = (x) => (x == null || !Number.isFinite(x) ? '—' : x.toLocaleString('en-US'));
function fmtBytes(n) {
  if (n < 1024) return `${n} B`;
  if (n < 1024 * 1024) return `${(n / 1024).toFixed(1)} KiB`;
  return `${(n / 1048576).toFixed(1)} MiB`;
}
const hms = (ms) => new Date(ms).toLocaleTimeString('en-GB', { hour12: false });

function setText(key, text) {
  const el = document.querySelector(`#live-panel [data-live="${key}"]`);
  if (el && el.textContent !== text) el.textContent = text;
}

function render() {
  const st = L.stats || {};
  const last = L.last;
  const v = $('#live-verdict');
  let kind = last ? last.kind : 3;
  let label = last ? (last.status === 1 ? (last.kind === 2 || last.kind === 4 ? KIND_NAME[last.kind] : 'Fault') : KIND_NAME[last.kind]) : 'waiting for rows';
  if (last && last.status === 1 && last.kind === 0) kind = 1;
  v.dataset.kind = String(kind);
  v.dataset.status = last ? String(last.status) : '';
  if (v.textContent !== label) v.textContent = label;
  setText('phase', { idle: 'stopped', starting: 'starting…', running: `running at ${L.speed > 0 ? `${L.speed}×` : 'max speed'}`, paused: 'paused', ended: 'replay complete' }[L.phase]);
  setText('source', `${describeSource(L.source)}${L.resumed ? ` · resumed at row ${int(L.startRow)}` : ''}`);
  setText('t', last ? `${fmt(last.t, 2)} s` : '—');
  setText('f', last ? fmt(last.f, 3) : '—');
  setText('r', last ? fmt(last.r, 2) : '—');
  setText('c', last ? fmt(last.c, 3) : '—');
  setText('rows', int(L.rowCount));
  setText('progress', L.totalRows ? `${int(L.nextRow)} / ${int(L.totalRows)} (${(100 * L.nextRow / L.totalRows).toFixed(1)} %)` : int(L.nextRow));
  setText('retrains', int(st.retrains));
  setText('gps', int(st.gpsEpochs));
  setText('resets', `${int(st.filterResets)} / ${int(st.dataGaps)}`);
  setText('errors', L.rowErrors ? `${int(L.rowErrors)} (${L.lastRowError})` : 'none');
  setText('snap', L.info ? `${fmtBytes(L.info.bytes)} · format v${L.info.version} · navguard ${L.info.crateVersion}` : '—');
  setText('saved', !L.persist ? `not saved (${L.persistError})`
    : L.lastSaved ? `${hms(L.lastSaved.savedAt)} · ${int(L.lastSaved.rowCount)} rows · ${L.saves} ${L.saves === 1 ? 'save' : 'saves'}${L.persistError ? ` · last save failed: ${L.persistError}` : ''}`
      : L.persistError ? `save failed: ${L.persistError}` : 'not yet');
}

// -------------------------------------------------------------------- plot

function trimBuf() {
  const b = L.buf;
  const lo = L.tNow - WINDOW_S;
  let i = 0;
  while (i < b.t.length - 1 && b.t[i + 1] < lo) i++; // keep one point before the window (stepped lines)
  if (i > 256 || (i > 0 && i > b.t.length / 2)) {
    for (const k of Object.keys(b)) b[k].splice(0, i);
  }
}

function scheduleDraw() {
  if (L.drawTimer) return;
  const wait = Math.max(0, DRAW_MS - (performance.now() - L.lastDraw));
  L.drawTimer = setTimeout(draw, wait);
}

function draw() {
  L.drawTimer = 0;
  L.lastDraw = performance.now();
  render();
  const u = L.plot;
  if (!u || $('#live-panel').hidden) return;
  const b = L.buf;
  // Methods other than anfis score their test statistic over its threshold: a fault at 1.
  const anfis = !L.config || !L.config.method || L.config.method === 'anfis';
  const thr = !anfis ? 1 : L.config && Number.isFinite(L.config.threshold) ? L.config.threshold : 0.5;
  u.setData([b.t.slice(), b.f.slice(), b.t.map(() => thr), b.r.slice(), b.c.slice()]);
  L.draws = (L.draws || 0) + 1;
}

function shade(u) {
  const b = L.buf;
  const { ctx } = u;
  const { left, top, width, height } = u.bbox;
  ctx.save();
  ctx.beginPath();
  ctx.rect(left, top, width, height);
  ctx.clip();
  let s = 0;
  for (let i = 1; i <= b.t.length; i++) {
    if (i < b.t.length && b.kind[i] === b.kind[s]) continue;
    const k = b.kind[s];
    if (k !== 0) {
      const x0 = u.valToPos(b.t[s], 'x', true);
      const x1 = u.valToPos(i < b.t.length ? b.t[i] : L.tNow, 'x', true);
      ctx.fillStyle = KIND_FILL[k];
      ctx.fillRect(x0, top, Math.max(1.5, x1 - x0), height);
    }
    s = i;
  }
  ctx.restore();
}

function ensurePlot() {
  const host = $('#plot-live');
  if (L.plot) return;
  const stepped = uPlot.paths.stepped({ align: 1 });
  const axis = (extra) => ({ stroke: '#374151', labelSize: 18, grid: { stroke: '#eef0f3', width: 1 }, ticks: { stroke: '#d1d5db', width: 1, size: 4 }, ...extra });
  L.plot = new uPlot({
    width: Math.max(320, host.clientWidth || 600),
    height: 220,
    legend: { show: true },
    cursor: { drag: { x: false, y: false, setScale: false }, y: false },
    scales: {
      x: { time: false, range: () => [L.tNow - WINDOW_S, L.tNow] },
      f: { range: (u, lo, hi) => [Math.max(-0.6, Math.min(-0.1, lo ?? 0)), Math.min(1.6, Math.max(1.2, (hi ?? 1) + 0.05))] },
      r: { range: (u, lo, hi) => [0, Math.max(3, (hi ?? 1) * 1.05)] },
    },
    hooks: { drawAxes: [shade] },
    series: [
      { label: 't (s)', value: (u, v) => fmt(v, 2) },
      { label: 'F (-)', scale: 'f', stroke: '#1d4ed8', width: 1.5, paths: stepped, points: { show: false }, value: (u, v) => fmt(v, 3) },
      { label: 'threshold', scale: 'f', stroke: '#b91c1c', width: 1.25, dash: [6, 4], points: { show: false }, value: (u, v) => fmt(v, 2) },
      { label: 'R (-)', scale: 'r', stroke: '#7c3aed', width: 1.25, paths: stepped, points: { show: false }, value: (u, v) => fmt(v, 2) },
      { label: 'C (-)', scale: 'f', stroke: '#0f766e', width: 1.25, paths: stepped, points: { show: false }, value: (u, v) => fmt(v, 3) },
    ],
    axes: [
      axis({ label: 'time (s)', size: 34 }),
      axis({ scale: 'f', label: 'F, C (-)', size: 64 }),
      axis({ scale: 'r', side: 1, label: 'R (-)', size: 56, grid: { show: false }, stroke: '#7c3aed' }),
    ],
  }, [[], [], [], [], []], host);
  let rt = 0;
  new ResizeObserver(() => {
    clearTimeout(rt);
    rt = setTimeout(() => { if (L.plot && host.clientWidth) L.plot.setSize({ width: Math.max(320, host.clientWidth), height: 220 }); }, 120);
  }).observe(host);
}

// ------------------------------------------------------------------ wiring

/** Start the live part of the page. helpers: {showError, hideError,
 *  readConfig, scenario: () => ({name, seed})}. */
export function initLive(helpers) {
  ui = helpers;
  startWorker();
  L.worker.postMessage({ type: 'hello' });
  setPhase('idle');
  render();

  $('#live-form').addEventListener('submit', (e) => { e.preventDefault(); startNew(); });
  $('#live-source').addEventListener('change', () => { $('#live-file-row').hidden = $('#live-source').value !== 'file'; });
  $('#live-file').addEventListener('change', () => {
    const f = $('#live-file').files[0];
    $('#live-file-name').textContent = f ? `${f.name} (${fmtBytes(f.size)})` : 'no file chosen';
  });
  $('#live-speed').addEventListener('change', () => {
    L.speed = readSpeed();
    if (L.phase === 'running' || L.phase === 'paused') L.worker.postMessage({ type: 'speed', speed: L.speed });
    render();
  });
  $('#live-pause').addEventListener('click', togglePause);
  $('#live-stop').addEventListener('click', stop);
  $('#live-resume').addEventListener('click', () => resumeSaved(null));
  $('#live-discard').addEventListener('click', discardOffer);
  $('#live-reopen-file').addEventListener('change', (e) => {
    const f = e.target.files[0];
    e.target.value = '';
    if (f) resumeSaved(f);
  });
  document.addEventListener('visibilitychange', onVisibility);
  window.addEventListener('pagehide', onPageHide);

  checkSaved()
    .catch((e) => ui.showError(`Saved live session: ${e.message || e}`))
    .finally(() => { L.checked = true; });

  // handle for the browser test and for debugging
  window.__navguardLive = {
    get phase() { return L.phase; },
    /** true while Stop waits for the worker and discards the saved session */
    get stopping() { return !!L.stopping; },
    /** true once the stored session (if any) has been checked on load */
    get checked() { return !!L.checked; },
    get source() { return L.source; },
    get speed() { return L.speed; },
    get config() { return L.config; },
    get startRow() { return L.startRow; },
    get startRowCount() { return L.startRowCount; },
    get startStats() { return L.startStats; },
    get resumed() { return L.resumed; },
    get nextRow() { return L.nextRow; },
    get totalRows() { return L.totalRows; },
    get rowCount() { return L.rowCount; },
    get stats() { return L.stats; },
    get last() { return L.last; },
    get info() { return L.info; },
    get saves() { return L.saves; },
    get lastSaved() { return L.lastSaved; },
    get draws() { return L.draws || 0; },
    get plotPoints() { return L.plot ? L.plot.data[0].length : 0; },
    /** Per-row outputs since the start/resume: {startRow, n, status, kind, f, r, c}. */
    fetchRecord: () => request({ type: 'record' }).then((m) => m.record),
    /** The stored live-session record (or undefined). */
    readSaved: () => store.get(store.SESSION),
    /** A session fed by a live link instead of a replay: startLink(name),
     *  then feed([{t, lat, lon, ...}, ...]) as rows arrive. */
    startLink: (name) => launch({ kind: 'link', name: name || 'live link' }, null, ui.readConfig(), 0, null),
    feed: (rows) => L.worker.postMessage({ type: 'rows', rows }),
  };
}
