// A browser app as a user writes it: `import … from 'navguard'`, bundled
// with no configuration (esbuild, Vite) and run in headless Chromium by
// tests/package/package.test.mjs. It reads /log (a real flight log served
// by the test), runs both push paths (recording the wasm bytes compiled for
// `new Detector()` plus `readLog`: the core module alone), an audit (the
// audit module, after `await loadAudit()`), the guards, then the lab.
import init, { Detector, readLog, auditBytes, columnNames, loadAudit, loadLab, loadedModules } from 'navguard';
import * as ng from 'navguard';

async function run() {
  const out = {};
  try {
    new Detector();
    out.beforeInit = 'no error';
  } catch (e) {
    out.beforeInit = e.message;
  }
  await init();
  const bytes = new Uint8Array(await (await fetch('/log')).arrayBuffer());
  const log = readLog(bytes);
  out.format = log.format;
  out.rows = log.rows;
  const cols = { ...log.columns };
  const res = new Detector().pushColumns(cols);
  // The fast `push` gives the same statuses as `pushColumns` (contract §2).
  const d2 = new Detector();
  const names = columnNames();
  const n = Math.min(3000, log.rows);
  let same = 0;
  let flagged = 0;
  for (let i = 0; i < n; i++) {
    const s = {};
    for (const k of names) if (cols[k] && !Number.isNaN(cols[k][i])) s[k] = cols[k][i];
    const o = d2.push(s);
    if (o.status === res.status[i]) same++;
    flagged += o.status;
  }
  out.pushSame = same;
  out.pushN = n;
  out.flagged = flagged;
  out.firstUse = loadedModules();
  out.wasmBytesFirstUse = globalThis.__wasmBytes;
  try {
    auditBytes(bytes);
  } catch (e) {
    out.auditBeforeLoad = e.message;
  }
  await loadAudit();
  const a = auditBytes(bytes);
  out.auditRows = a.report.rows;
  out.statsKeys = Object.keys(a.report.stats).sort();
  // The guards hold in the browser build too.
  d2.free();
  try {
    d2.push({ t: 1 });
  } catch (e) {
    out.freed = e.message;
  }
  const d3 = new Detector();
  try {
    d3.push({ get t() { d3.push({ t: 0 }); return 1; } });
  } catch (e) {
    out.reentry = e.message;
  }
  out.rowsAfterReentry = d3.rowCount();
  out.exports = Object.keys(ng).sort();
  out.beforeLab = loadedModules();
  try {
    ng.simulate('paper', 1);
  } catch (e) {
    out.labBeforeLoad = e.message;
  }
  out.wasmBytesCore = globalThis.__wasmBytes;
  await loadLab();
  out.simLines = ng.simulate('paper', 1).split('\n').length;
  out.afterLab = loadedModules();
  out.wasmBytesAll = globalThis.__wasmBytes;
  return out;
}

run().then(
  (r) => { globalThis.__result = r; },
  (e) => { globalThis.__result = { error: String((e && e.stack) || e) }; },
);
