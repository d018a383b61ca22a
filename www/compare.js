// "Compare methods" panel: runs the wasm CompareRun (every detection method
// over a seeded battery of simulated flights, plus optionally the opened log)
// in the audit worker, in slices with a progress bar, and shows the same
// tables as `navguard compare` (numbers formatted like the CLI).
//
// The worker protocol (worker.js):
//   in:  {type:'compare', id, seeds, methods, includeLog}
//        {type:'compare-cancel', target: id}
//   out: {type:'compare-progress', id, frac, steps}
//        {type:'compare-result', id, comparison, markdown, ms, logName}
//        {type:'compare-cancelled', id}
//        {type:'error', id, message}

export const METHODS = ['anfis', 'chi2', 'nis', 'gate', 'mahalanobis', 'rms', 'knee', 'adaptive'];

/** `x` with `d` decimals exactly as the CLI (Rust `{:.d$}`) prints it: ties
 *  round half to even (JS toFixed rounds them up); "–" for NaN / ±∞. */
export function fixed(x, d) {
  if (typeof x !== 'number' || !Number.isFinite(x)) return '–';
  const s = x.toFixed(d);
  if (Math.abs(x) >= 1e20) return s;
  // an exact tie has a finite decimal expansion ending in 5 at digit d + 1
  const long = x.toFixed(d + 25);
  const tail = long.slice(long.length - 25);
  if (tail !== '5' + '0'.repeat(24)) return s;
  let trunc = long.slice(0, long.length - 25);
  if (trunc.endsWith('.')) trunc = trunc.slice(0, -1);
  const lastDigit = Number(trunc[trunc.length - 1]);
  return lastDigit % 2 === 0 ? trunc : s;
}

function esc(s) {
  return String(s).replace(/[&<>"']/g, (c) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;', "'": '&#39;' })[c]);
}

/** Best F2 over the methods (NaN ignored); -Infinity when none is finite. */
function bestF2(methods) {
  return methods.reduce((b, m) => (Number.isFinite(m.metrics.f2) ? Math.max(b, m.metrics.f2) : b), -Infinity);
}

/** HTML of the three tables for a `comparison`. */
export function comparisonHtml(c) {
  const ms = c.methods;
  const best = bestF2(ms);
  let h = `<p class="compare-caption muted">${c.flights} simulated flights (${c.seeds.length} seed${c.seeds.length === 1 ? '' : 's'}: ${esc(c.seeds.join(', '))}); fault-flight rates pooled over labelled GPS epochs; false alarms per hour on the clean flights. Best F2 highlighted.</p>`;
  h += '<div class="table-wrap compare-wrap"><table id="compare-methods"><thead><tr><th>Method</th>' +
    '<th class="num">Accuracy</th><th class="num">False alarm</th><th class="num">Misdetection</th><th class="num">F2</th>' +
    '<th class="num">False alarms / h (clean)</th><th class="num">Clean epochs flagged</th></tr></thead><tbody>';
  for (const m of ms) {
    const isBest = Number.isFinite(m.metrics.f2) && m.metrics.f2 === best;
    h += `<tr data-method="${esc(m.method)}"${isBest ? ' class="best"' : ''}>` +
      `<td class="method">${esc(m.method)}${isBest ? ' <span class="best-tag">best F2</span>' : ''}</td>` +
      `<td class="num" data-col="accuracy">${fixed(m.metrics.accuracy, 4)}</td>` +
      `<td class="num" data-col="falseAlarm">${fixed(m.metrics.falseAlarmRate, 4)}</td>` +
      `<td class="num" data-col="misdetection">${fixed(m.metrics.misdetectionRate, 4)}</td>` +
      `<td class="num f2" data-col="f2">${fixed(m.metrics.f2, 4)}</td>` +
      `<td class="num" data-col="faPerHour">${fixed(m.falseAlarmsPerHour, 1)}</td>` +
      `<td class="num" data-col="cleanFlagged">${fixed(100 * m.cleanFlaggedFraction, 2)}%</td></tr>`;
  }
  h += '</tbody></table></div>';

  const head = ms.map((m) => `<th class="num">${esc(m.method)}</th>`).join('');
  const first = ms[0];
  if (first && first.kinds.length) {
    h += '<h3>Faults caught (of injected) · median detection delay, s, per fault kind</h3>';
    h += `<div class="table-wrap compare-wrap"><table id="compare-kinds"><thead><tr><th>Kind</th>${head}</tr></thead><tbody>`;
    first.kinds.forEach((k, i) => {
      h += `<tr data-kind="${esc(k.group)}"><td>${esc(k.group)}</td>`;
      for (const m of ms) {
        const r = m.kinds[i];
        h += r ? `<td class="num">${r.detected}/${r.faults} · ${fixed(r.medianDelayS, 1)}</td>` : '<td class="num">–</td>';
      }
      h += '</tr>';
    });
    h += '</tbody></table></div>';
  }
  if (first && first.logs.length) {
    h += '<h3>Real logs (no labels): share of GPS epochs flagged</h3>';
    h += `<div class="table-wrap compare-wrap"><table id="compare-logs"><thead><tr><th>Log</th>${head}</tr></thead><tbody>`;
    first.logs.forEach((l, i) => {
      h += `<tr><td>${esc(l.name)} <span class="muted">(${l.gpsEpochs.toLocaleString('en-US')} epochs)</span></td>`;
      for (const m of ms) {
        const r = m.logs[i];
        h += r ? `<td class="num">${fixed(100 * r.flaggedFraction, 2)}%</td>` : '<td class="num">–</td>';
      }
      h += '</tr>';
    });
    h += '</tbody></table></div>';
  }
  return h;
}

/** Wire the panel. `io`: {send(msg) → id, hasLog() → bool, logName() → string|null}.
 *  Returns {onMessage(m) → handled?, workerRestarted(), refresh(), state}. */
export function initCompare(io) {
  const $ = (s) => document.querySelector(s);
  const C = {
    job: 0,
    running: false,
    progressLog: [],   // {frac, steps} per progress message (for the test)
    result: null,      // last compare-result message
    markdown: '',
    status: '',
  };

  const form = $('#compare-form');
  const runBtn = $('#compare-run');
  const cancelBtn = $('#compare-cancel');
  const bar = $('#compare-bar');
  const detail = $('#compare-detail');
  const out = $('#compare-out');
  const copyBtn = $('#compare-copy');
  const mdPre = $('#compare-md');
  const incl = $('#compare-log');

  // method checkboxes
  const box = $('#compare-method-list');
  for (const m of METHODS) {
    const l = document.createElement('label');
    l.className = 'chk';
    l.innerHTML = `<input type="checkbox" name="cmp-method" value="${m}" checked> ${m}`;
    box.append(l);
  }
  const chosen = () => Array.from(form.querySelectorAll('input[name=cmp-method]:checked')).map((i) => i.value);

  function setStatus(s) {
    C.status = s;
    detail.textContent = s;
  }

  function setRunning(on) {
    C.running = on;
    runBtn.disabled = on || chosen().length === 0;
    cancelBtn.hidden = !on;
    $('#compare-panel').dataset.state = on ? 'running' : C.result ? 'done' : 'idle';
  }

  function refresh() {
    const has = io.hasLog();
    incl.disabled = !has;
    if (!has) incl.checked = false;
    const name = io.logName();
    $('#compare-log-name').textContent = has && name ? `(${name})` : '(no log opened)';
    if (!C.running) runBtn.disabled = chosen().length === 0;
  }

  function start() {
    if (C.running) return;
    const seedsEl = $('#compare-seeds');
    const seeds = Math.max(1, Math.min(10, Math.floor(Number(seedsEl.value) || 3)));
    seedsEl.value = seeds;
    const methods = chosen();
    if (!methods.length) return;
    C.progressLog = [];
    bar.value = 0;
    bar.hidden = false;
    setStatus(`starting: ${methods.length} method${methods.length === 1 ? '' : 's'} × ${seeds} seed${seeds === 1 ? '' : 's'}`);
    C.job = io.send({
      type: 'compare',
      seeds,
      methods: methods.length === METHODS.length ? undefined : methods,
      includeLog: incl.checked && !incl.disabled,
    });
    setRunning(true);
  }

  function onMessage(m) {
    if (!C.job || m.id !== C.job) return false;
    if (m.type === 'compare-progress') {
      if (C.progressLog.length < 5000) C.progressLog.push({ frac: m.frac, steps: m.steps });
      bar.value = m.frac;
      setStatus(`${Math.floor(100 * m.frac)} % · ${m.steps} flight × method runs`);
    } else if (m.type === 'compare-result') {
      C.job = 0;
      C.result = m;
      C.markdown = m.markdown;
      bar.value = 1;
      out.innerHTML = comparisonHtml(m.comparison);
      mdPre.textContent = m.markdown;
      $('#compare-md-wrap').hidden = false;
      copyBtn.disabled = false;
      setStatus(`100 % · done in ${(m.ms / 1000).toFixed(1)} s`);
      setRunning(false);
    } else if (m.type === 'compare-cancelled') {
      C.job = 0;
      setStatus('cancelled');
      setRunning(false);
    } else if (m.type === 'error') {
      C.job = 0;
      setStatus(`failed: ${m.message}`);
      setRunning(false);
    }
    return true;
  }

  function workerRestarted() {
    if (!C.job) return;
    C.job = 0;
    setStatus('interrupted (the worker was restarted); run again');
    setRunning(false);
  }

  async function copy() {
    if (!C.markdown) return;
    let ok = false;
    try {
      await navigator.clipboard.writeText(C.markdown);
      ok = true;
    } catch {
      const ta = document.createElement('textarea');
      ta.value = C.markdown;
      ta.setAttribute('readonly', '');
      ta.style.position = 'fixed';
      ta.style.opacity = '0';
      document.body.append(ta);
      ta.select();
      try { ok = document.execCommand('copy'); } catch { ok = false; }
      ta.remove();
    }
    $('#compare-copy-state').textContent = ok ? 'copied' : 'copy failed: select the Markdown below';
    if (!ok) $('#compare-md-wrap').open = true;
  }

  form.addEventListener('submit', (e) => { e.preventDefault(); start(); });
  form.addEventListener('change', (e) => { if (e.target.name === 'cmp-method' && !C.running) runBtn.disabled = chosen().length === 0; });
  cancelBtn.addEventListener('click', () => {
    if (!C.job) return;
    io.send({ type: 'compare-cancel', target: C.job });
    setStatus('cancelling…');
  });
  copyBtn.addEventListener('click', copy);
  refresh();
  setRunning(false);
  return { onMessage, workerRestarted, refresh, state: C };
}
