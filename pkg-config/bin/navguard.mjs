#!/usr/bin/env node
// navguard CLI: audit flight logs, simulate scenarios, reproduce the paper.
//   navguard audit FILE [--json] [--per-sample OUT.csv] [--config CFG.json]
//   navguard simulate NAME [--seed N] [--out FILE.csv]
//   navguard report [--seed N] [--json] [--quick]
//   navguard train LABELLED.csv [...] --out MODEL.json
//   navguard compare [--seeds N] [--methods a,b] [--logs DIR] [--json] [--update-readme FILE]
import { readFileSync, writeFileSync, statSync, readdirSync, openSync, writeSync, closeSync } from 'node:fs';
import { Worker } from 'node:worker_threads';
import { availableParallelism } from 'node:os';
import { createRequire } from 'node:module';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';
import { performance } from 'node:perf_hooks';
import { perSampleHeader, perSampleRows } from '../lib/csv.mjs';
import { streamAudit } from '../lib/stream-audit.mjs';
import { tcSweep, faultKinds, cleanFlights, formatReport } from '../lib/report.mjs';

const require = createRequire(import.meta.url);
const ng = require(join(dirname(fileURLToPath(import.meta.url)), '..', 'index.js'));

const USAGE = `usage:
  navguard audit FILE [--json] [--per-sample OUT.csv] [--config CFG.json]
  navguard audit DIR [--json] [--summary OUT.json] [--config CFG.json] [--jobs N]
  navguard simulate NAME [--seed N] [--out FILE.csv]     (names: ${ng.scenarioNames().join(', ')})
  navguard report [--seed N] [--json] [--quick]
  navguard train LABELLED.csv [...] --out MODEL.json
  navguard compare [--seeds N] [--methods a,b,...] [--logs DIR] [--json] [--update-readme README.md]`;

function fail(msg, code = 2) {
  process.stderr.write(`navguard: ${msg}\n`);
  process.exit(code);
}

function parse(argv) {
  const pos = [], opt = {};
  for (let i = 0; i < argv.length; i++) {
    const a = argv[i];
    if (a.startsWith('--')) {
      const k = a.slice(2);
      if (['json', 'quick', 'help'].includes(k)) opt[k] = true;
      else if (i + 1 < argv.length) opt[k] = argv[++i];
      else fail(`option ${a} needs a value`);
    } else pos.push(a);
  }
  return { pos, opt };
}

const progress = (msg) => { if (process.stderr.isTTY) process.stderr.write(`\r\x1b[K${msg}`); };
const progressDone = () => { if (process.stderr.isTTY) process.stderr.write('\r\x1b[K'); };

function readConfig(path) {
  if (!path) return undefined;
  try { return JSON.parse(readFileSync(path, 'utf8')); } catch (e) { fail(`--config ${path}: ${e.message}`); }
}

/** Any log streamed from disk in 4 MiB chunks (lib/stream-audit.mjs):
 * memory stays bounded whatever the file's size and format; the per-sample
 * file is written as the outputs come. */
function auditStream(file, fd, size, opt, config) {
  let out = null;
  try {
    if (opt['per-sample']) {
      out = openSync(opt['per-sample'], 'w');
      writeSync(out, perSampleHeader());
    }
    const res = streamAudit(ng, fd, config, {
      keepOutputs: out !== null,
      onChunk(run, pos, pass) {
        if (out !== null) writeSync(out, perSampleRows(run.outputs()));
        const of = pass > 1 || run.format() === 'ulog' ? ` (pass ${pass} of 2)` : '';
        progress(`auditing ${file}: ${(100 * pos / Math.max(1, size)).toFixed(0)}% of ${(size / 1e6).toFixed(1)} MB${of}, ${run.rows()} rows`);
      },
    });
    if (out !== null) writeSync(out, perSampleRows(res.columns));
    return res;
  } finally {
    if (out !== null) closeSync(out);
  }
}

function audit(file, opt) {
  let fd, size;
  try { fd = openSync(file, 'r'); size = statSync(file).size; } catch (e) { fail(`${file}: ${e.code === 'ENOENT' ? 'no such file' : e.message}`); }
  const config = readConfig(opt.config);
  progress(`auditing ${file} (${(size / 1e6).toFixed(1)} MB)...`);
  let res;
  try {
    res = auditStream(file, fd, size, opt, config);
  } catch (e) { progressDone(); fail(`${file}: ${e.message}`); } finally { closeSync(fd); }
  progressDone();
  const { report } = res;
  const out = { file, ...report };
  if (opt.json) {
    process.stdout.write(JSON.stringify(out, (k, v) => (typeof v === 'number' && !Number.isFinite(v) ? null : v)) + '\n');
    return;
  }
  const L = [];
  L.push(`${file}: ${report.format}, ${report.rows} rows, ${report.durationS.toFixed(1)} s`);
  L.push(`  GPS: ${report.gpsAvailable ? `${report.gpsEpochs} epochs at ${report.gpsRateHz.toFixed(1)} Hz, fix in ${(100 * report.gpsFixFraction).toFixed(1)}% of reports` : 'unavailable'}; IMU ${report.imuRateHz.toFixed(1)} Hz`);
  if (report.missing.length) L.push(`  missing inputs: ${report.missing.join(', ')}`);
  L.push(`  flagged GPS epochs: ${(100 * report.flaggedGpsEpochFraction).toFixed(2)}%`);
  L.push(`  fault intervals: ${report.faults.length}`);
  for (const f of report.faults.slice(0, 20)) {
    L.push(`    ${f.start.toFixed(2).padStart(9)} - ${f.end.toFixed(2).padStart(9)} s  ${f.kind.padEnd(10)} peak F ${f.peakF.toFixed(2)}  driver ${f.driver} (${f.indicator})`);
  }
  if (report.faults.length > 20) L.push(`    ... ${report.faults.length - 20} more (use --json)`);
  for (const w of report.warnings) L.push(`  warning: ${w}`);
  if (report.metrics) {
    const m = report.metrics;
    L.push(`  vs labels: accuracy ${m.accuracy.toFixed(4)}, false alarm ${m.falseAlarmRate.toFixed(4)}, misdetection ${m.misdetectionRate.toFixed(4)}, precision ${m.precision.toFixed(4)}, recall ${m.recall.toFixed(4)}, F2 ${m.f2.toFixed(4)}, mean delay ${Number.isFinite(m.meanDetectionDelay) ? m.meanDetectionDelay.toFixed(2) + ' s' : '-'} (TP ${m.tp} FN ${m.fn} FP ${m.fp} TN ${m.tn})`);
  }
  console.log(L.join('\n'));
}

/** Audit every file in a folder in parallel (worker_threads), one summary.
 * Symlinks are followed; one that leads nowhere or to a folder is listed as
 * unreadable rather than skipped without a word. */
async function auditDir(dir, opt) {
  const entries = readdirSync(dir, { withFileTypes: true }).filter((d) => d.isFile() || d.isSymbolicLink());
  const files = [], broken = [];
  for (const d of entries.sort((a, b) => a.name.localeCompare(b.name))) {
    const p = join(dir, d.name);
    if (d.isFile()) { files.push(p); continue; }
    let st = null;
    try { st = statSync(p); } catch (e) { broken.push({ file: p, error: `broken symlink (${e.code === 'ENOENT' ? 'target missing' : e.message})` }); continue; }
    if (st.isFile()) files.push(p);
    else broken.push({ file: p, error: `symlink to a ${st.isDirectory() ? 'folder' : 'non-file'}: not audited` });
  }
  if (!files.length && !broken.length) fail(`${dir}: no files`);
  const config = readConfig(opt.config);
  const jobs = Math.max(1, Math.min(Number(opt.jobs ?? availableParallelism()), files.length));
  const results = [...broken];
  let next = 0, done = 0;
  const t0 = performance.now();
  if (files.length) await new Promise((resolve) => {
    const workers = Array.from({ length: jobs }, () => new Worker(new URL('../lib/audit-worker.mjs', import.meta.url)));
    const feed = (w) => {
      if (next < files.length) w.postMessage({ file: files[next++], config });
      else w.terminate();
    };
    for (const w of workers) {
      w.on('message', (r) => {
        results.push(r);
        done++;
        progress(`audited ${done}/${files.length}: ${r.file}`);
        if (done === files.length) resolve();
        feed(w);
      });
      w.on('error', (e) => { results.push({ file: '(worker)', error: e.message }); done++; if (done >= files.length) resolve(); });
      feed(w);
    }
  });
  progressDone();
  results.sort((a, b) => a.file.localeCompare(b.file));
  const rows = results.map((r) => r.error ? { file: r.file, error: r.error } : {
    file: r.file, format: r.report.format, durationS: r.report.durationS, gpsAvailable: r.report.gpsAvailable,
    gpsRateHz: r.report.gpsRateHz, flaggedGpsEpochFraction: r.report.flaggedGpsEpochFraction,
    residualFaults: r.report.faults.filter((f) => f.kind === 'residual').length,
    outages: r.report.faults.filter((f) => f.kind === 'gps_outage').length,
    dataGaps: r.report.dataGaps.length, warnings: r.report.warnings, missing: r.report.missing, ms: r.ms,
  });
  const summary = { dir, files: files.length + broken.length, failed: rows.filter((r) => r.error).length, wallMs: performance.now() - t0, jobs, logs: rows };
  const json = JSON.stringify(summary, (k, v) => (typeof v === 'number' && !Number.isFinite(v) ? null : v), 2);
  if (opt.summary) writeFileSync(opt.summary, json + '\n');
  if (opt.json) { console.log(json); return; }
  console.log(`${dir}: ${summary.files} files, ${summary.failed} unreadable, ${jobs} workers, ${(summary.wallMs / 1000).toFixed(2)} s`);
  console.log('  file                                              format     dur s  GPS Hz  flagged  faults outages gaps');
  for (const r of rows) {
    const name = r.file.length > 48 ? '...' + r.file.slice(-45) : r.file;
    if (r.error) { console.log(`  ${name.padEnd(48)}  unreadable: ${r.error}`); continue; }
    console.log(`  ${name.padEnd(48)}  ${r.format.padEnd(9)} ${r.durationS.toFixed(1).padStart(6)} ${r.gpsAvailable ? r.gpsRateHz.toFixed(1).padStart(6) : '    no'}  ${(100 * r.flaggedGpsEpochFraction).toFixed(2).padStart(6)}%  ${String(r.residualFaults).padStart(5)} ${String(r.outages).padStart(7)} ${String(r.dataGaps).padStart(4)}`);
  }
}

/** Logs under DIR (recursively), sorted, for `compare --logs`. */
function logFiles(dir) {
  const out = [];
  for (const d of readdirSync(dir, { withFileTypes: true })) {
    const p = join(dir, d.name);
    if (d.isDirectory()) out.push(...logFiles(p));
    else if (/\.(csv|ulg|bin|log)$/i.test(d.name)) out.push(p);
  }
  return out.sort();
}

const BEGIN = '<!-- compare:begin (generated by `navguard compare`; do not edit) -->';
const END = '<!-- compare:end -->';

/** Every method over the battery (and real logs): tables to stdout, or into
 * the README between the compare markers. */
function compare(opt) {
  const options = { seeds: Number(opt.seeds ?? 5) };
  if (opt.methods) options.methods = String(opt.methods).split(',');
  let run;
  try { run = new ng.CompareRun(options); } catch (e) { fail(e.message); }
  if (opt.logs) {
    let files;
    try { files = logFiles(opt.logs); } catch (e) { fail(`--logs ${opt.logs}: ${e.message}`); }
    for (const f of files) {
      try { run.addLog(f.slice(opt.logs.length).replace(/^\/+/, ''), readFileSync(f)); } catch (e) { process.stderr.write(`navguard: skipping ${e.message}\n`); }
    }
  }
  const t0 = performance.now();
  let res;
  try {
    for (let done = 0; done < 1; ) {
      done = run.step();
      progress(`comparing methods: ${(100 * done).toFixed(0)}%`);
    }
    res = run.finish();
  } catch (e) { progressDone(); fail(e.message); }
  progressDone();
  process.stderr.write(`compared in ${((performance.now() - t0) / 1000).toFixed(1)} s\n`);
  if (opt.json) { console.log(JSON.stringify(res.comparison, (k, v) => (typeof v === 'number' && !Number.isFinite(v) ? null : v))); return; }
  if (opt['update-readme']) {
    const path = opt['update-readme'];
    let text;
    try { text = readFileSync(path, 'utf8'); } catch (e) { fail(`${path}: ${e.message}`); }
    const a = text.indexOf(BEGIN), b = text.indexOf(END);
    if (a < 0 || b < a) fail(`${path}: no compare markers (${BEGIN} ... ${END})`);
    writeFileSync(path, text.slice(0, a + BEGIN.length) + '\n' + res.markdown + text.slice(b));
    process.stderr.write(`updated ${path}\n`);
    return;
  }
  console.log(res.markdown);
}

function main() {
  const [cmd, ...rest] = process.argv.slice(2);
  const { pos, opt } = parse(rest);
  switch (cmd) {
    case 'audit':
      if (pos.length !== 1) fail(`audit takes one FILE or DIR\n${USAGE}`);
      try { if (statSync(pos[0]).isDirectory()) return auditDir(pos[0], opt); } catch { /* audit() reports it */ }
      return audit(pos[0], opt);
    case 'simulate': {
      if (pos.length !== 1) fail(`simulate takes one scenario NAME\n${USAGE}`);
      let csv;
      try { csv = ng.simulate(pos[0], Number(opt.seed ?? 1)); } catch (e) { fail(e.message); }
      if (opt.out) writeFileSync(opt.out, csv); else process.stdout.write(csv);
      return;
    }
    case 'report': {
      const seed = Number(opt.seed ?? 1);
      const sweep = tcSweep(ng, seed, progress);
      const kinds = opt.quick ? null : faultKinds(ng, [1, 2, 3], progress);
      const clean = opt.quick ? null : cleanFlights(ng, [1, 2, 3], progress);
      progressDone();
      if (opt.json) console.log(JSON.stringify({ sweep, kinds, clean }));
      else console.log(formatReport({ sweep, kinds, clean }));
      return;
    }
    case 'train': {
      if (!pos.length || !opt.out) fail(`train needs labelled CSV files and --out\n${USAGE}`);
      const files = pos.map((p) => { try { return new Uint8Array(readFileSync(p)); } catch (e) { fail(`${p}: ${e.message}`); } });
      let model;
      try { model = ng.trainFromCsv(files, readConfig(opt.config)); } catch (e) { fail(e.message); }
      writeFileSync(opt.out, JSON.stringify(model) + '\n');
      process.stderr.write(`wrote ${opt.out}: ${model.provenance}\n`);
      return;
    }
    case 'compare':
      return compare(opt);
    case undefined: case 'help': case '--help': case '-h':
      console.log(USAGE);
      return;
    default:
      fail(`unknown command "${cmd}"\n${USAGE}`);
  }
}

main();
