// navguard ground-station page. All heavy work (reading, parsing, detection,
// plot-data preparation, CSV export) happens in worker.js; this module only
// drives the UI and the uPlot charts. The live session (streaming rows into a
// Detector, snapshot kept in IndexedDB) is live.js with its own live-worker.js.
import uPlot from './vendor/uPlot.esm.js';
import { initLive } from './live.js';
import { initCompare } from './compare.js';
import { initTight } from './tight.js';
import { verdictOf, qualityLabel, fmtUtc, fmtSince, checkedWithoutGps, robustRange, ticks } from './report-html.js';

const $ = (sel) => document.querySelector(sel);
const STAGES = ['reading', 'parsing', 'detecting', 'plotting'];
const COLORS = {
  normal: '#2563eb',
  fault: '#dc2626',
  outage: '#d97706',
  nogps: '#9ca3af',
  gap: '#6b7280',
  f: '#1d4ed8',
  thr: '#b91c1c',
  r: '#7c3aed',
  c: '#0f766e',
  sats: '#1d4ed8',
  eph: '#c2410c',
  fix: '#15803d',
  track: '#94a3b8',
  rn: '#2563eb',
  re: '#16a34a',
  rd: '#9333ea',
  baro: '#ea580c',
};
const KIND_FILL = { 1: 'rgba(220,38,38,0.13)', 2: 'rgba(217,119,6,0.16)', 3: 'rgba(156,163,175,0.18)' };
const KIND_SOLID = { 0: '#dbeafe', 1: COLORS.fault, 2: COLORS.outage, 3: '#d1d5db' };
const KIND_NAME = { 0: 'normal', 1: 'residual fault', 2: 'GPS outage', 3: 'no GPS yet' };
const FAULT_KIND_LABEL = { residual: 'residual fault', gps_outage: 'GPS outage', gps_stale: 'GPS output frozen', gps_degraded: 'GPS degraded (receiver-declared)' };
const SYNC_KEY = 'navguard-time';
const AXIS_L = 64; // fixed axis widths keep every time plot's x pixels aligned
const AXIS_R = 56;

const state = {
  worker: null,
  ready: null,        // {scenarios, defaults, version}
  job: 0,             // id of the job in flight (0 = idle)
  jobKind: null,
  workerHasLog: false,
  pendingRerun: false,
  result: null,       // last result message
  config: null,       // config used for the last result
  plots: [],          // time plots
  track: null,
  selected: -1,
  syncing: false,
  progressLog: [],    // progress messages of the current job (for the test)
};
window.navguard = state; // handle for debugging and the browser test

// ------------------------------------------------------------------ worker

function startWorker() {
  const w = new Worker(new URL('./worker.js', import.meta.url), { type: 'module' });
  w.onmessage = (ev) => onWorkerMessage(ev.data);
  w.onerror = (ev) => {
    ev.preventDefault();
    showError(`Worker failed: ${ev.message || 'could not start (is the wasm build in www/pkg/?)'}`);
    finishJob();
  };
  state.worker = w;
  state.workerHasLog = false;
  if (compare) {
    compare.workerRestarted();
    compare.refresh();
  }
  if (tight) tight.workerRestarted();
  return w;
}

let compare = null; // the "Compare methods" panel (compare.js)
let tight = null;   // the "Tightly coupled" panel (tight.js)
let nextId = 1;
function send(msg) {
  const id = nextId++;
  state.worker.postMessage({ ...msg, id });
  return id;
}

function runJob(kind, msg) {
  if (state.job && kind !== 'rerun') {
    // a new log replaces whatever is in flight
    state.worker.terminate();
    startWorker();
    send({ type: 'hello' });
  }
  hideError();
  state.jobKind = kind;
  state.job = send(msg);
  document.body.dataset.state = 'busy';
  state.progressLog = [];
  showProgress(kind === 'rerun' ? 'detecting' : 'reading', 0, kind === 'rerun' ? 'rerunning with the new configuration' : '');
}

function finishJob() {
  state.job = 0;
  state.jobKind = null;
  $('#progress').hidden = true;
  document.body.dataset.state = state.result ? 'done' : 'idle';
}

function onWorkerMessage(m) {
  if (m.type === 'ready') {
    state.ready = m;
    fillScenarios(m.scenarios);
    if (!state.config) setConfigForm(m.defaults);
    if (!state.job) document.body.dataset.state = state.result ? 'done' : 'idle';
    return;
  }
  if (m.type === 'csv') {
    download(m.blob, `${baseName()}.per-sample.csv`);
    return;
  }
  if (m.type === 'html') {
    state.lastHtml = m.blob;
    download(m.blob, `${baseName()}.report.html`);
    return;
  }
  if (compare && compare.onMessage(m)) return;
  if (tight && tight.onMessage(m)) return;
  if (m.id !== state.job) return; // stale
  if (m.type === 'progress') {
    showProgress(m.stage, m.frac, m.detail);
  } else if (m.type === 'error') {
    showError(m.message);
    if (state.jobKind !== 'rerun') state.workerHasLog = false;
    finishJob();
    if (compare) compare.refresh();
    $('#config-state').textContent = '';
  } else if (m.type === 'result') {
    state.workerHasLog = true;
    showProgress('plotting', 0, 'drawing plots');
    // let the progress bar paint before building the charts
    requestAnimationFrame(() => setTimeout(() => {
      try {
        render(m);
      } catch (e) {
        showError(`Plotting failed: ${e.message}`);
      }
      finishJob();
      if (state.pendingRerun) {
        state.pendingRerun = false;
        rerun();
      }
    }, 0));
  }
}

// ---------------------------------------------------------------- progress

function showProgress(stage, frac, detail) {
  if (state.progressLog.length < 1000) state.progressLog.push({ stage, frac, detail });
  const p = $('#progress');
  p.hidden = false;
  const si = STAGES.indexOf(stage);
  for (const li of p.querySelectorAll('.stages li')) {
    const i = STAGES.indexOf(li.dataset.stage);
    li.className = i < si ? 'done' : i === si ? 'active' : '';
  }
  $('#progress-bar').value = (si + Math.max(0, Math.min(1, frac || 0))) / STAGES.length;
  $('#progress-detail').textContent = detail || '';
}

function showError(msg) {
  const e = $('#error');
  e.textContent = msg;
  e.hidden = false;
}
function hideError() {
  $('#error').hidden = true;
}

// ------------------------------------------------------------------- input

function openFile(file) {
  if (!file) return;
  state.source = { kind: 'file', name: file.name };
  runJob('file', { type: 'file', file, config: readConfig() });
}

function fillScenarios(names) {
  const sel = $('#scenario');
  sel.textContent = '';
  for (const n of names) {
    const o = document.createElement('option');
    o.value = o.textContent = n;
    sel.append(o);
  }
  sel.value = names.includes('paper') ? 'paper' : names[0];
  sel.disabled = false;
  $('#sim-run').disabled = false;
}

function setConfigForm(cfg) {
  const f = $('#config');
  f.method.value = cfg.method || 'anfis';
  f.tc.value = cfg.tc;
  f.window.value = cfg.window;
  f.threshold.value = cfg.threshold;
}

function readConfig() {
  const f = $('#config');
  const cfg = {};
  if (f.method.value) cfg.method = f.method.value;
  const tc = Number(f.tc.value), w = Number(f.window.value), th = Number(f.threshold.value);
  if (f.tc.value !== '' && Number.isFinite(tc)) cfg.tc = tc;
  if (f.window.value !== '' && Number.isFinite(w)) cfg.window = w;
  if (f.threshold.value !== '' && Number.isFinite(th)) cfg.threshold = th;
  return cfg;
}

let rerunTimer = 0;
function scheduleRerun() {
  clearTimeout(rerunTimer);
  const f = $('#config');
  if (!f.checkValidity()) {
    $('#config-state').textContent = 'invalid value';
    return;
  }
  $('#config-state').textContent = state.workerHasLog ? 'rerunning…' : '';
  rerunTimer = setTimeout(rerun, 350);
}

function rerun() {
  if (!state.workerHasLog) return;
  if (state.job) {
    state.pendingRerun = true;
    return;
  }
  runJob('rerun', { type: 'rerun', config: readConfig() });
}

// ------------------------------------------------------------------ render

function render(m) {
  const keepX = m.source && state.result && state.jobKind === 'rerun' ? currentX() : null;
  state.result = m;
  state.config = readConfig();
  state.renders = (state.renders || 0) + 1;
  document.body.classList.add('has-result');
  state.selected = -1;
  renderVerdict(m);
  renderSummary(m);
  renderTable(m.report);
  renderPlots(m, keepX);
  $('#export-json').disabled = false;
  $('#export-csv').disabled = false;
  $('#export-html').disabled = false;
  $('#config-state').textContent = `audit ${m.auditMs.toFixed(0)} ms`;
  if (compare) compare.refresh();
}

const fmt = (x, d = 2) => (x == null || !Number.isFinite(x) ? '—' : x.toFixed(d));
const pct = (x) => (x == null || !Number.isFinite(x) ? '—' : `${(100 * x).toFixed(1)} %`);
function esc(s) {
  return String(s).replace(/[&<>"']/g, (c) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;', "'": '&#39;' })[c]);
}

/** Seconds since the log's start: every time the page shows. */
const t0Of = (m) => (m && Number.isFinite(m.report.startT) ? m.report.startT : 0);

// The operator's answer first: verdict, what it rests on, when the flight was.
function renderVerdict(m) {
  const r = m.report;
  const v = verdictOf(r);
  const faults = r.faults;
  const flagged = faults.reduce((a, f) => a + (f.end - f.start), 0);
  const el = $('#verdict');
  el.dataset.verdict = v;
  el.hidden = false;
  // A fault only the whole-log verdict holds (a drag-off the detector
  // followed, dated at its end) has no causal interval to count.
  const rec = r.reconciled || [];
  const head = v === 'faults' && !faults.length ? `${rec.length} fault interval${rec.length === 1 ? '' : 's'} over the whole log, none flagged as the samples came`
    : v === 'faults' ? `${faults.length} fault interval${faults.length === 1 ? '' : 's'}, ${fmt(flagged, 1)} s flagged`
    : v === 'clean' ? 'No navigation fault found' : 'No verdict: no GPS fix in this log';
  const when = fmtUtc(r.startUtc) ? `started ${fmtUtc(r.startUtc)}` : 'start time unknown (no GPS time in the log)';
  const mode = (r.modes || []).length ? ` · ${r.modes.length} flight mode${r.modes.length === 1 ? '' : 's'}` : '';
  const alerts = (r.messages || []).filter((x) => x.level === 'error' || x.level === 'warning').length;
  const msgs = (r.messages || []).length ? ` · ${r.messages.length} autopilot messages (${alerts} warnings/errors)` : '';
  el.innerHTML = `<span class="verdict-badge v-${v.replace(' ', '-')}">${esc(v)}</span>` +
    `<div class="verdict-text"><strong>${esc(head)}</strong>` +
    `<span class="muted">${esc(m.source.name)} · ${esc(FORMAT_NAME[r.format] || r.format)} · ${fmt(r.durationS, 1)} s · ${esc(when)}${esc(mode)}${esc(msgs)}</span>` +
    (r.gpsAvailable ? `<span class="muted">GPS ${fmt(r.gpsRateHz, 1)} Hz, ${pct(r.flaggedGpsEpochFraction)} of epochs flagged; receiver quality as ${esc(qualityLabel(r))}; times are seconds since the log's start</span>`
      : `<span class="nogps-note">${esc(checkedWithoutGps(r))}</span>`) +
    '</div>';
}

function renderSummary(m) {
  const r = m.report;
  const src = m.source;
  const counts = { residual: 0, gps_outage: 0 };
  for (const f of r.faults) counts[f.kind] = (counts[f.kind] || 0) + 1;
  const faultTime = r.faults.reduce((a, f) => a + (f.end - f.start), 0);
  const meta = new Map(r.meta);
  const rows = [
    ['Source', src.kind === 'sim' ? `simulated “${esc(src.scenario)}”, seed ${src.seed}` : esc(src.name)],
    ['Format', `${esc(FORMAT_NAME[r.format] || r.format)}${meta.get('firmware') ? ` <span class="muted">(${esc(meta.get('firmware'))})</span>` : ''}`],
    ['Samples', `${r.rows.toLocaleString('en-US')} <span class="muted">(${(src.size / 1048576).toFixed(2)} MiB)</span>`],
    ['Start (UTC)', fmtUtc(r.startUtc) ? esc(fmtUtc(r.startUtc)) : '<span class="muted">unknown (no GPS time in the log)</span>'],
    ['Duration', `${fmt(r.durationS, 1)} s <span class="muted">(boot clock ${fmt(m.plot.tMin, 1)}–${fmt(m.plot.tMax, 1)} s)</span>`],
    ['Receiver quality', r.ephSource === 'hdop' ? 'HDOP <span class="muted">(unitless; no accuracy in metres in this log)</span>' : r.ephSource === 'eph' ? 'eph (m)' : '<span class="muted">not in the log</span>'],
    ['GPS rate', r.gpsEpochs ? `${fmt(r.gpsRateHz, 1)} Hz <span class="muted">(${r.gpsEpochs.toLocaleString('en-US')} epochs)</span>` : '— <span class="muted">(no GPS epochs)</span>'],
    ['IMU rate', r.imuRateHz > 0 ? `${fmt(r.imuRateHz, 1)} Hz` : '— <span class="muted">(no IMU)</span>'],
    ['GPS availability', r.gpsAvailable ? `${pct(r.gpsFixFraction)} <span class="muted">of epochs with a fix</span>` : '<span class="bad">GPS unavailable</span>'],
    ['Flagged GPS epochs', pct(r.flaggedGpsEpochFraction)],
    ['Fault intervals', `<span class="tag fault">${counts.residual} residual</span> <span class="tag outage">${counts.gps_outage} outage</span>${counts.gps_stale ? ` <span class="tag outage">${counts.gps_stale} frozen</span>` : ''}${counts.gps_degraded ? ` <span class="tag outage">${counts.gps_degraded} degraded</span>` : ''} <span class="muted">${fmt(faultTime, 1)} s total</span>`],
    ['Data gaps', r.dataGaps.length ? r.dataGaps.map((g) => `${fmt(g.start - t0Of(m), 1)}–${fmt(g.end - t0Of(m), 1)} s`).join(', ') : 'none'],
    ['Missing inputs', r.missing.length ? `<span class="warn">${r.missing.map(esc).join(', ')}</span>` : 'none'],
    ['Method', esc(methodOf(m))],
    ['Detector', `${r.stats.retrains} retrains, ${r.stats.filterResets} filter resets${r.stats.filterErrors ? `, <span class="warn">${r.stats.filterErrors} filter errors</span>` : ''}`],
  ];
  let html = '<dl class="kv">' + rows.map(([k, v]) => `<dt>${k}</dt><dd>${v}</dd>`).join('') + '</dl>';
  const warnings = r.warnings.slice();
  if (!r.gpsAvailable && !warnings.some((w) => /GPS unavailable/i.test(w))) warnings.unshift('GPS unavailable: no valid fix in this log');
  if (warnings.length) {
    html += `<h3>Warnings</h3><ul class="warnings">${warnings.map((w) => `<li>${esc(w)}</li>`).join('')}</ul>`;
  }
  if (r.metrics) {
    const x = r.metrics;
    html += '<h3>Metrics against labels</h3><dl class="kv metrics">' + [
      ['Accuracy', pct(x.accuracy)],
      ['False-alarm rate', pct(x.falseAlarmRate)],
      ['Misdetection rate', pct(x.misdetectionRate)],
      ['Precision / recall', `${pct(x.precision)} / ${pct(x.recall)}`],
      ['Mean detection delay', `${fmt(x.meanDetectionDelay, 2)} s`],
      ['Intervals detected', `${x.detectedIntervals} / ${x.faultIntervals}`],
      ['TP / FP / TN / FN', `${x.tp} / ${x.fp} / ${x.tn} / ${x.fn}`],
    ].map(([k, v]) => `<dt>${k}</dt><dd>${v}</dd>`).join('') + '</dl>';
  }
  const t0 = t0Of(m);
  if ((r.modes || []).length) {
    html += `<details class="modes" open><summary>Flight modes (${r.modes.length})</summary><ul class="events">${r.modes.map((x) => `<li><span class="num">${fmtSince(x.t - t0)}</span> ${esc(x.mode)}</li>`).join('')}</ul></details>`;
  }
  if ((r.messages || []).length) {
    html += `<details class="messages"><summary>Autopilot messages (${r.messages.length})</summary><ul class="events">${r.messages.map((x) => `<li class="lvl-${esc(x.level)}"><span class="num">${fmtSince(x.t - t0)}</span> <b>${esc(x.level)}</b> ${esc(x.text)}</li>`).join('')}</ul></details>`;
  }
  if (r.meta.length) {
    html += `<details class="meta"><summary>Log metadata (${r.meta.length})</summary><dl class="kv">${r.meta.map(([k, v]) => `<dt>${esc(k)}</dt><dd>${esc(v)}</dd>`).join('')}</dl></details>`;
  }
  $('#summary').innerHTML = html;
}
// The method the result was computed with (as the worker's wasm checked it).
function methodOf(m) {
  return (m.checkedConfig && m.checkedConfig.method) || (state.config && state.config.method) || 'anfis';
}
const FORMAT_NAME = { csv: 'navlog CSV', ulog: 'PX4 ULog', dataflash: 'ArduPilot DataFlash' };

function renderTable(report) {
  const tb = $('#faults tbody');
  tb.textContent = '';
  $('#fault-count').textContent = `(${report.faults.length})`;
  if (!report.faults.length) {
    tb.innerHTML = report.gpsAvailable
      ? '<tr class="empty"><td colspan="9">No fault intervals detected.</td></tr>'
      : `<tr class="empty"><td colspan="9"><span class="bad">No verdict: GPS unavailable in this log</span>. ${esc(checkedWithoutGps(report))}</td></tr>`;
    return;
  }
  report.faults.forEach((f, i) => {
    const tr = document.createElement('tr');
    tr.tabIndex = 0;
    tr.dataset.index = i;
    tr.dataset.start = f.start;
    tr.dataset.end = f.end;
    tr.dataset.kind = f.kind;
    tr.className = f.kind === 'residual' ? 'k-fault' : 'k-outage';
    // data-start/end: boot clock (as the report); shown: since the log's start
    const t0 = t0Of(state.result);
    tr.innerHTML = `<td class="num muted">${i + 1}</td><td class="num">${fmt(f.start - t0, 2)}</td><td class="num">${fmt(f.end - t0, 2)}</td>` +
      `<td class="num">${fmt(f.end - f.start, 2)}</td><td><i class="sw ${f.kind === 'residual' ? 'fault' : 'outage'}"></i>${FAULT_KIND_LABEL[f.kind] || esc(f.kind)}</td>` +
      `<td>${esc(typeof f.severity === 'string' ? f.severity : '—')}</td>` +
      `<td class="num">${fmt(f.peakF, 3)}</td><td>${esc(f.driver === 'none' ? '—' : f.driver.replace(/_/g, ' '))}</td><td>${esc(f.indicator === 'none' ? '—' : f.indicator)}</td>`;
    tb.append(tr);
  });
}

function selectFault(i) {
  const f = state.result && state.result.report.faults[i];
  if (!f) return;
  state.selected = i;
  for (const tr of $('#faults tbody').children) tr.classList.toggle('selected', Number(tr.dataset.index) === i);
  const dur = f.end - f.start;
  const margin = Math.max(2, dur * 0.5);
  setX(f.start - margin, f.end + margin);
}

// ------------------------------------------------------------------- plots

function destroyPlots() {
  for (const u of state.plots) u.destroy();
  state.plots = [];
  if (state.track) state.track.destroy();
  state.track = null;
}

function currentX() {
  const u = state.plots[0];
  if (!u) return null;
  const { min, max } = u.scales.x;
  const d = u.data[0];
  if (!d.length || (min <= d[0] && max >= d[d.length - 1])) return null; // not zoomed
  return [min, max];
}

function setX(min, max) {
  state.syncing = true;
  for (const u of state.plots) u.setScale('x', { min, max });
  state.syncing = false;
  updateTrackWindow(min, max);
}

function timeWidth() {
  return Math.max(320, $('.timeplots').clientWidth);
}

// Shade residual-fault / outage / no-GPS runs and data gaps behind the series.
function shadeHook(solid) {
  return (u) => {
    const m = state.result;
    if (!m) return;
    const { ctx } = u;
    const { left, top, width, height } = u.bbox;
    ctx.save();
    ctx.beginPath();
    ctx.rect(left, top, width, height);
    ctx.clip();
    for (const [s, e, k] of m.plot.runs) {
      if (!solid && k === 0) continue;
      const x0 = u.valToPos(s, 'x', true);
      const x1 = u.valToPos(e, 'x', true);
      if (x1 < left || x0 > left + width) continue;
      ctx.fillStyle = solid ? KIND_SOLID[k] : KIND_FILL[k];
      ctx.fillRect(x0, top, Math.max(solid ? 1 : 1.5, x1 - x0), height);
    }
    ctx.fillStyle = hatch(ctx);
    for (const g of m.plot.gaps) {
      const x0 = u.valToPos(g.start, 'x', true);
      const x1 = u.valToPos(g.end, 'x', true);
      ctx.fillRect(x0, top, x1 - x0, height);
    }
    drawEvents(u, m.report, solid);
    ctx.restore();
  };
}

const MODE_TINTS = ['rgba(37,99,235,0.10)', 'rgba(22,163,74,0.12)', 'rgba(234,179,8,0.16)', 'rgba(147,51,234,0.10)', 'rgba(13,148,136,0.12)'];

// Flight modes as a tinted strip along the top (named on the status band)
// and the autopilot's warnings and errors as dashed vertical lines.
function drawEvents(u, r, named) {
  const { ctx } = u;
  const { left, top, width, height } = u.bbox;
  const pr = devicePixelRatio || 1;
  const modes = r.modes || [];
  const strip = Math.round((named ? 14 : 5) * pr);
  modes.forEach((md, i) => {
    const x0 = Math.max(left, u.valToPos(md.t, 'x', true));
    const x1 = Math.min(left + width, i + 1 < modes.length ? u.valToPos(modes[i + 1].t, 'x', true) : left + width);
    if (x1 <= x0) return;
    ctx.fillStyle = MODE_TINTS[i % MODE_TINTS.length].replace(/0\.\d+\)$/, named ? '0.35)' : '0.45)');
    ctx.fillRect(x0, top, x1 - x0, strip);
    ctx.fillStyle = 'rgba(17,24,39,0.55)';
    ctx.fillRect(x0, top, Math.max(1, pr), named ? height : strip);
    if (named && x1 - x0 > 30 * pr) {
      ctx.fillStyle = '#111827';
      ctx.font = `${10 * pr}px system-ui, sans-serif`;
      ctx.textBaseline = 'top';
      ctx.fillText(md.mode, x0 + 3 * pr, top + 2 * pr, x1 - x0 - 4 * pr);
    }
  });
  ctx.setLineDash([3 * pr, 3 * pr]);
  ctx.lineWidth = pr;
  for (const msg of r.messages || []) {
    if (msg.level !== 'error' && msg.level !== 'warning') continue;
    const x = u.valToPos(msg.t, 'x', true);
    if (x < left || x > left + width) continue;
    ctx.strokeStyle = msg.level === 'error' ? 'rgba(185,28,28,0.7)' : 'rgba(126,34,206,0.6)';
    ctx.beginPath();
    ctx.moveTo(x, top);
    ctx.lineTo(x, top + height);
    ctx.stroke();
  }
  ctx.setLineDash([]);
}

// Scales whose range is robust (percentiles), so points may fall outside.
const ROBUST_SCALES = new Set(['y', 'm']);

// Points outside a plot's robust y range: a small triangle at the edge.
function clipMarks(u) {
  const { ctx } = u;
  const { left, top, width, height } = u.bbox;
  const pr = devicePixelRatio || 1;
  let n = 0;
  ctx.save();
  for (let s = 1; s < u.series.length; s++) {
    if (!u.series[s].show || !ROBUST_SCALES.has(u.series[s].scale)) continue;
    const { min, max } = u.scales[u.series[s].scale];
    const xs = u.data[0], ys = u.data[s];
    ctx.fillStyle = u.series[s]._stroke || u.series[s].stroke || '#111';
    for (let i = 0; i < ys.length; i++) {
      const y = ys[i];
      if (y == null || (y >= min && y <= max)) continue;
      const x = u.valToPos(xs[i], 'x', true);
      if (x < left || x > left + width) continue;
      n++;
      const up = y > max;
      const e = up ? top : top + height;
      const d = (up ? 7 : -7) * pr;
      ctx.beginPath();
      ctx.moveTo(x - 4 * pr, e + d);
      ctx.lineTo(x, e);
      ctx.lineTo(x + 4 * pr, e + d);
      ctx.closePath();
      ctx.fill();
    }
  }
  ctx.restore();
  u._clipped = n;
}

// Round ticks in seconds since the log's start (the data stay on the boot
// clock, as the report's intervals are).
const sinceSplits = (u, ai, min, max) => {
  const t0 = t0Of(state.result);
  return ticks(min - t0, max - t0, Math.max(3, Math.floor(u.bbox.width / (devicePixelRatio || 1) / 90))).map((v) => v + t0);
};
const sinceValues = (u, splits) => {
  const t0 = t0Of(state.result);
  return splits.map((v) => String(Math.round((v - t0) * 1000) / 1000));
};

let hatchPattern = null;
function hatch(ctx) {
  if (hatchPattern) return hatchPattern;
  const c = document.createElement('canvas');
  c.width = c.height = 8;
  const g = c.getContext('2d');
  g.strokeStyle = 'rgba(107,114,128,0.45)';
  g.lineWidth = 1;
  g.beginPath();
  g.moveTo(0, 8);
  g.lineTo(8, 0);
  g.stroke();
  hatchPattern = ctx.createPattern(c, 'repeat');
  return hatchPattern;
}

const tAxis = (last) => ({
  label: last ? "time since the log's start (s)" : 't (s)',
  splits: sinceSplits,
  values: sinceValues,
  labelSize: 18,
  size: 34,
  stroke: '#374151',
  grid: { stroke: '#e5e7eb', width: 1 },
  ticks: { stroke: '#d1d5db', width: 1, size: 4 },
});
const yAxis = (label, scale, side = 3, extra = {}) => ({
  scale,
  side,
  label,
  labelSize: 18,
  size: side === 3 ? AXIS_L : AXIS_R,
  stroke: '#374151',
  grid: { show: side === 3, stroke: '#eef0f3', width: 1 },
  ticks: { stroke: '#d1d5db', width: 1, size: 4 },
  ...extra,
});
const spacerAxis = () => ({ side: 1, scale: '_', size: AXIS_R, show: true, values: () => [], grid: { show: false }, ticks: { show: false }, label: '' });

function baseTimeOpts(title, height, extra) {
  return {
    width: timeWidth(),
    height,
    ...extra,
    cursor: {
      sync: { key: SYNC_KEY, scales: ['x', null], setSeries: false },
      drag: { x: true, y: false, setScale: true },
      y: false,
      focus: { prox: 30 },
      ...(extra.cursor || {}),
    },
    scales: { x: { time: false }, _: { range: [0, 1] }, ...(extra.scales || {}) },
    hooks: {
      setScale: [(u, key) => {
        if (key !== 'x' || state.syncing) return;
        state.syncing = true;
        const { min, max } = u.scales.x;
        for (const o of state.plots) if (o !== u) o.setScale('x', { min, max });
        state.syncing = false;
        updateTrackWindow(min, max);
      }],
      setCursor: [(u) => {
        const left = u.cursor.left;
        moveTrackMarker(left == null || left < 0 ? null : u.posToVal(left, 'x'));
      }],
      ...(extra.hooks || {}),
    },
  };
}

// Pad every time plot's x data with the log's first and last instants, so all
// share one full range (double-click resets to the whole flight everywhere).
function pad(plot, cols) {
  const t = plot.t.slice();
  const out = cols.map((c) => c.slice());
  if (!t.length || t[0] > state.result.plot.tMin) {
    t.unshift(state.result.plot.tMin);
    out.forEach((c) => c.unshift(null));
  }
  if (t[t.length - 1] < state.result.plot.tMax) {
    t.push(state.result.plot.tMax);
    out.forEach((c) => c.push(null));
  }
  return [t, ...out];
}

const stepped = uPlot.paths.stepped({ align: 1 });
const pointsPath = uPlot.paths.points();
// Polyline in data order for the x/y track (uPlot's linear() assumes sorted x
// and merges points that share a pixel column, which distorts a 2-D path).
function trackPath(u, si) {
  const [xs, ys] = u.data[si];
  const p = new Path2D();
  for (let i = 0; i < xs.length; i++) {
    const x = u.valToPos(xs[i], 'x', true);
    const y = u.valToPos(ys[i], 'y', true);
    if (i === 0) p.moveTo(x, y); else p.lineTo(x, y);
  }
  return { stroke: p, fill: null, clip: null, band: null, gaps: null, flags: 0 };
}

function renderPlots(m, keepX) {
  destroyPlots();
  const p = m.plot;
  // ANFIS decides at the configured threshold; every other method's score is
  // its test statistic over its own threshold, so a fault is f >= 1
  const method = methodOf(m);
  const thr = method === 'anfis' ? (m.checkedConfig?.threshold ?? state.config.threshold ?? state.ready?.defaults?.threshold ?? 0.5) : 1;

  // (c) status band
  const bandData = pad({ t: p.runs.map((r) => r[0]) }, [p.runs.map((r) => r[2])]);
  const band = new uPlot({
    ...baseTimeOpts('status', 96, {
      legend: { show: true },
      scales: { k: { range: [0, 3] } },
      hooks: { drawAxes: [shadeHook(true)] },
    }),
    series: [
      { label: 't (s)', value: (u, v) => (v == null ? '—' : fmt(v - t0Of(state.result), 2)) },
      { label: 'status', scale: 'k', stroke: 'transparent', width: 0, paths: () => null, points: { show: false }, value: (u, v) => (v == null ? '—' : KIND_NAME[v]) },
    ],
    axes: [tAxis(), yAxis('status', 'k', 3, { values: () => [], ticks: { show: false }, grid: { show: false } }), spacerAxis()],
  }, bandData, $('#plot-band'));

  // (b1) F-indicator with the threshold
  const fData = pad(p.ind, [p.ind.f]);
  fData.push(fData[0].map(() => thr));
  const fPlot = new uPlot({
    ...baseTimeOpts('F', 190, {
      // clamp: a wild ANFIS extrapolation must not squash the decision region
      scales: { f: { range: (u, lo, hi) => [Math.max(-0.6, Math.min(-0.1, lo ?? 0)), Math.min(1.6, Math.max(1.2, (hi ?? 1) + 0.05))] } },
      hooks: { drawAxes: [shadeHook(false)] },
    }),
    series: [
      { label: 't (s)', value: (u, v) => (v == null ? '—' : fmt(v - t0Of(state.result), 2)) },
      { label: 'F (-)', scale: 'f', stroke: COLORS.f, width: 1.5, paths: stepped, points: { show: false }, value: (u, v) => fmt(v, 3) },
      { label: method === 'anfis' ? `threshold ${thr}` : `fault at 1 (${method})`, scale: 'f', stroke: COLORS.thr, width: 1.25, dash: [6, 4], points: { show: false }, value: (u, v) => fmt(v, 2) },
    ],
    axes: [tAxis(), yAxis('F (-)', 'f'), spacerAxis()],
  }, fData, $('#plot-f'));

  // (b2) R and C indicators
  const rcData = pad(p.ind, [p.ind.r, p.ind.c]);
  const rcPlot = new uPlot({
    ...baseTimeOpts('RC', 190, {
      scales: {
        r: { range: (u, lo, hi) => [0, Math.max(3, (hi ?? 1) * 1.05)] },
        c: { range: (u, lo, hi) => [Math.min(0, lo ?? 0), 1] },
      },
      hooks: { drawAxes: [shadeHook(false)] },
    }),
    series: [
      { label: 't (s)', value: (u, v) => (v == null ? '—' : fmt(v - t0Of(state.result), 2)) },
      { label: 'R (-)', scale: 'r', stroke: COLORS.r, width: 1.25, paths: stepped, points: { show: false }, value: (u, v) => fmt(v, 2) },
      { label: 'C (-)', scale: 'c', stroke: COLORS.c, width: 1.25, paths: stepped, points: { show: false }, value: (u, v) => fmt(v, 3) },
    ],
    axes: [tAxis(), yAxis('R (-)', 'r', 3, { stroke: COLORS.r }), yAxis('C (-)', 'c', 1, { stroke: COLORS.c })],
  }, rcData, $('#plot-rc'));

  // (d) GPS quality
  const hasGq = p.gq.t.length > 0;
  const gData = pad(p.gq, [p.gq.sats, p.gq.fix, p.gq.eph]);
  const gPlot = new uPlot({
    ...baseTimeOpts('GPS', 190, {
      scales: {
        n: { range: (u, lo, hi) => [0, Math.max(4, Math.ceil((hi ?? 0) + 1))] },
        // HDOP 99.99 ("unknown") or one wild eph must not flatten the line
        m: { range: (u, lo, hi) => [0, Math.max(2, robustRange(u.data[3].filter((v) => v != null))[1])] },
      },
      hooks: { drawAxes: [shadeHook(false)], draw: [clipMarks] },
    }),
    series: [
      { label: 't (s)', value: (u, v) => (v == null ? '—' : fmt(v - t0Of(state.result), 2)) },
      { label: 'satellites (-)', scale: 'n', stroke: COLORS.sats, width: 1.5, paths: stepped, points: { show: false }, value: (u, v) => (v == null ? '—' : String(v)) },
      { label: 'fix type (-)', scale: 'n', stroke: COLORS.fix, width: 1.5, paths: stepped, points: { show: false }, value: (u, v) => (v == null ? '—' : String(v)) },
      { label: qualityLabel(m.report), scale: 'm', stroke: COLORS.eph, width: 1.25, paths: stepped, points: { show: false }, value: (u, v) => fmt(v, 2) },
    ],
    axes: [tAxis(true), yAxis('sats, fix (-)', 'n'), yAxis(qualityLabel(m.report), 'm', 1, { stroke: COLORS.eph })],
  }, gData, $('#plot-gps'));
  $('#plot-gps').classList.toggle('nodata', !hasGq);

  // (e) residuals per axis: GPS position N/E/D + baro, GPS velocity N/E/D
  const rPos = residualPlot($('#plot-rpos'), p.resPos, 'residual (m)', 'm', [
    ['N', COLORS.rn], ['E', COLORS.re], ['D', COLORS.rd], ['baro', COLORS.baro],
  ], false);
  const rVel = residualPlot($('#plot-rvel'), p.resVel, 'residual (m/s)', 'm/s', [
    ['N', COLORS.rn], ['E', COLORS.re], ['D', COLORS.rd],
  ], true);

  state.plots = [band, fPlot, rcPlot, gPlot, rPos, rVel];
  renderTrack(p);
  if (keepX) setX(keepX[0], keepX[1]);
}

// Residual series sampled only on measurement rows (see sparseSeries in the
// worker): `undefined` between samples is drawn across, `null` breaks the line.
function residualPlot(host, res, axisLabel, unit, series, last) {
  const data = pad(res, res.ys);
  const u = new uPlot({
    ...baseTimeOpts(axisLabel, 180, {
      scales: {
        y: {
          range: (u, lo, hi) => {
            if (lo == null || hi == null) return [-1, 1];
            // robust to single spikes: percentiles of the visible samples,
            // points beyond are marked at the edge (clipMarks); at least
            // ±0.25 of the unit, so a quiet flight does not show noise as structure
            const xs = u.data[0], { min: x0, max: x1 } = u.scales.x;
            const vis = [];
            for (let s = 1; s < u.data.length; s++) {
              if (u.series[s] && u.series[s].show === false) continue;
              const ys = u.data[s];
              for (let i = 0; i < ys.length; i++) if (ys[i] != null && (x0 == null || (xs[i] >= x0 && xs[i] <= x1))) vis.push(ys[i]);
            }
            const [a0, b0] = vis.length ? robustRange(vis, true) : [lo, hi];
            const a = Math.min(a0, -0.25), b = Math.max(b0, 0.25);
            return [a, b];
          },
        },
      },
      hooks: { drawAxes: [shadeHook(false)], draw: [clipMarks] },
    }),
    series: [
      { label: 't (s)', value: (u, v) => (v == null ? '—' : fmt(v - t0Of(state.result), 2)) },
      ...series.map(([name, color], i) => ({
        label: `${name} (${unit})`,
        scale: 'y',
        stroke: color,
        width: name === 'baro' ? 1 : 1.25,
        spanGaps: false,
        points: { size: 4, width: 1, fill: color },
        value: (u, v) => fmt(v, 2),
        show: res.n[i] > 0,
      })),
    ],
    axes: [tAxis(last), yAxis(axisLabel, 'y'), spacerAxis()],
  }, data, host);
  host.classList.toggle('nodata', !res.n.some((c) => c > 0));
  return u;
}

// (a) GPS track, N up / E right, equal metres per pixel, coloured by status.
function renderTrack(p) {
  const host = $('#plot-track');
  const tr = p.tr;
  const width = Math.max(260, host.clientWidth || 400);
  const height = Math.round(Math.min(width, 480));
  const split = (pred) => {
    const e = [], n = [];
    for (let i = 0; i < tr.t.length; i++) if (pred(i)) { e.push(tr.e[i]); n.push(tr.n[i]); }
    return [e, n];
  };
  const data = [
    null,
    [tr.e, tr.n],
    split((i) => tr.kind[i] === 0 || tr.kind[i] === 3 || tr.kind[i] === 6),
    split((i) => tr.kind[i] === 1),
    split((i) => tr.kind[i] === 2),
    [[], []], // zoom window highlight
  ];
  // equal-aspect ranges
  let eMin = Infinity, eMax = -Infinity, nMin = Infinity, nMax = -Infinity;
  for (let i = 0; i < tr.t.length; i++) {
    eMin = Math.min(eMin, tr.e[i]); eMax = Math.max(eMax, tr.e[i]);
    nMin = Math.min(nMin, tr.n[i]); nMax = Math.max(nMax, tr.n[i]);
  }
  if (!tr.t.length) { eMin = nMin = -10; eMax = nMax = 10; }
  const pw = width - AXIS_L - 16, ph = height - 50 - 10;
  const span = Math.max((eMax - eMin) / pw, (nMax - nMin) / ph, 20 / Math.min(pw, ph)) * 1.08; // m per px
  const ec = (eMin + eMax) / 2, nc = (nMin + nMax) / 2;
  const xr = [ec - span * pw / 2, ec + span * pw / 2];
  const yr = [nc - span * ph / 2, nc + span * ph / 2];
  const pts = (color, size) => ({ label: '', stroke: color, fill: color, width: 0, paths: pointsPath, points: { show: false, size, fill: color, stroke: color, width: 0 } });
  const u = new uPlot({
    mode: 2,
    width,
    height,
    legend: { live: false },
    cursor: { drag: { x: false, y: false, setScale: false }, points: { show: false }, show: true },
    scales: { x: { time: false, range: () => xr }, y: { range: () => yr } },
    series: [
      {},
      { label: 'track', facets: [{ scale: 'x', auto: false }, { scale: 'y', auto: false }], stroke: COLORS.track, width: 1, paths: trackPath, points: { show: false } },
      { ...pts(COLORS.normal, 3), label: 'normal', facets: [{ scale: 'x', auto: false }, { scale: 'y', auto: false }] },
      { ...pts(COLORS.fault, 5), label: 'residual fault', facets: [{ scale: 'x', auto: false }, { scale: 'y', auto: false }] },
      { ...pts(COLORS.outage, 5), label: 'GPS outage', facets: [{ scale: 'x', auto: false }, { scale: 'y', auto: false }] },
      { label: 'zoomed span', facets: [{ scale: 'x', auto: false }, { scale: 'y', auto: false }], stroke: '#111827', width: 2.5, paths: trackPath, points: { show: false } },
    ],
    axes: [
      { scale: 'x', label: 'East (m)', labelSize: 18, size: 36, stroke: '#374151', grid: { stroke: '#eef0f3' }, ticks: { stroke: '#d1d5db', size: 4 } },
      { scale: 'y', label: 'North (m)', labelSize: 18, size: AXIS_L, stroke: '#374151', grid: { stroke: '#eef0f3' }, ticks: { stroke: '#d1d5db', size: 4 } },
    ],
  }, data, host);
  const mark = document.createElement('div');
  mark.className = 'track-marker';
  mark.hidden = true;
  u.over.append(mark);
  u._marker = mark;
  state.track = u;
  host.classList.toggle('nodata', !tr.t.length);
}

function bsearch(arr, x) {
  let lo = 0, hi = arr.length - 1;
  if (hi < 0) return -1;
  while (lo < hi) {
    const mid = (lo + hi + 1) >> 1;
    if (arr[mid] <= x) lo = mid; else hi = mid - 1;
  }
  return lo;
}

function moveTrackMarker(t) {
  const u = state.track;
  if (!u || !state.result) return;
  const tr = state.result.plot.tr;
  const mk = u._marker;
  if (t == null || !tr.t.length) { mk.hidden = true; return; }
  const i = bsearch(tr.t, t);
  if (i < 0) { mk.hidden = true; return; }
  mk.hidden = false;
  mk.style.left = `${u.valToPos(tr.e[i], 'x')}px`;
  mk.style.top = `${u.valToPos(tr.n[i], 'y')}px`;
}

// Highlight the part of the track inside the current time window.
function updateTrackWindow(min, max) {
  const u = state.track;
  if (!u || !state.result) return;
  const { tr, tMin, tMax } = state.result.plot;
  if (min <= tMin && max >= tMax && state.selected >= 0) {
    // zoom reset: the selected interval is no longer what is shown
    state.selected = -1;
    for (const tr of $('#faults tbody').children) tr.classList.remove('selected');
  }
  const e = [], n = [];
  if (min > tMin || max < tMax) {
    for (let i = 0; i < tr.t.length; i++) if (tr.t[i] >= min && tr.t[i] <= max) { e.push(tr.e[i]); n.push(tr.n[i]); }
  }
  const d = u.data.slice();
  d[5] = [e, n];
  u.setData(d, false);
}

// ----------------------------------------------------------------- exports

function baseName() {
  const s = state.result?.source;
  if (!s) return 'navguard';
  return `navguard-${s.name.replace(/\.[^.]+$/, '').replace(/[^\w.-]+/g, '_')}`;
}

function download(blob, name) {
  const a = document.createElement('a');
  a.href = URL.createObjectURL(blob);
  a.download = name;
  document.body.append(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(a.href), 10000);
}

function exportJson() {
  const m = state.result;
  if (!m) return;
  const out = { file: m.source.name, source: m.source, config: state.config, ...m.report };
  download(new Blob([JSON.stringify(out, null, 2) + '\n'], { type: 'application/json' }), `${baseName()}.report.json`);
}

function exportHtml() {
  if (!state.result || !state.workerHasLog) return;
  send({ type: 'html' });
}

function exportCsv() {
  if (!state.result || !state.workerHasLog) return;
  send({ type: 'csv' });
}

// ------------------------------------------------------------------- wiring

function resize() {
  if (!state.result) return;
  const w = timeWidth();
  for (const u of state.plots) u.setSize({ width: w, height: u.height });
  const keep = currentX();
  // the track's equal-aspect ranges depend on its size: rebuild it
  if (state.track) {
    state.track.destroy();
    renderTrack(state.result.plot);
    if (keep) updateTrackWindow(keep[0], keep[1]);
  }
}

// Operator view ("audit") or the research panels (compare, tightly
// coupled, GAN, paper figures) on a second tab.
function showTab(name) {
  state.tab = name;
  for (const b of document.querySelectorAll('.tabs [data-tab]')) b.setAttribute('aria-selected', String(b.dataset.tab === name));
  for (const p of document.querySelectorAll('[data-tab-panel]')) p.hidden = p.dataset.tabPanel !== name;
  // panels laid out while hidden have no width: let them size now
  window.dispatchEvent(new Event('resize'));
}

function init() {
  startWorker();
  send({ type: 'hello' });
  document.body.dataset.state = 'loading';

  $('#file').addEventListener('change', (e) => {
    openFile(e.target.files[0]);
    e.target.value = '';
  });
  $('#sim-form').addEventListener('submit', (e) => {
    e.preventDefault();
    const name = $('#scenario').value;
    const seed = Math.max(0, Math.floor(Number($('#seed').value) || 0));
    $('#seed').value = seed;
    state.source = { kind: 'sim', name };
    runJob('sim', { type: 'sim', name, seed, config: readConfig() });
  });
  $('#cancel').addEventListener('click', () => {
    if (!state.job) return;
    state.worker.terminate();
    startWorker();
    send({ type: 'hello' });
    finishJob();
    $('#config-state').textContent = state.result ? 'cancelled; reload the log to change the configuration' : '';
  });
  $('#config').addEventListener('input', scheduleRerun);
  $('#config').addEventListener('submit', (e) => { e.preventDefault(); scheduleRerun(); });
  $('#config-reset').addEventListener('click', () => {
    if (state.ready) setConfigForm(state.ready.defaults);
    scheduleRerun();
  });
  $('#export-json').addEventListener('click', exportJson);
  $('#export-csv').addEventListener('click', exportCsv);
  $('#export-html').addEventListener('click', exportHtml);
  for (const b of document.querySelectorAll('.tabs [data-tab]')) b.addEventListener('click', () => showTab(b.dataset.tab));
  const tbody = $('#faults tbody');
  tbody.addEventListener('click', (e) => {
    const tr = e.target.closest('tr[data-index]');
    if (tr) selectFault(Number(tr.dataset.index));
  });
  tbody.addEventListener('keydown', (e) => {
    const tr = e.target.closest('tr[data-index]');
    if (!tr) return;
    if (e.key === 'Enter' || e.key === ' ') { e.preventDefault(); selectFault(Number(tr.dataset.index)); }
    if (e.key === 'ArrowDown' && tr.nextElementSibling) { e.preventDefault(); tr.nextElementSibling.focus(); selectFault(Number(tr.nextElementSibling.dataset.index)); }
    if (e.key === 'ArrowUp' && tr.previousElementSibling) { e.preventDefault(); tr.previousElementSibling.focus(); selectFault(Number(tr.previousElementSibling.dataset.index)); }
  });

  // drag and drop anywhere
  const drop = $('#drop');
  let depth = 0;
  const hasFiles = (e) => e.dataTransfer && Array.from(e.dataTransfer.types || []).includes('Files');
  window.addEventListener('dragenter', (e) => { if (!hasFiles(e)) return; e.preventDefault(); depth++; drop.hidden = false; });
  window.addEventListener('dragover', (e) => { if (!hasFiles(e)) return; e.preventDefault(); e.dataTransfer.dropEffect = 'copy'; });
  window.addEventListener('dragleave', (e) => { if (!hasFiles(e)) return; depth = Math.max(0, depth - 1); if (!depth) drop.hidden = true; });
  window.addEventListener('drop', (e) => {
    if (!hasFiles(e)) return;
    e.preventDefault();
    depth = 0;
    drop.hidden = true;
    openFile(e.dataTransfer.files[0]);
  });

  compare = initCompare({
    send,
    hasLog: () => state.workerHasLog,
    logName: () => (state.workerHasLog && state.result ? state.result.source.name : null),
  });
  state.compare = compare.state;
  tight = initTight({ send });
  state.tight = tight.state;

  let rt = 0;
  new ResizeObserver(() => { clearTimeout(rt); rt = setTimeout(resize, 120); }).observe($('.timeplots'));

  // live session (live.js, its own worker): uses the top bar's scenario and seed
  initLive({
    showError,
    hideError,
    readConfig,
    scenario: () => {
      const seed = Math.max(0, Math.floor(Number($('#seed').value) || 0));
      const sel = $('#scenario');
      return { name: sel.disabled ? 'paper' : sel.value, seed };
    },
  });
}

init();
