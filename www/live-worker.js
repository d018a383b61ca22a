// navguard live-session worker: owns one streaming Detector and feeds it rows
// in real time. A dedicated worker (not worker.js) so that an audit, or the
// audit's Cancel (which terminates worker.js), never stalls or kills a live
// session.
//
// Messages in (all may carry an `id`, echoed on the direct reply):
//   {type:'hello'}                                       -> ready
//   {type:'inspect', snapshot}                           -> inspected {info} | error
//   {type:'start', source, config, speed, resume?}       -> started | error
//       source: {kind:'sim', scenario, seed}             replay of a simulated scenario
//             | {kind:'file', name, size, bytes}         replay of a log (Uint8Array)
//             | {kind:'link', name}                      rows arrive as 'rows' messages
//       resume: {snapshot: Uint8Array, nextRow}          Detector.restore + continue at nextRow
//   {type:'rows', rows: [NavSample, ...]}                push rows from a live link (source kind 'link')
//   {type:'speed', speed}                                replay speed (number, or 0 = as fast as possible)
//   {type:'pause'} / {type:'play'} / {type:'stop'}
//   {type:'snapshot', reason}                            -> snapshot (now)
//   {type:'record'}                                      -> record (outputs since the start/resume)
// Messages out:
//   tick      {state, nextRow, totalRows, rowCount, stats, last, plot, rowErrors, simT}   ~4 Hz
//   snapshot  {snapshot, info, nextRow, rowCount, stats, reason}                           every SAVE_MS and on request
//   started   {startRow, totalRows, rowCount, stats, info, config, tStart, tEnd, resumed}
//   ended     {nextRow, rowCount, stats}
//   error     {phase, message}
import init, { loadLab, Detector, simulate, readLog, columnNames, snapshotInfo, scenarioNames, version } from './pkg/navguard.js';

const TICK_MS = 250;      // UI updates at most 4 times a second
const SAVE_MS = 2000;     // a snapshot for IndexedDB every 2 s of wall time
const SLICE_MS = 12;      // longest synchronous push loop
const RECORD_N = 20000;   // per-row outputs kept since the start/resume (test hook)

const ready = init();
const post = (msg, transfer) => self.postMessage(msg, transfer || []);
const errMsg = (e) => (e && e.message ? e.message : String(e));

let COLS = null;          // contract column names, pushRow order
let det = null;           // the Detector
let src = null;           // {kind, cols: [Float64Array|null per column], t, rows}
let next = 0;             // next source row index
let state = 'idle';       // idle | running | paused | ended
let speed = 1;            // 0 = as fast as possible
let anchorWall = 0, anchorT = 0; // replay clock: source time anchorT at wall time anchorWall
let timer = 0;
let lastTick = 0, lastSave = 0;
let rowErrors = 0, lastRowError = '';
let last = null;          // last output {t,status,f,r,c,kind}
let plot = newPlotBuf();  // change points since the last tick
let rec = null;           // outputs since the start/resume
const row = new Float64Array(32);
const out = new Float64Array(8);

function newPlotBuf() { return { t: [], f: [], r: [], c: [], kind: [], status: [] }; }

function newRecord(startRow) {
  return { startRow, n: 0, status: new Uint8Array(RECORD_N), kind: new Uint8Array(RECORD_N), f: new Float64Array(RECORD_N), r: new Float64Array(RECORD_N), c: new Float64Array(RECORD_N) };
}

self.onmessage = async (ev) => {
  const msg = ev.data;
  const id = msg.id;
  try {
    await ready;
    // A simulated source needs the lab wasm module, loaded on first use.
    if (msg.source?.kind === 'sim') await loadLab();
    if (!COLS) COLS = columnNames();
    switch (msg.type) {
      case 'hello':
        post({ type: 'ready', id, version: version(), scenarios: scenarioNames() });
        break;
      case 'inspect':
        post({ type: 'inspected', id, info: snapshotInfo(toBytes(msg.snapshot)) });
        break;
      case 'start':
        start(msg, id);
        break;
      case 'rows':
        if (!det || state === 'ended') throw new Error('no live session to push rows into');
        for (const s of msg.rows) pushSample(s);
        if (performance.now() - lastSave >= SAVE_MS) sendSnapshot('auto');
        else maybeTick(performance.now(), true);
        break;
      case 'speed':
        speed = Number(msg.speed) || 0;
        reanchor();
        break;
      case 'pause':
        if (state !== 'running') break;
        state = 'paused';
        clearTimeout(timer);
        sendSnapshot('pause');
        break;
      case 'play':
        if (state !== 'paused') break;
        state = 'running';
        reanchor();
        schedule(0);
        tick();
        break;
      case 'stop':
        halt();
        post({ type: 'stopped', id });
        break;
      case 'snapshot':
        if (det) sendSnapshot(msg.reason || 'request', id);
        break;
      case 'record':
        post({ type: 'record', id, record: recordOut() });
        break;
      default:
        throw new Error(`unknown message ${msg.type}`);
    }
  } catch (e) {
    post({ type: 'error', id, phase: msg.type, message: errMsg(e) });
  }
};

function toBytes(x) {
  if (x instanceof Uint8Array) return x;
  if (x instanceof ArrayBuffer) return new Uint8Array(x);
  throw new Error('snapshot: stored value is not a byte array');
}

function halt() {
  clearTimeout(timer);
  if (det) det.free();
  det = null;
  src = null;
  state = 'idle';
}

function start(msg, id) {
  halt();
  const s = msg.source || {};
  let bytes;
  if (s.kind === 'sim') {
    bytes = new TextEncoder().encode(simulate(String(s.scenario), Number(s.seed)));
  } else if (s.kind === 'file') {
    bytes = toBytes(s.bytes);
    if (s.size != null && bytes.length !== s.size) throw new Error(`${s.name}: ${bytes.length} bytes, expected ${s.size}`);
  } else if (s.kind !== 'link') {
    throw new Error(`unknown live source ${s.kind}`);
  }
  let startRow = 0;
  let resumed = false;
  let d;
  if (msg.resume) {
    // throws on a damaged snapshot or one of another format version
    d = Detector.restore(toBytes(msg.resume.snapshot));
    startRow = Number(msg.resume.nextRow) || 0;
    resumed = true;
  } else {
    d = new Detector(msg.config || undefined);
  }
  let log = null;
  if (bytes) {
    try {
      log = readLog(bytes);
    } catch (e) {
      d.free();
      throw e;
    }
    if (startRow > log.rows) {
      d.free();
      throw new Error(`saved live session is at row ${startRow}, but the source has only ${log.rows} rows`);
    }
  }
  det = d;
  src = log
    ? { kind: s.kind, rows: log.rows, t: log.columns.t, cols: COLS.map((k) => log.columns[k] || null) }
    : { kind: 'link', rows: Infinity, t: null, cols: null };
  next = startRow;
  rowErrors = 0;
  lastRowError = '';
  last = null;
  plot = newPlotBuf();
  rec = newRecord(startRow);
  speed = Number(msg.speed) || 0;
  state = 'running';
  const snap = det.snapshot();
  post({
    type: 'started', id, resumed, startRow, totalRows: log ? log.rows : null,
    rowCount: det.rowCount(), stats: det.stats(), info: snapshotInfo(snap), config: det.config(),
    tStart: log && log.rows ? log.columns.t[0] : null, tEnd: log && log.rows ? log.columns.t[log.rows - 1] : null,
    format: log ? log.format : null,
  });
  lastSave = lastTick = performance.now();
  reanchor();
  if (src.t) schedule(0);
  tick();
}

// The replay clock restarts at the next row's time (after a pause, a speed
// change or a resume), so nothing is skipped and nothing bursts.
function reanchor() {
  anchorWall = performance.now();
  anchorT = src && src.t && next < src.rows ? src.t[next] : 0;
}

function schedule(ms) {
  clearTimeout(timer);
  timer = setTimeout(pump, ms);
}

function pump() {
  if (state !== 'running' || !src || !src.t) return;
  const t0 = performance.now();
  const target = speed > 0 ? anchorT + ((t0 - anchorWall) / 1000) * speed : Infinity;
  const t = src.t;
  const n = src.rows;
  let k = 0;
  while (next < n && t[next] <= target) {
    pushIndex(next);
    next++;
    if ((++k & 63) === 0 && performance.now() - t0 > SLICE_MS) break;
  }
  const now = performance.now();
  if (next >= n) {
    state = 'ended';
    sendSnapshot('end');
    post({ type: 'ended', nextRow: next, rowCount: det.rowCount(), stats: det.stats() });
    return;
  }
  maybeTick(now, false);
  if (now - lastSave >= SAVE_MS) sendSnapshot('auto');
  // wait for the next row's time (capped so the UI keeps ticking)
  const wait = speed > 0 ? Math.min(TICK_MS, Math.max(0, ((t[next] - anchorT) / speed) * 1000 - (now - anchorWall))) : 0;
  schedule(wait);
}

function pushIndex(i) {
  const cols = src.cols;
  for (let j = 0; j < cols.length; j++) row[j] = cols[j] ? cols[j][i] : NaN;
  pushRow(row);
}

function pushSample(s) {
  for (let j = 0; j < COLS.length; j++) {
    const v = s[COLS[j]];
    row[j] = v == null || v === '' ? NaN : Number(v);
  }
  pushRow(row);
  next++;
}

// The one place rows enter the detector, whatever the source (replay or link).
function pushRow(r) {
  try {
    det.pushRowInto(r.subarray(0, COLS.length), out);
  } catch (e) {
    rowErrors++;
    lastRowError = errMsg(e);
    return;
  }
  const [t, status, f, rr, c, kind] = out;
  if (rec && rec.n < RECORD_N) {
    const j = rec.n++;
    rec.status[j] = status; rec.kind[j] = kind; rec.f[j] = f; rec.r[j] = rr; rec.c[j] = c;
  }
  // change points only: F/R/C move on GPS epochs, kind on any row
  if (!last || last.f !== f || last.r !== rr || last.c !== c || last.kind !== kind || last.status !== status || plot.t.length === 0) {
    plot.t.push(t); plot.f.push(f); plot.r.push(rr); plot.c.push(c); plot.kind.push(kind); plot.status.push(status);
  }
  last = { t, status, f, r: rr, c, kind };
}

function maybeTick(now, force) {
  if (force || now - lastTick >= TICK_MS) tick();
}

function tick() {
  lastTick = performance.now();
  if (!det) return;
  // always include the latest row so the plot reaches "now"
  if (last && plot.t[plot.t.length - 1] !== last.t) {
    plot.t.push(last.t); plot.f.push(last.f); plot.r.push(last.r); plot.c.push(last.c); plot.kind.push(last.kind); plot.status.push(last.status);
  }
  const p = {
    t: Float64Array.from(plot.t), f: Float64Array.from(plot.f), r: Float64Array.from(plot.r),
    c: Float64Array.from(plot.c), kind: Uint8Array.from(plot.kind), status: Uint8Array.from(plot.status),
  };
  plot = newPlotBuf();
  post({
    type: 'tick', state, nextRow: next, totalRows: src && Number.isFinite(src.rows) ? src.rows : null,
    rowCount: det.rowCount(), stats: det.stats(), last, plot: p, rowErrors, lastRowError,
    recorded: rec ? rec.n : 0,
  }, [p.t.buffer, p.f.buffer, p.r.buffer, p.c.buffer, p.kind.buffer, p.status.buffer]);
}

function sendSnapshot(reason, id) {
  tick(); // the page's counters never lag behind what is saved
  lastSave = performance.now();
  const snapshot = det.snapshot();
  const info = snapshotInfo(snapshot);
  post({ type: 'snapshot', id, reason, snapshot, info, nextRow: next, rowCount: det.rowCount(), stats: det.stats(), state, rowErrors }, [snapshot.buffer]);
}

function recordOut() {
  if (!rec) return null;
  const n = rec.n;
  return { startRow: rec.startRow, n, status: rec.status.slice(0, n), kind: rec.kind.slice(0, n), f: rec.f.slice(0, n), r: rec.r.slice(0, n), c: rec.c.slice(0, n) };
}
