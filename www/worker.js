// navguard audit worker: reads the log, parses it, runs the detector and
// prepares compact plot data, so the page never blocks. Messages in:
//   {type:'file', file: File, config}      read + parse + audit
//   {type:'sim', name, seed, config}       simulate + parse + audit
//   {type:'rerun', config}                 audit the cached log again
//   {type:'csv'}                           per-sample CSV of the last audit
//   {type:'compare', seeds, methods?, includeLog}  CompareRun over every method
//   {type:'compare-cancel', target}        stop the compare job `target`
//   {type:'tight', env, faultType, seed, strategy?, ganModel?, ganT2?}
//                                          tightSimulate + TightDetector (with
//                                          ganModel bytes: withGanModel, GAN-FDSR)
//   {type:'gan-train', options}            tightGanTrain (one synchronous call:
//                                          tight.js runs it in a worker of its own,
//                                          and cancels by terminating that worker)
// Messages out: ready | progress | result | csv | error (each with the job id),
// compare-progress | compare-result | compare-cancelled (see compare.js),
// tight-result, gan-progress | gan-result (see tight.js).
// A comparison runs in slices of ~50 ms, so audit messages are served in
// between (each job keeps its own wasm object).
import { flightSeries, reconciledAt, renderReport } from './report-html.js';
import init, { loadAudit, loadLab, Auditor, readLog, simulate, scenarioNames, Detector, CompareRun, TightDetector, tightSimulate, tightGanTrain, version } from './pkg/navguard.js';

// Messages that need the lab wasm module, loaded on the first of them.
const LAB = new Set(['compare', 'tight', 'gan-train', 'sim']);

const ready = init();
let bytes = null;     // Uint8Array of the current log
let log = null;       // readLog() result for it
let source = null;    // {kind:'file'|'sim', name, size}
let last = null;      // last audit result ({report, columns})

const post = (msg, transfer) => self.postMessage(msg, transfer || []);
const progress = (id, stage, frac, detail) => post({ type: 'progress', id, stage, frac, detail });
// Let the progress message leave before a long synchronous wasm call.
const yieldNow = () => new Promise((r) => setTimeout(r, 0));
// Same, without the 4 ms clamp nested timers get (used between audit slices).
const tick = new MessageChannel();
const tickWaiters = [];
tick.port1.onmessage = () => tickWaiters.shift()();
const yieldFast = () => new Promise((r) => { tickWaiters.push(r); tick.port2.postMessage(0); });

self.onmessage = async (ev) => {
  const msg = ev.data;
  const id = msg.id;
  try {
    await ready;
    if (LAB.has(msg.type)) await loadLab();
    if (msg.type === 'hello') {
      const d = new Detector(undefined);
      const defaults = d.config();
      d.free();
      post({ type: 'ready', id, scenarios: scenarioNames(), defaults, version: version() });
      return;
    }
    if (msg.type === 'compare') {
      await compare(id, msg);
      return;
    }
    if (msg.type === 'compare-cancel') {
      cancelled.add(msg.target);
      return;
    }
    if (msg.type === 'tight') {
      post(tight(id, msg));
      return;
    }
    if (msg.type === 'gan-train') {
      const res = ganTrain(id, msg);
      post(res, [res.model.buffer]);
      return;
    }
    if (msg.type === 'file') {
      bytes = await readFile(id, msg.file);
      source = { kind: 'file', name: msg.file.name, size: msg.file.size };
      await parse(id);
    } else if (msg.type === 'sim') {
      progress(id, 'reading', 0, `simulating “${msg.name}” (seed ${msg.seed})`);
      await yieldNow();
      const csv = simulate(msg.name, Number(msg.seed));
      bytes = new TextEncoder().encode(csv);
      source = { kind: 'sim', name: `${msg.name}-seed${msg.seed}.csv`, scenario: msg.name, seed: Number(msg.seed), size: bytes.length };
      progress(id, 'reading', 1, `simulated ${fmtBytes(bytes.length)}`);
      await parse(id);
    } else if (msg.type === 'rerun') {
      if (!bytes) throw new Error('no log loaded');
    } else if (msg.type === 'csv') {
      if (!last) throw new Error('no audit result yet');
      const blob = perSampleCsv(last.columns, last.report);
      post({ type: 'csv', id, blob });
      return;
    } else if (msg.type === 'html') {
      // The same report file as `navguard report FILE --html` (one module).
      if (!last) throw new Error('no audit result yet');
      const html = renderReport({ title: `navguard report: ${source.name}`, version: version(), flights: [{ name: source.name, report: last.report, series: flightSeries(log.columns, last.columns, last.report) }] });
      post({ type: 'html', id, blob: new Blob([html], { type: 'text/html' }) });
      return;
    } else {
      throw new Error(`unknown message ${msg.type}`);
    }
    const t0 = performance.now();
    const config = msg.config || undefined;
    // the configuration as the wasm checked it (method, defaults filled in)
    const d = new Detector(config);
    const checkedConfig = d.config();
    d.free();
    last = await audit(id, config);
    const auditMs = performance.now() - t0;
    progress(id, 'detecting', 1, 'preparing plot data');
    await yieldNow();
    const plot = preparePlots(log, last);
    post({ type: 'result', id, source, report: last.report, plot, auditMs, checkedConfig, logMeta: { format: log.format, rows: log.rows, columns: Object.keys(log.columns) } });
  } catch (e) {
    post({ type: 'error', id, message: e && e.message ? e.message : String(e) });
  }
};

// ----------------------------------------------------------- comparison

const cancelled = new Set(); // compare job ids asked to stop

// CompareRun: step() runs one (flight, method) pair (a few ms to a few hundred
// ms); step for ~50 ms, report the fraction, yield so a cancel can arrive.
async function compare(id, msg) {
  const t0 = performance.now();
  const opts = { seeds: Math.max(1, Math.min(100, Math.floor(Number(msg.seeds) || 3))) };
  if (Array.isArray(msg.methods) && msg.methods.length) opts.methods = msg.methods;
  const run = new CompareRun(opts);
  try {
    let logName = null;
    if (msg.includeLog) {
      if (!bytes || !source) throw new Error('no log is opened to include');
      run.addLog(source.name, bytes);
      logName = source.name;
    }
    let frac = 0;
    let steps = 0;
    post({ type: 'compare-progress', id, frac, steps });
    await yieldFast();
    while (frac < 1) {
      if (cancelled.delete(id)) {
        post({ type: 'compare-cancelled', id });
        return;
      }
      const s0 = performance.now();
      do {
        frac = run.step();
        steps++;
      } while (frac < 1 && performance.now() - s0 < 50);
      post({ type: 'compare-progress', id, frac, steps });
      await yieldFast();
    }
    cancelled.delete(id);
    const { comparison, markdown } = run.finish();
    post({ type: 'compare-result', id, comparison, markdown, logName, steps, ms: performance.now() - t0 });
  } finally {
    run.free();
  }
}

// ------------------------------------------------- tightly coupled GNSS/INS

const TIGHT_STRATEGIES = ['none', 'fdi', 'fda', 'switch', 'gan'];

// One simulated flight of docs/tight.md through a TightDetector (under a
// second of work, so in one go). Returns the GNSS epochs only (IMU-only rows
// carry no test), as plain arrays (null = not defined at that epoch).
function tight(id, msg) {
  const t0 = performance.now();
  const env = Math.floor(Number(msg.env));
  const faultType = Math.floor(Number(msg.faultType));
  const seed = Math.max(0, Math.floor(Number(msg.seed) || 0));
  if (!(env >= 1 && env <= 5)) throw new Error(`environment must be 1..5, got ${msg.env}`);
  if (!(faultType >= 0 && faultType <= 5)) throw new Error(`fault type must be 0..5, got ${msg.faultType}`);
  const sim = tightSimulate(env, faultType, seed);
  const config = { ...sim.config };
  if (msg.strategy) {
    if (!TIGHT_STRATEGIES.includes(msg.strategy)) throw new Error(`unknown strategy ${msg.strategy}`);
    config.strategy = msg.strategy;
  }
  // A trained GAN model (tightGanTrain's bytes) replaces the embedded one;
  // withGanModel makes the strategy GAN-FDSR whatever config says.
  const ganModel = msg.ganModel instanceof Uint8Array ? msg.ganModel : null;
  if (ganModel) config.strategy = 'gan';
  const det = ganModel ? TightDetector.withGanModel(config, ganModel) : new TightDetector(config);
  let out;
  try {
    out = det.pushCsv(sim.csv);
  } finally {
    det.free();
  }
  const ep = { t: [], status: [], prn: [], lambda: [], statistic: [], rdpop: [], action: [], nSats: [], ganScore: [] };
  const val = (x) => (typeof x === 'number' && Number.isFinite(x) ? x : null);
  for (const o of out) {
    if (o.status === 'no-gnss') continue;
    ep.t.push(o.t);
    ep.status.push(o.status);
    ep.prn.push(o.faultyPrn ?? null);
    ep.lambda.push(val(o.lambdaMax));
    ep.statistic.push(val(o.statistic));
    ep.rdpop.push(val(o.rdpop));
    ep.action.push(o.action ?? null);
    ep.nSats.push(o.nSats ?? null);
    ep.ganScore.push(val(o.ganScoreMax));
  }
  return {
    type: 'tight-result', id, env, faultType, seed,
    strategy: config.strategy, alpha: config.alpha, eta: config.eta,
    ganModel: ganModel ? 'trained' : config.strategy === 'gan' ? 'embedded' : null,
    ganT2: ganModel && Number.isFinite(msg.ganT2) ? msg.ganT2 : null,
    faultyPrn: sim.faultyPrn, faultStart: sim.faultStart, faultEnd: sim.faultEnd,
    rows: out.length, tEnd: out.length ? out[out.length - 1].t : 0,
    epochs: ep, ms: performance.now() - t0,
  };
}

// Train a GAN-FDSR model (tightGanTrain): one synchronous wasm call of tens
// of seconds; a gan-progress message leaves after every epoch.
function ganTrain(id, msg) {
  const t0 = performance.now();
  const res = tightGanTrain(msg.options || undefined, (p) => {
    post({ type: 'gan-progress', id, ...p, ms: performance.now() - t0 });
  });
  return { type: 'gan-result', id, ...res, ms: performance.now() - t0 };
}

async function readFile(id, file) {
  const total = file.size;
  const out = new Uint8Array(total);
  let got = 0;
  let lastPost = 0;
  progress(id, 'reading', 0, `0 / ${fmtBytes(total)}`);
  const reader = file.stream().getReader();
  for (;;) {
    const { done, value } = await reader.read();
    if (done) break;
    if (got + value.length > total) throw new Error('file grew while reading');
    out.set(value, got);
    got += value.length;
    const now = performance.now();
    if (now - lastPost > 50 || got === total) {
      lastPost = now;
      progress(id, 'reading', total ? got / total : 1, `${fmtBytes(got)} / ${fmtBytes(total)}`);
    }
  }
  return got === total ? out : out.subarray(0, got);
}

async function parse(id) {
  progress(id, 'parsing', 0, `recognising and parsing ${fmtBytes(bytes.length)}`);
  await yieldNow();
  log = null;
  last = null;
  log = readLog(bytes);
  progress(id, 'parsing', 1, `${log.format}: ${log.rows.toLocaleString('en-US')} samples`);
}

// Run the detector in slices so the page sees a real percentage. The time
// spent yielding between slices is small next to a slice (>= 20 000 rows).
async function audit(id, config) {
  const samples = `${log.rows.toLocaleString('en-US')} samples`;
  progress(id, 'detecting', 0, `running the detector over ${samples}: 0 %`);
  // The audit module (its own detector and readers, ~300 KB) loads on the
  // first audit: plotting a log (readLog) needs only the core.
  await loadAudit();
  await yieldNow();
  const a = new Auditor(bytes, config);
  try {
    const n = a.rows();
    const slice = Math.max(20000, Math.ceil(n / 100));
    // step() returns 1 once every row is in; the bound only guards a stall
    for (let frac = n ? 0 : 1, left = Math.ceil(n / slice) + 1; frac < 1 && left > 0; left--) {
      frac = a.step(slice);
      progress(id, 'detecting', frac, `running the detector over ${samples}: ${Math.floor(100 * frac)} %`);
      await yieldFast();
    }
    return a.finish();
  } finally {
    a.free();
  }
}

function fmtBytes(n) {
  if (n < 1024) return `${n} B`;
  if (n < 1024 * 1024) return `${(n / 1024).toFixed(1)} KiB`;
  return `${(n / 1048576).toFixed(1)} MiB`;
}

// ---------------------------------------------------------------- plot data

const R_EARTH = 6378137.0; // WGS-84 equatorial radius, m

/** Compact, exact data for stepped plots: only rows where a value changes, plus
 *  null rows that break lines across logging gaps. Plain arrays (null = gap). */
function preparePlots(log, audit) {
  const cols = log.columns;
  const ac = audit.columns;
  const t = ac.t;
  const n = t.length;
  const gaps = audit.report.dataGaps || [];
  const tMin = n ? t[0] : 0;
  const tMax = n ? t[n - 1] : 1;
  const inGapAfter = makeGapTest(gaps);

  // Indicators and kind, change points only.
  const ind = { t: [], f: [], r: [], c: [], status: [] };
  for (let i = 0; i < n; i++) {
    const changed = i === 0 || i === n - 1 || ac.f[i] !== ac.f[i - 1] || ac.r[i] !== ac.r[i - 1] || ac.c[i] !== ac.c[i - 1] || ac.status[i] !== ac.status[i - 1];
    if (i > 0 && inGapAfter(t[i - 1], t[i])) {
      // hold the last values up to the gap's start, then break the line
      if (ind.t[ind.t.length - 1] !== t[i - 1]) {
        ind.t.push(t[i - 1]); ind.f.push(num(ac.f[i - 1])); ind.r.push(num(ac.r[i - 1])); ind.c.push(num(ac.c[i - 1])); ind.status.push(ac.status[i - 1]);
      }
      pushRow(ind, (t[i - 1] + t[i]) / 2, null);
      ind.t.push(t[i]); ind.f.push(num(ac.f[i])); ind.r.push(num(ac.r[i])); ind.c.push(num(ac.c[i])); ind.status.push(ac.status[i]);
      continue;
    }
    if (!changed) continue;
    ind.t.push(t[i]);
    ind.f.push(num(ac.f[i]));
    ind.r.push(num(ac.r[i]));
    ind.c.push(num(ac.c[i]));
    ind.status.push(ac.status[i]);
  }

  // Kind runs: [start, end, kind].
  const runs = [];
  let k0 = n ? ac.kind[0] : 0;
  let s0 = tMin;
  for (let i = 1; i < n; i++) {
    const k = ac.kind[i];
    const gap = inGapAfter(t[i - 1], t[i]);
    if (k !== k0 || gap) {
      runs.push([s0, gap ? t[i - 1] : t[i], k0]);
      k0 = k;
      s0 = t[i];
    }
  }
  if (n) runs.push([s0, tMax, k0]);

  // GPS quality: rows that carry any of sats / eph / fix.
  const sats = cols.sats, eph = cols.eph, fix = cols.fix;
  const gq = { t: [], sats: [], eph: [], fix: [] };
  if (sats || eph || fix) {
    let prevT = null;
    for (let i = 0; i < n; i++) {
      const s = sats ? sats[i] : NaN, e = eph ? eph[i] : NaN, f = fix ? fix[i] : NaN;
      if (Number.isNaN(s) && Number.isNaN(e) && Number.isNaN(f)) continue;
      if (prevT !== null && inGapAfter(prevT, t[i])) pushRow(gq, (prevT + t[i]) / 2, null);
      gq.t.push(t[i]);
      gq.sats.push(num(s));
      gq.eph.push(num(e));
      gq.fix.push(num(f));
      prevT = t[i];
    }
  }

  // Track in local N/E metres around the first fix (or pn/pe as given).
  const tr = { t: [], n: [], e: [], kind: [], status: [] };
  const lat = cols.lat, lon = cols.lon, pn = cols.pn, pe = cols.pe;
  let lat0 = NaN, lon0 = NaN, cosLat0 = 1;
  for (let i = 0; i < n; i++) {
    let N, E;
    if (lat && lon && !Number.isNaN(lat[i]) && !Number.isNaN(lon[i])) {
      if (Number.isNaN(lat0)) { lat0 = lat[i]; lon0 = lon[i]; cosLat0 = Math.cos(lat0 * Math.PI / 180); }
      N = (lat[i] - lat0) * Math.PI / 180 * R_EARTH;
      E = (lon[i] - lon0) * Math.PI / 180 * R_EARTH * cosLat0;
    } else if (pn && pe && !Number.isNaN(pn[i]) && !Number.isNaN(pe[i])) {
      N = pn[i];
      E = pe[i];
    } else continue;
    if (fix && fix[i] < 2) continue; // a row that says "no fix" is not a position
    tr.t.push(t[i]);
    tr.n.push(N);
    tr.e.push(E);
    tr.kind.push(ac.kind[i]);
    tr.status.push(ac.status[i]);
  }

  const resPos = sparseSeries(t, [ac.rPn, ac.rPe, ac.rPd, ac.rBaro], inGapAfter);
  const resVel = sparseSeries(t, [ac.rVn, ac.rVe, ac.rVd], inGapAfter);

  // Labels, for the summary (ground truth present?).
  const hasLabel = !!cols.label;
  return { tMin, tMax, ind, runs, gq, tr, resPos, resVel, anchor: Number.isNaN(lat0) ? null : [lat0, lon0], hasLabel, gaps };
}

/** Aligned data for measurement-rate series (residuals exist only on GPS or
 *  baro rows): x = the rows where any series is finite; per series the value,
 *  `undefined` where it has no sample (uPlot draws across it and the cursor
 *  skips it) and `null` to break the line over a data gap or a pause of more
 *  than max(1 s, 5 × its median sample interval), e.g. a GPS outage.
 *  Returns {t, ys: [[...], ...], n: [samples per series]}. */
function sparseSeries(t, cols, inGapAfter) {
  const k = cols.length;
  const have = cols.map((c) => !!c && c.length === t.length);
  // pass 1: per-series median interval
  const maxDt = cols.map((c, s) => {
    if (!have[s]) return Infinity;
    const dts = [];
    let prev = NaN;
    for (let i = 0; i < t.length; i++) {
      if (!Number.isFinite(c[i])) continue;
      if (!Number.isNaN(prev)) dts.push(t[i] - prev);
      prev = t[i];
    }
    if (!dts.length) return Infinity;
    const d = Float64Array.from(dts).sort();
    return Math.max(1, 5 * d[d.length >> 1]);
  });
  // pass 2: merge
  const x = [];
  const ys = cols.map(() => []);
  const lastT = new Array(k).fill(NaN);
  const lastIdx = new Array(k).fill(-1);
  const counts = new Array(k).fill(0);
  for (let i = 0; i < t.length; i++) {
    let any = false;
    for (let s = 0; s < k; s++) if (have[s] && Number.isFinite(cols[s][i])) { any = true; break; }
    if (!any) continue;
    const ti = t[i];
    // breaks first: null on every x between the series' last sample and this
    // one (uPlot clips a run of nulls from the sample before to the sample
    // after); a new x halfway when there is none in between
    for (let s = 0; s < k; s++) {
      if (!have[s] || !Number.isFinite(cols[s][i]) || lastIdx[s] < 0) continue;
      if (ti - lastT[s] <= maxDt[s] && !inGapAfter(lastT[s], ti)) continue;
      const j0 = lastIdx[s] + 1;
      // the last x may already be this instant (another series' sample)
      let end = x.length && x[x.length - 1] === ti ? x.length - 1 : x.length;
      if (j0 >= end) {
        x.splice(end, 0, (x[end - 1] + ti) / 2);
        for (let q = 0; q < k; q++) {
          // extend other series' null runs that reach up to here
          ys[q].splice(end, 0, ys[q][end - 1] === null ? null : undefined);
          if (lastIdx[q] >= end) lastIdx[q]++;
        }
        end++;
      }
      for (let j = j0; j < end; j++) ys[s][j] = null;
    }
    // rows sharing an instant (e.g. a GPS and a baro row) share one x
    const row = x.length && x[x.length - 1] === ti ? x.length - 1 : -1;
    const at = row >= 0 ? row : x.length;
    if (row < 0) {
      x.push(ti);
      for (const y of ys) y.push(undefined);
    }
    for (let s = 0; s < k; s++) {
      if (!have[s] || !Number.isFinite(cols[s][i])) continue;
      if (ys[s][at] != null) continue; // keep the first of two samples at one instant
      ys[s][at] = cols[s][i];
      lastT[s] = ti;
      lastIdx[s] = at;
      counts[s]++;
    }
  }
  return { t: x, ys, n: counts };
}

function pushRow(o, t, v) {
  for (const k of Object.keys(o)) o[k].push(k === 't' ? t : v);
}
function num(x) { return Number.isFinite(x) ? x : null; }

function makeGapTest(gaps) {
  // true when the step (a, b] crosses a reported data gap
  return (a, b) => {
    for (const g of gaps) if (a <= g.start + 1e-9 && b >= g.end - 1e-9 && b > a) return true;
    return false;
  };
}

const RESID_COLS = ['rPn', 'rPe', 'rPd', 'rVn', 'rVe', 'rVd', 'rBaro'];

/** The CLI's per-sample CSV: the contract's columns, kind, the residuals,
 * and the whole-log verdict (`reconciled`, as `audit --per-sample`). */
function perSampleCsv(c, report) {
  const parts = [`t,status,f,r,c,kind,${RESID_COLS.join(',')},reconciled\n`];
  const at = reconciledAt(report);
  const n = c.t.length;
  const res = RESID_COLS.map((k) => c[k] || new Float64Array(n).fill(NaN));
  const cell = (x) => (Number.isFinite(x) ? x : '');
  const CH = 20000;
  for (let i0 = 0; i0 < n; i0 += CH) {
    let s = '';
    const i1 = Math.min(n, i0 + CH);
    for (let i = i0; i < i1; i++) {
      s += `${c.t[i]},${c.status[i]},${c.f[i]},${c.r[i]},${c.c[i]},${c.kind[i]}`;
      for (const r of res) s += `,${cell(r[i])}`;
      s += `,${at(c.t[i])}\n`;
    }
    parts.push(s);
  }
  return new Blob(parts, { type: 'text/csv' });
}
