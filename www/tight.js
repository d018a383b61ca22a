// "Tightly coupled (Shen et al. 2022)" panel: one simulated flight of the
// tightly coupled GNSS/INS system of docs/tight.md (tightSimulate) through a
// TightDetector, in the audit worker; shows the largest normalised innovation
// |λ| against the threshold T1, RDPOP against η, and a detection summary.
//
// The worker protocol (worker.js):
//   in:  {type:'tight', id, env, faultType, seed, strategy?, ganModel?, ganT2?}
//   out: {type:'tight-result', id, env, faultType, seed, strategy, alpha, eta,
//         ganModel ('trained' | 'embedded' | null), ganT2 (trained model's T2),
//         faultyPrn, faultStart, faultEnd, rows, tEnd, epochs, ms}
//        {type:'error', id, message}
// `epochs`: GNSS epochs only, as arrays t, status, prn, lambda (lambdaMax),
// statistic, rdpop, action, nSats, ganScore (ganScoreMax) (null where not
// defined).
//
// "Train a GAN in the browser": tightGanTrain is one synchronous wasm call, so
// it runs in a worker of its own (worker.js again) that Cancel terminates:
//   in:  {type:'gan-train', id, options}
//   out: {type:'gan-progress', id, epoch, epochs, dLoss, gLoss, dReal, dFake, ms}
//        {type:'gan-result', id, model, tau, m, lambda, t2, falseAlarm,
//         trainWindows, calibWindows, parameters, table1, ms}
//        {type:'error', id, message}
import uPlot from './vendor/uPlot.esm.js';

export const FAULT_TYPES = [
  'no fault',
  'Type 1: step 20 m',
  'Type 2: step 10 m',
  'Type 3: ramp 1 m/s',
  'Type 4: ramp 0.5 m/s',
  'Type 5: ramp 0.3 m/s',
];
export const ENVIRONMENTS = [
  'Env 1: 9 highest satellites',
  'Env 2: 5 highest (urban canyon)',
  'Env 3: 5 satellites, good geometry without the faulty one',
  'Env 4: 5 satellites, poor geometry without the faulty one',
  'Env 5: 6 satellites, the faulty one critical',
];

const SYNC_KEY = 'navguard-tight';
const COL = { lambda: '#1d4ed8', thr: '#b91c1c', flag: '#dc2626', rdpop: '#7c3aed', eta: '#b45309', gan: '#0f766e', t2: '#b91c1c' };

/** Inverse of the standard normal CDF (Acklam's rational approximation,
 *  relative error < 1.2e-9), for T1 = N⁻¹(1 − α/2). */
export function normInv(p) {
  if (!(p > 0 && p < 1)) return NaN;
  const a = [-3.969683028665376e+01, 2.209460984245205e+02, -2.759285104469687e+02, 1.383577518672690e+02, -3.066479806614716e+01, 2.506628277459239e+00];
  const b = [-5.447609879822406e+01, 1.615858368580409e+02, -1.556989798598866e+02, 6.680131188771972e+01, -1.328068155288572e+01];
  const c = [-7.784894002430293e-03, -3.223964580411365e-01, -2.400758277161838e+00, -2.549732539343734e+00, 4.374664141464968e+00, 2.938163982698783e+00];
  const d = [7.784695709041462e-03, 3.224671290700398e-01, 2.445134137142996e+00, 3.754408661907416e+00];
  const lo = 0.02425;
  if (p < lo) {
    const q = Math.sqrt(-2 * Math.log(p));
    return (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) / ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1);
  }
  if (p > 1 - lo) return -normInv(1 - p);
  const q = p - 0.5;
  const r = q * q;
  return (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q / (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1);
}

/** The detection summary of a tight-result message. The fault section is
 *  [faultStart, faultEnd) (the simulator's); with fault type 0 nothing is
 *  injected, so every flagged epoch is a false alarm. */
export function tightSummary(m) {
  const e = m.epochs;
  const injected = m.faultType > 0;
  const inSection = (t) => injected && t >= m.faultStart && t < m.faultEnd;
  let first = -1, before = 0, after = 0, sectionEpochs = 0, sectionFlagged = 0, otherPrn = 0, flagged = 0;
  for (let i = 0; i < e.t.length; i++) {
    const t = e.t[i];
    const f = e.status[i] === 'fault';
    if (f) flagged++;
    if (inSection(t)) {
      sectionEpochs++;
      if (f) {
        sectionFlagged++;
        if (first < 0) first = i;
        if (e.prn[i] !== m.faultyPrn) otherPrn++;
      }
    } else if (f) {
      if (!injected || t < m.faultStart) before++;
      else after++;
    }
  }
  return {
    injected,
    epochs: e.t.length,
    flagged,
    firstT: first >= 0 ? e.t[first] : null,
    delay: first >= 0 ? e.t[first] - m.faultStart : null,
    namedPrn: first >= 0 ? e.prn[first] : null,
    prnOk: first >= 0 ? e.prn[first] === m.faultyPrn : null,
    falseAlarmsBefore: before,
    flagsAfter: after,
    sectionEpochs,
    sectionFlagged,
    sectionShare: sectionEpochs ? sectionFlagged / sectionEpochs : null,
    otherPrn,
  };
}

function esc(s) {
  return String(s).replace(/[&<>"']/g, (c) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;', "'": '&#39;' })[c]);
}
const fx = (x, d) => (x == null || !Number.isFinite(x) ? '—' : x.toFixed(d));

/** HTML of the summary table. */
export function summaryHtml(m, s, t1) {
  const prn = (p) => (p == null ? '—' : `G${p}`);
  const rows = [];
  const row = (key, label, value, cls = '') => rows.push(`<tr data-key="${key}"><th scope="row">${esc(label)}</th><td class="num${cls ? ` ${cls}` : ''}">${value}</td></tr>`);
  row('faulty', 'Injected faulty satellite', m.faultType > 0 ? `${prn(m.faultyPrn)} <span class="muted">(${esc(FAULT_TYPES[m.faultType])}, ${fx(m.faultStart, 0)}–${fx(m.faultEnd, 0)} s)</span>` : '<span class="muted">none injected</span>');
  if (s.injected) {
    row('first', 'First fault epoch in the section', s.firstT == null ? '<span class="bad">not detected</span>' : `${fx(s.firstT, 1)} s`);
    row('delay', 'Delay after fault start', s.delay == null ? '—' : `${fx(s.delay, 1)} s`);
    row('prn', 'Named satellite vs injected', s.namedPrn == null ? '—'
      : `${prn(s.namedPrn)} vs ${prn(m.faultyPrn)} <span class="${s.prnOk ? 'ok' : 'bad'}" data-ok="${s.prnOk}">${s.prnOk ? '✓' : '✗'}</span>`);
    row('before', 'False-alarm epochs before the fault', String(s.falseAlarmsBefore), s.falseAlarmsBefore ? 'warn' : '');
    row('share', 'Fault-section epochs flagged', `${s.sectionFlagged}/${s.sectionEpochs} (${fx(100 * s.sectionShare, 1)} %)`);
    row('other', 'Section flags naming another satellite', String(s.otherPrn), s.otherPrn ? 'warn' : '');
    row('after', 'Flagged epochs after the section', String(s.flagsAfter), s.flagsAfter ? 'warn' : '');
  } else {
    row('before', 'False-alarm epochs (whole flight)', String(s.falseAlarmsBefore), s.falseAlarmsBefore ? 'warn' : '');
  }
  row('setup', 'Strategy · T1 · η', `${esc(m.strategy)} · ${fx(t1, 3)} (α ${m.alpha}) · ${m.eta}`);
  if (m.strategy === 'gan') {
    const sc = m.epochs.ganScore.filter((v) => v != null);
    row('gan', 'GAN model · T2 · largest score', `${m.ganModel === 'trained' ? 'trained here' : 'embedded default'} · ${fx(m.ganT2, 3)} · ${sc.length ? fx(Math.max(...sc), 3) : '—'}`);
  }
  row('epochs', 'GNSS epochs · rows', `${s.epochs} · ${m.rows}`);
  return `<table id="tight-table" class="tight-table"><tbody>${rows.join('')}</tbody></table>`;
}

/** HTML table of a Markdown pipe table (the chaos Table 1 of tightGanTrain). */
export function markdownTableHtml(md, id) {
  const lines = String(md).trim().split('\n').map((l) => l.trim()).filter((l) => l.startsWith('|'));
  const cells = (l) => l.replace(/^\|/, '').replace(/\|$/, '').split('|').map((c) => c.trim());
  if (lines.length < 2) return `<pre>${esc(md)}</pre>`;
  const head = cells(lines[0]);
  const align = cells(lines[1]).map((c) => c.endsWith(':'));
  const body = lines.slice(2).map((l) => `<tr>${cells(l).map((c, i) => `<td${align[i] ? ' class="num"' : ''}>${esc(c)}</td>`).join('')}</tr>`);
  return `<table id="${id}" class="tight-table"><caption>Table 1: chaos analysis of the training flights</caption><thead><tr>${head.map((h, i) => `<th scope="col"${align[i] ? ' class="num"' : ''}>${esc(h)}</th>`).join('')}</tr></thead><tbody>${body.join('')}</tbody></table>`;
}

/** HTML of a gan-result message: the model's numbers and Table 1. */
export function ganResultHtml(r) {
  const rows = [];
  const row = (key, label, value) => rows.push(`<tr data-key="${key}"><th scope="row">${esc(label)}</th><td class="num">${value}</td></tr>`);
  row('tau', 'Delay τ (median over satellites)', String(r.tau));
  row('m', 'Embedding dimension m', String(r.m));
  row('lambda', 'λ (generation vs discrimination weight)', fx(r.lambda, 4));
  row('t2', 'Threshold T2', fx(r.t2, 4));
  row('fa', 'Calibration false-alarm rate', `${fx(100 * r.falseAlarm, 3)} %`);
  row('params', 'Parameters (G + D)', String(r.parameters));
  row('windows', 'Training · calibration windows', `${r.trainWindows} · ${r.calibWindows}`);
  row('bytes', 'Model size', `${r.model.length} bytes`);
  row('time', 'Training time', `${fx(r.ms / 1000, 1)} s`);
  return `<table id="tight-gan-table" class="tight-table"><caption>Trained model</caption><tbody>${rows.join('')}</tbody></table>${markdownTableHtml(r.table1, 'tight-gan-table1')}`;
}

/** Wire the panel. `io`: {send(msg) → id}. Returns {onMessage(m) → handled?,
 *  workerRestarted(), state}. */
export function initTight(io) {
  const $ = (s) => document.querySelector(s);
  const T = {
    job: 0,
    running: false,
    result: null,   // last tight-result message
    summary: null,  // tightSummary(result)
    t1: null,
    status: '',
    plots: [],
    gan: {
      running: false,
      worker: null,   // the training worker while it runs
      job: 0,
      progress: [],   // gan-progress messages of the last training
      result: null,   // last gan-result (with its model bytes)
      status: '',
    },
  };
  const form = $('#tight-form');
  const runBtn = $('#tight-run');
  const detail = $('#tight-detail');
  const envSel = $('#tight-env');
  const typeSel = $('#tight-type');
  ENVIRONMENTS.forEach((label, i) => envSel.add(new Option(label, String(i + 1), i === 0, i === 0)));
  FAULT_TYPES.forEach((label, i) => typeSel.add(new Option(`${i}: ${label.replace(/^Type \d: /, '')}`, String(i), i === 1, i === 1)));

  function setStatus(s) {
    T.status = s;
    detail.textContent = s;
  }
  function setRunning(on) {
    T.running = on;
    runBtn.disabled = on;
    $('#tight-panel').dataset.state = on ? 'running' : T.result ? 'done' : 'idle';
  }

  function start() {
    if (T.running) return;
    const seedEl = $('#tight-seed');
    const seed = Math.max(0, Math.floor(Number(seedEl.value) || 0));
    seedEl.value = seed;
    const env = Number(envSel.value);
    const faultType = Number(typeSel.value);
    const strategy = $('#tight-strategy').value || undefined;
    const msg = { type: 'tight', env, faultType, seed, strategy };
    const g = T.gan.result;
    if (strategy === 'gan' && g && $('#tight-use-trained').checked) {
      msg.ganModel = g.model; // copied, so later runs can use it again
      msg.ganT2 = g.t2;
    }
    setStatus(`simulating Env ${env}, ${FAULT_TYPES[faultType]}, seed ${seed}${msg.ganModel ? ' (trained GAN model)' : ''}…`);
    T.job = io.send(msg);
    setRunning(true);
  }

  function onMessage(m) {
    if (!T.job || m.id !== T.job) return false;
    if (m.type === 'tight-result') {
      T.job = 0;
      T.result = m;
      T.t1 = normInv(1 - (m.alpha ?? 0.001) / 2);
      T.summary = tightSummary(m);
      $('#tight-out').innerHTML = summaryHtml(m, T.summary, T.t1);
      $('#tight-plots').hidden = false;
      render();
      setStatus(`done in ${(m.ms / 1000).toFixed(2)} s · ${m.epochs.t.length} GNSS epochs`);
      setRunning(false);
    } else if (m.type === 'error') {
      T.job = 0;
      setStatus(`failed: ${m.message}`);
      setRunning(false);
    }
    return true;
  }

  function workerRestarted() {
    if (!T.job) return;
    T.job = 0;
    setStatus('interrupted (the worker was restarted); run again');
    setRunning(false);
  }

  // fault section shaded, drawn under the series
  const shade = (u) => {
    const m = T.result;
    if (!m || m.faultType === 0) return;
    const { ctx } = u;
    const { left, top, width, height } = u.bbox;
    const x0 = Math.max(left, u.valToPos(m.faultStart, 'x', true));
    const x1 = Math.min(left + width, u.valToPos(m.faultEnd, 'x', true));
    if (x1 <= x0) return;
    ctx.save();
    ctx.fillStyle = 'rgba(220,38,38,0.12)';
    ctx.fillRect(x0, top, x1 - x0, height);
    ctx.restore();
  };

  const width = () => Math.max(320, $('#tight-plots').clientWidth || 800);

  function render() {
    for (const u of T.plots) u.destroy();
    T.plots = [];
    const m = T.result;
    const e = m.epochs;
    const t1 = T.t1;
    const flagged = e.lambda.map((v, i) => (e.status[i] === 'fault' ? v : null));
    const axis = (label, scale, side = 3) => ({
      scale, side, label, labelSize: 18, size: 60, stroke: '#374151',
      grid: { show: side === 3, stroke: '#eef0f3', width: 1 }, ticks: { stroke: '#d1d5db', width: 1, size: 4 },
    });
    const xAxis = { label: 'time (s)', labelSize: 18, size: 34, stroke: '#374151', grid: { stroke: '#e5e7eb', width: 1 }, ticks: { stroke: '#d1d5db', width: 1, size: 4 } };
    const common = (height) => ({
      width: width(),
      height,
      cursor: { sync: { key: SYNC_KEY, scales: ['x', null], setSeries: false }, drag: { x: true, y: false, setScale: true }, y: false },
      hooks: {
        drawClear: [shade],
        setScale: [(u, key) => {
          if (key !== 'x' || T.syncing) return;
          T.syncing = true;
          const { min, max } = u.scales.x;
          for (const o of T.plots) if (o !== u) o.setScale('x', { min, max });
          T.syncing = false;
        }],
      },
    });
    const tLabel = { label: 't (s)', value: (u, v) => fx(v, 0) };
    const lam = new uPlot({
      ...common(220),
      scales: { x: { time: false }, y: { range: (u, lo, hi) => [0, Math.max(t1 * 1.6, (hi ?? 0) * 1.08)] } },
      series: [
        tLabel,
        { label: 'max |λ| (-)', stroke: COL.lambda, width: 1.25, points: { show: false }, value: (u, v) => fx(v, 2) },
        { label: `T1 = ${fx(t1, 3)}`, stroke: COL.thr, width: 1.25, dash: [6, 4], points: { show: false }, value: (u, v) => fx(v, 3) },
        { label: 'flagged epoch', stroke: COL.flag, width: 0, paths: () => null, points: { show: true, size: 5, fill: COL.flag, stroke: COL.flag, width: 1 }, value: (u, v) => (v == null ? '—' : fx(v, 2)) },
      ],
      axes: [xAxis, axis('|λ| (-)', 'y')],
    }, [e.t, e.lambda, e.t.map(() => t1), flagged], $('#tight-plot-lambda'));
    const hasRdpop = e.rdpop.some((v) => v != null);
    const rd = new uPlot({
      ...common(170),
      scales: { x: { time: false }, y: { range: (u, lo, hi) => [0, Math.max(m.eta * 2, (hi ?? 0) * 1.1)] } },
      series: [
        tLabel,
        { label: 'RDPOP of the flagged satellite (-)', stroke: COL.rdpop, width: 1, spanGaps: false, points: { show: true, size: 4, fill: COL.rdpop }, value: (u, v) => fx(v, 4) },
        { label: `η = ${m.eta}`, stroke: COL.eta, width: 1.25, dash: [6, 4], points: { show: false }, value: (u, v) => fx(v, 3) },
      ],
      axes: [xAxis, axis('RDPOP (-)', 'y')],
    }, [e.t, e.rdpop, e.t.map(() => m.eta)], $('#tight-plot-rdpop'));
    $('#tight-plot-rdpop').classList.toggle('tight-nodata', !hasRdpop);
    T.plots = [lam, rd];
    // GAN-FDSR: the largest GAN score per epoch, with T2 when it is known
    // (a model trained here; the embedded model's T2 is not exported).
    const isGan = m.strategy === 'gan';
    $('#tight-fig-gan').hidden = !isGan;
    if (isGan) {
      const t2 = m.ganT2;
      const gFlag = e.ganScore.map((v, i) => (e.status[i] === 'fault' ? v : null));
      const series = [
        tLabel,
        { label: 'max GAN score (-)', stroke: COL.gan, width: 1.25, points: { show: false }, value: (u, v) => fx(v, 3) },
      ];
      const data = [e.t, e.ganScore];
      if (t2 != null) {
        series.push({ label: `T2 = ${fx(t2, 3)}`, stroke: COL.t2, width: 1.25, dash: [6, 4], points: { show: false }, value: (u, v) => fx(v, 3) });
        data.push(e.t.map(() => t2));
      }
      series.push({ label: 'flagged epoch', stroke: COL.flag, width: 0, paths: () => null, points: { show: true, size: 5, fill: COL.flag, stroke: COL.flag, width: 1 }, value: (u, v) => (v == null ? '—' : fx(v, 3)) });
      data.push(gFlag);
      const gp = new uPlot({
        ...common(170),
        scales: { x: { time: false }, y: { range: (u, lo, hi) => [0, Math.max((t2 ?? 0) * 1.3, (hi ?? 1) * 1.08)] } },
        series,
        axes: [xAxis, axis('GAN score (-)', 'y')],
      }, data, $('#tight-plot-gan'));
      T.plots.splice(1, 0, gp);
    }
  }

  let rt = 0;
  new ResizeObserver(() => {
    clearTimeout(rt);
    rt = setTimeout(() => { for (const u of T.plots) u.setSize({ width: width(), height: u.height }); }, 120);
  }).observe($('#tight-panel'));

  form.addEventListener('submit', (e) => { e.preventDefault(); start(); });
  setRunning(false);

  // ---- Train a GAN in the browser
  const G = T.gan;
  const ganBtn = $('#tight-gan-train');
  const ganCancel = $('#tight-gan-cancel');
  const ganBar = $('#tight-gan-bar');
  const ganDetail = $('#tight-gan-detail');
  const useTrained = $('#tight-use-trained');
  function ganStatus(s, cls = '') {
    G.status = s;
    ganDetail.textContent = s;
    ganDetail.className = `detail${cls ? ` ${cls}` : ''}`;
  }
  function ganRunning(on) {
    G.running = on;
    ganBtn.disabled = on;
    ganCancel.hidden = !on;
    ganBar.hidden = !on;
    $('#tight-gan').dataset.state = on ? 'running' : G.result ? 'done' : 'idle';
  }
  function ganStop() {
    if (G.worker) G.worker.terminate();
    G.worker = null;
    G.job = 0;
  }
  function ganTrain() {
    if (G.running) return;
    const int = (sel, lo, hi, dflt) => {
      const el = $(sel);
      const v = Math.min(hi, Math.max(lo, Math.floor(Number(el.value) || dflt)));
      el.value = v;
      return v;
    };
    const epochs = int('#tight-gan-epochs', 1, 50, 2);
    const flights = int('#tight-gan-flights', 1, 10, 2);
    const options = { epochs, trainSeeds: Array.from({ length: flights }, (_, i) => 101 + i) };
    G.progress = [];
    ganBar.max = epochs + 1; // the last step: calibration of T2
    ganBar.value = 0;
    ganStatus(`simulating ${flights} training + 2 calibration flights, chaos analysis…`);
    const w = new Worker(new URL('./worker.js', import.meta.url), { type: 'module' });
    G.worker = w;
    G.job += 1;
    const id = `gan-${G.job}`;
    w.onmessage = (ev) => {
      const m = ev.data;
      if (G.worker !== w || m.id !== id) return;
      if (m.type === 'gan-progress') {
        G.progress.push(m);
        ganBar.value = m.epoch;
        ganStatus(`epoch ${m.epoch}/${m.epochs} · D loss ${fx(m.dLoss, 3)} · G loss ${fx(m.gLoss, 3)} · D(real) ${fx(m.dReal, 2)} · D(fake) ${fx(m.dFake, 2)}${m.epoch === m.epochs ? ' · calibrating T2…' : ''}`);
      } else if (m.type === 'gan-result') {
        ganStop();
        G.result = m;
        ganBar.value = ganBar.max;
        $('#tight-gan-out').innerHTML = ganResultHtml(m);
        useTrained.disabled = false;
        useTrained.checked = true;
        $('#tight-strategy').value = 'gan';
        ganStatus(`trained in ${fx(m.ms / 1000, 1)} s · ${epochs} epoch${epochs === 1 ? '' : 's'} · the next run uses this model (GAN-FDSR)`);
        ganRunning(false);
      } else if (m.type === 'error') {
        ganStop();
        ganStatus(`training failed: ${m.message}`, 'bad');
        ganRunning(false);
      }
    };
    w.onerror = (ev) => {
      if (G.worker !== w) return;
      ev.preventDefault();
      ganStop();
      ganStatus(`training failed: ${ev.message || 'the training worker could not start'}`, 'bad');
      ganRunning(false);
    };
    w.postMessage({ type: 'gan-train', id, options });
    ganRunning(true);
  }
  $('#tight-gan-form').addEventListener('submit', (e) => { e.preventDefault(); ganTrain(); });
  // tightGanTrain is one synchronous call: the worker cannot read a cancel
  // message until it returns, so Cancel ends the training worker.
  ganCancel.addEventListener('click', () => {
    if (!G.running) return;
    ganStop();
    ganStatus(`cancelled after ${G.progress.length} epoch${G.progress.length === 1 ? '' : 's'}`);
    ganRunning(false);
  });
  ganRunning(false);
  return { onMessage, workerRestarted, state: T };
}
