#!/usr/bin/env node
// navguard CLI: audit flight logs, simulate scenarios, reproduce the paper.
//   navguard audit FILE|DIR [--json] [--per-sample OUT.csv] [--html OUT.html] [--config CFG.json]
//   navguard report FILE --html OUT.html [--config CFG.json]
//   navguard simulate NAME [--seed N] [--out FILE.csv]
//   navguard report [--seed N] [--json] [--quick]
//   navguard train LABELLED.csv [...] --out MODEL.json
//   navguard compare [--seeds N | --battery tune|eval [--flights N]] [--methods a,b] [--logs DIR] [--json] [--update-readme FILE]
import { readFileSync, statSync, closeSync } from 'node:fs';
import { Worker } from 'node:worker_threads';
import { availableParallelism } from 'node:os';
import { createRequire } from 'node:module';
import { dirname, join, relative } from 'node:path';
import { fileURLToPath } from 'node:url';
import { performance } from 'node:perf_hooks';
import { perSampleHeader, perSampleRows } from '../lib/csv.mjs';
import { streamAudit } from '../lib/stream-audit.mjs';
import { tcSweep, faultKinds, cleanFlights, formatReport } from '../lib/report.mjs';
import { CliError, AtomicOutput, ScratchFile, openInput, readSmall, walkLogs, writeAtomic } from '../lib/files.mjs';
import { parseArgs, suggest } from '../lib/args.mjs';
import { verdictOf, faultList, reconciledIfDifferent, reconciledAt, intervalLine, flightSeries, renderReport, qualityLabel, fmtUtc, fmtSince, checkedWithoutGps } from '../lib/html-report.mjs';

const require = createRequire(import.meta.url);
const ng = require(join(dirname(fileURLToPath(import.meta.url)), '..', 'node.cjs'));

const USAGE = `usage:
  navguard audit FILE [--json] [--per-sample OUT.csv] [--html OUT.html] [--config CFG.json] [--fail-on-fault]
  navguard audit DIR [--json] [--summary OUT.json] [--html OUT.html] [--config CFG.json] [--jobs N] [--fail-on-fault]
  navguard report FILE --html OUT.html [--config CFG.json]
  navguard simulate NAME [--seed N] [--out FILE.csv]     (names: ${ng.scenarioNames().join(', ')})
  navguard report [--seed N] [--json] [--quick]
  navguard train LABELLED.csv [...] --out MODEL.json
  navguard compare [--seeds N | --battery tune|eval [--flights N]] [--methods a,b,...] [--logs DIR] [--json] [--update-readme README.md]`;

function fail(msg, code = 2) {
  process.stderr.write(`navguard: ${msg}\n`);
  process.exit(code);
}

const progress = (msg) => { if (process.stderr.isTTY) process.stderr.write(`\r\x1b[K${msg}`); };
const progressDone = () => { if (process.stderr.isTTY) process.stderr.write('\r\x1b[K'); };

/** A config or model file is small: more than this is not one (and a device
 * such as /dev/zero is refused as not a regular file). */
const CONFIG_LIMIT = 16 << 20;

function readConfig(path) {
  if (!path) return undefined;
  const text = readSmall(path, CONFIG_LIMIT, '--config');
  try { return JSON.parse(text); } catch (e) { throw new CliError(`--config ${path}: ${e.message}`); }
}

/** JSON with non-finite numbers as null; a report too large for one string
 * is an error with exit 2, not a stack trace. */
function toJson(value, indent) {
  try {
    return JSON.stringify(value, (k, v) => (typeof v === 'number' && !Number.isFinite(v) ? null : v), indent);
  } catch (e) {
    throw new CliError(`the JSON report cannot be built: ${e.message}`);
  }
}

/** Exit status under --fail-on-fault: 1 when any audited log has faults. */
let faultsFound = false;
/** Exit status 2 when any log of a folder could not be read. */
let unreadable = false;

/** A whole log read for the HTML report: its columns for the plots and the
 * audit with per-row outputs (the report equals the streamed one). */
function auditForHtml(file, config) {
  const { fd } = openInput(file);
  let bytes;
  try { bytes = new Uint8Array(readFileSync(fd)); } finally { closeSync(fd); }
  try {
    const log = ng.readLog(bytes);
    const { report, columns } = ng.auditBytes(bytes, config);
    return { report, series: flightSeries(log.columns, columns, report) };
  } catch (e) {
    throw new CliError(`${file}: ${e && e.message ? e.message : e}`);
  }
}

/** Write the HTML report of `flights` to `out` (atomically; never an input). */
function writeHtml(out, flights, inputs, title) {
  progress(`writing ${out}...`);
  const html = renderReport({ title, version: ng.version(), flights });
  writeAtomic(out, html, '--html', inputs);
  progressDone();
  process.stderr.write(`wrote ${out} (${(html.length / 1024).toFixed(0)} KiB, ${flights.length} log${flights.length === 1 ? '' : 's'})\n`);
}

/** `report FILE --html OUT` and `audit FILE --html OUT`. */
function htmlReport(file, opt) {
  const config = readConfig(opt.config);
  const out = new AtomicOutput(opt.html, '--html', [file]);
  out.abort(); // checked now, written by writeHtml once the audit is done
  progress(`auditing ${file} for the HTML report...`);
  let res;
  try { res = auditForHtml(file, config); } finally { progressDone(); }
  if (verdictOf(res.report) === 'faults') faultsFound = true;
  writeHtml(opt.html, [{ name: file, ...res }], [file], `navguard report: ${file}`);
  return res.report;
}

/** Any log streamed from disk in 4 MiB chunks (lib/stream-audit.mjs):
 * memory stays bounded whatever the file's size and format; the per-sample
 * file is written as the outputs come (to its temporary file). */
function auditStream(file, fd, size, perSample, config) {
  if (perSample !== null) perSample.write(perSampleHeader());
  const res = streamAudit(ng, fd, config, {
    keepOutputs: perSample !== null,
    onChunk(run, pos, pass) {
      if (perSample !== null) perSample.write(perSampleRows(run.outputs()));
      const of = pass > 1 || run.format() === 'ulog' ? ` (pass ${pass} of 2)` : '';
      progress(`auditing ${file}: ${(100 * pos / Math.max(1, size)).toFixed(0)}% of ${(size / 1e6).toFixed(1)} MB${of}, ${run.rows()} rows`);
    },
  });
  if (perSample !== null) perSample.write(perSampleRows(res.columns));
  return res;
}

/** The per-sample file's second pass: each line of the first (`scratch`)
 * with the whole-log verdict appended, `reconciled` (1 inside an interval
 * of `report.reconciled`, else 0), known only once the log has been read
 * to its end. */
function addReconciled(scratch, out, report) {
  const at = reconciledAt(report);
  let header = true, chunk = '';
  scratch.eachLine((line) => {
    if (line === '') return;
    chunk += header ? `${line},reconciled\n` : `${line},${at(Number(line.slice(0, line.indexOf(','))))}\n`;
    header = false;
    if (chunk.length > 1 << 16) { out.write(chunk); chunk = ''; }
  });
  out.write(chunk);
}

function audit(file, opt) {
  const config = readConfig(opt.config);
  const { fd, size } = openInput(file);
  let res, perSample = null, scratch = null;
  try {
    // The per-sample file is written beside its target and renamed over it
    // only once the audit succeeded: an output that names the input (or a
    // link to it) is refused, and a failed run leaves no half-written file.
    // Its rows go to a scratch file first: their `reconciled` column needs
    // the whole log's verdict.
    if (opt['per-sample']) {
      perSample = new AtomicOutput(opt['per-sample'], '--per-sample', [file]);
      scratch = new ScratchFile(perSample);
    }
    progress(`auditing ${file} (${(size / 1e6).toFixed(1)} MB)...`);
    try {
      res = auditStream(file, fd, size, scratch, config);
    } catch (e) {
      if (e instanceof CliError) throw e;
      throw new CliError(`${file}: ${e && e.message ? e.message : e}`);
    }
    if (perSample !== null) {
      progress(`${file}: writing the per-sample file...`);
      addReconciled(scratch, perSample, res.report);
      perSample.commit();
    }
    perSample = null;
  } finally {
    if (perSample !== null) perSample.abort();
    if (scratch !== null) scratch.remove();
    closeSync(fd);
    progressDone();
  }
  const { report } = res;
  if (opt.html) htmlReport(file, opt);
  const verdict = verdictOf(report);
  if (verdict === 'faults') faultsFound = true;
  const out = { file, verdict, ...report };
  if (opt.json) {
    writeOut(toJson(out) + '\n');
    return;
  }
  const L = [];
  const t0 = Number.isFinite(report.startT) ? report.startT : 0;
  const faults = faultList(report);
  L.push(`${file}: ${report.format}, ${report.rows} rows, ${report.durationS.toFixed(1)} s: ${verdict}`);
  L.push(`  start: ${fmtUtc(report.startUtc) || 'UTC unknown (no GPS time in the log)'}; times below are seconds since the log's start (boot clock ${t0.toFixed(3)} s)`);
  L.push(`  GPS: ${report.gpsAvailable ? `${report.gpsEpochs} epochs at ${report.gpsRateHz.toFixed(1)} Hz, fix in ${(100 * report.gpsFixFraction).toFixed(1)}% of reports, receiver quality as ${qualityLabel(report)}` : 'unavailable'}; IMU ${report.imuRateHz.toFixed(1)} Hz`);
  if (report.missing.length) L.push(`  missing inputs: ${report.missing.join(', ')}`);
  L.push(report.gpsAvailable ? `  flagged GPS epochs: ${(100 * report.flaggedGpsEpochFraction).toFixed(2)}%` : `  flagged GPS epochs: none to judge (no GPS fix in the log)\n  ${checkedWithoutGps(report)}`);
  L.push(`  fault intervals: ${faults.length}`);
  for (const f of faults.slice(0, 20)) L.push(intervalLine(f, t0));
  if (faults.length > 20) L.push(`    ... ${faults.length - 20} more (use --json)`);
  // The whole-log verdict, when it differs: flicker joined, and faults the
  // detector saw end dated from their onset.
  const rec = reconciledIfDifferent(report);
  if (rec) {
    L.push(`  reconciled over the whole log: ${rec.length} interval${rec.length === 1 ? '' : 's'}`);
    for (const f of rec.slice(0, 20)) L.push(intervalLine(f, t0));
    if (rec.length > 20) L.push(`    ... ${rec.length - 20} more (use --json)`);
  }
  if ((report.modes || []).length) L.push(`  flight modes: ${report.modes.slice(0, 12).map((m) => `${fmtSince(m.t - t0)} ${m.mode}`).join(', ')}${report.modes.length > 12 ? `, ... (${report.modes.length} in all)` : ''}`);
  const alerts = (report.messages || []).filter((m) => m.level === 'error' || m.level === 'warning');
  if ((report.messages || []).length) L.push(`  autopilot messages: ${report.messages.length} (${alerts.length} warnings or errors)`);
  for (const m of alerts.slice(0, 10)) L.push(`    ${fmtSince(m.t - t0).padStart(9)}  ${m.level}: ${m.text}`);
  for (const w of report.warnings) L.push(`  warning: ${w}`);
  if (report.metrics) {
    const m = report.metrics;
    L.push(`  vs labels: accuracy ${m.accuracy.toFixed(4)}, false alarm ${m.falseAlarmRate.toFixed(4)}, misdetection ${m.misdetectionRate.toFixed(4)}, precision ${m.precision.toFixed(4)}, recall ${m.recall.toFixed(4)}, F2 ${m.f2.toFixed(4)}, mean delay ${Number.isFinite(m.meanDetectionDelay) ? m.meanDetectionDelay.toFixed(2) + ' s' : '-'} (TP ${m.tp} FN ${m.fn} FP ${m.fp} TN ${m.tn})`);
  }
  writeOut(L.join('\n') + '\n');
}

/** Audit every log under a folder (recursively) in parallel
 * (worker_threads), one summary. */
async function auditDir(dir, opt) {
  const { logs: files, skipped } = walkLogs(dir);
  if (!files.length) throw new CliError(`${dir}: no logs found (${skipped.length} other files skipped)`);
  const config = readConfig(opt.config);
  // Checked before the audit starts, so a bad path costs nothing.
  const summaryOut = opt.summary ? new AtomicOutput(opt.summary, '--summary', files) : null;
  if (opt.html) new AtomicOutput(opt.html, '--html', files).abort();
  const series = !!opt.html;
  const jobs = Math.max(1, Math.min(opt.jobs ?? availableParallelism(), files.length));
  const results = [];
  let next = 0, done = 0;
  const t0 = performance.now();
  await new Promise((resolve) => {
    const workers = Array.from({ length: jobs }, () => new Worker(new URL('../lib/audit-worker.mjs', import.meta.url)));
    const feed = (w) => {
      if (next < files.length) w.postMessage({ file: files[next++], config, series });
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
  const rows = results.map((r) => r.error ? { file: r.file, verdict: 'unreadable', error: r.error } : {
    file: r.file, verdict: verdictOf(r.report), format: r.report.format, durationS: r.report.durationS, gpsAvailable: r.report.gpsAvailable,
    startT: r.report.startT, startUtc: r.report.startUtc ?? null, ephSource: r.report.ephSource,
    gpsRateHz: r.report.gpsRateHz, flaggedGpsEpochFraction: r.report.flaggedGpsEpochFraction,
    residualFaults: faultList(r.report).filter((f) => f.kind === 'residual').length,
    outages: faultList(r.report).filter((f) => f.kind === 'gps_outage' || f.kind === 'gps_stale').length,
    dataGaps: r.report.dataGaps.length, warnings: r.report.warnings, missing: r.report.missing,
    // Every interval (boot-clock s, as in the single-file report), not only counts.
    faults: faultList(r.report), ms: r.ms,
  });
  if (rows.some((r) => r.verdict === 'faults')) faultsFound = true;
  if (rows.some((r) => r.error)) unreadable = true;
  if (opt.html) {
    const name = (f) => relative(dir, f) || f;
    const flights = results.map((r) => (r.error ? { name: name(r.file), error: r.error } : { name: name(r.file), report: r.report, series: r.series }));
    writeHtml(opt.html, flights, files, `navguard fleet report: ${dir}`);
  }
  const summary = { dir, files: files.length, failed: rows.filter((r) => r.error).length, skipped, wallMs: performance.now() - t0, jobs, logs: rows };
  const json = toJson(summary, 2);
  if (summaryOut !== null) { summaryOut.write(json + '\n'); summaryOut.commit(); }
  if (opt.json) { writeOut(json + '\n'); return; }
  const L = [`${dir}: ${files.length} logs, ${summary.failed} unreadable, ${skipped.length} other files skipped, ${jobs} workers, ${(summary.wallMs / 1000).toFixed(2)} s`];
  L.push('  file                                              format     dur s  GPS Hz  flagged  faults outages gaps  verdict     start (UTC)');
  for (const r of rows) {
    const name = r.file.length > 48 ? '...' + r.file.slice(-45) : r.file;
    if (r.error) { L.push(`  ${name.padEnd(48)}  unreadable: ${r.error}`); continue; }
    L.push(`  ${name.padEnd(48)}  ${r.format.padEnd(9)} ${r.durationS.toFixed(1).padStart(6)} ${r.gpsAvailable ? r.gpsRateHz.toFixed(1).padStart(6) : '    no'}  ${r.gpsAvailable ? (100 * r.flaggedGpsEpochFraction).toFixed(2).padStart(6) + '%' : '      -'}  ${String(r.residualFaults).padStart(5)} ${String(r.outages).padStart(7)} ${String(r.dataGaps).padStart(4)}  ${r.verdict.padEnd(10)}  ${fmtUtc(r.startUtc) || '-'}`);
  }
  writeOut(L.join('\n') + '\n');
}

const BEGIN = '<!-- compare:begin (generated by `navguard compare`; do not edit) -->';
const END = '<!-- compare:end -->';

/** Every method over the battery (and real logs): tables to stdout, or into
 * the README between the compare markers. */
function compare(opt) {
  const options = {};
  if (opt.battery) {
    if (opt.seeds !== undefined) throw new CliError(`--seeds does not go with --battery (use --flights)`);
    options.battery = opt.battery;
    if (opt.flights !== undefined) options.flights = opt.flights;
  } else {
    if (opt.flights !== undefined) throw new CliError(`--flights goes with --battery tune|eval`);
    options.seeds = opt.seeds ?? 5;
  }
  if (opt.methods) options.methods = opt.methods;
  // The README is rewritten in place: check it before the long run.
  const readme = opt['update-readme'];
  let readmeText = null;
  if (readme) {
    readmeText = readSmall(readme, CONFIG_LIMIT, '--update-readme');
    const a = readmeText.indexOf(BEGIN), b = readmeText.indexOf(END);
    if (a < 0 || b < a) throw new CliError(`${readme}: no compare markers (${BEGIN} ... ${END})`);
  }
  let run;
  try { run = new ng.CompareRun(options); } catch (e) { throw new CliError(e.message); }
  if (opt.logs) {
    const { logs } = walkLogs(opt.logs);
    for (const f of logs) {
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
  } catch (e) { progressDone(); throw new CliError(e.message); }
  progressDone();
  process.stderr.write(`compared in ${((performance.now() - t0) / 1000).toFixed(1)} s\n`);
  if (opt.json) { writeOut(toJson(res.comparison) + '\n'); return; }
  if (readme) {
    const a = readmeText.indexOf(BEGIN), b = readmeText.indexOf(END);
    writeAtomic(readme, readmeText.slice(0, a + BEGIN.length) + '\n' + res.markdown + readmeText.slice(b), '--update-readme');
    process.stderr.write(`updated ${readme}\n`);
    return;
  }
  writeOut(res.markdown + '\n');
}

/** Each command's flags (name -> value kind, see lib/args.mjs) and help. */
const COMMANDS = {
  audit: {
    flags: { json: 'bool', 'per-sample': 'path', config: 'path', summary: 'path', jobs: 'count', 'fail-on-fault': 'bool', html: 'path' },
    help: `navguard audit FILE [--json] [--per-sample OUT.csv] [--html OUT.html] [--config CFG.json] [--fail-on-fault]
navguard audit DIR [--json] [--summary OUT.json] [--html OUT.html] [--config CFG.json] [--jobs N] [--fail-on-fault]

Audit a flight log (navlog CSV, PX4 ULog or ArduPilot DataFlash, recognised by
content) or every log under a folder (recursively, following links).
  --json             one JSON report on stdout
  --per-sample FILE  one line per input row: t,status,f,r,c,kind,residuals,reconciled
                     (written atomically; never the input file)
  --config FILE      detector configuration (JSON object)
  --html FILE        a self-contained HTML report (one flight, or the fleet
                     with one section per log); written atomically
  --summary FILE     (DIR) the fleet summary as JSON, every interval listed
  --jobs N           (DIR) parallel workers (default: the number of cores)
  --fail-on-fault    exit 1 when a fault interval was found (for scripts)
Each log gets a verdict: faults, clean, or "no verdict" (no GPS fix to judge).
Times in tables are seconds since the log's start (JSON: boot clock, with
startT and startUtc). Progress goes to stderr on a terminal only.
Exit status: 0 when every log was read (1 with --fail-on-fault and faults
found), 2 when a log could not be read.`,
  },
  simulate: {
    flags: { seed: 'seed', out: 'path' },
    help: `navguard simulate NAME [--seed N] [--out FILE.csv]

Simulate a built-in scenario into navlog CSV (stdout, or FILE written atomically).
Names: ${ng.scenarioNames().join(', ')}`,
  },
  report: {
    flags: { seed: 'seed', json: 'bool', quick: 'bool', html: 'path', config: 'path', 'fail-on-fault': 'bool' },
    help: `navguard report FILE --html OUT.html [--config CFG.json] [--fail-on-fault]
navguard report [--seed N] [--json] [--quick]

With FILE: a self-contained HTML report of one flight log (verdict, fault
intervals, plots, track, receiver quality, flight modes and autopilot
messages), written atomically to OUT.html; it never overwrites the log.
Without: the paper scenario's TC sweep, the fault kinds and the clean flights.`,
  },
  train: {
    flags: { out: 'path', config: 'path' },
    help: `navguard train LABELLED.csv [...] --out MODEL.json [--config CFG.json]

Train an ANFIS model from labelled navlog CSV files (--out written atomically).`,
  },
  compare: {
    flags: { seeds: 'count', methods: 'list', logs: 'path', json: 'bool', 'update-readme': 'path', battery: 'string', flights: 'count' },
    help: `navguard compare [--seeds N | --battery tune|eval [--flights N]] [--methods a,b,...] [--logs DIR] [--json] [--update-readme README.md]

Every config.method over the seeded battery (and the logs under DIR).
--battery runs N flights (default 48) of the randomised development battery's
split instead (other noise models, rates, IMU grades, trajectories, fault kinds
and durations; the eval split was never used for tuning).`,
  },
};

const VERSION = `navguard ${ng.version()}`;

/** stdout that ends quietly when the reader goes away (\`| head\`). */
function writeOut(text) {
  process.stdout.write(text);
}
process.stdout.on('error', (e) => {
  if (e.code === 'EPIPE') process.exit(0);
  process.stderr.write(`navguard: stdout: ${e.message}\n`);
  process.exit(2);
});

function run(cmd, pos, opt) {
  switch (cmd) {
    case 'audit': {
      if (pos.length !== 1) throw new CliError(`audit takes one FILE or DIR; see 'navguard audit --help'`);
      let dir = false;
      try { dir = statSync(pos[0]).isDirectory(); } catch { /* audit() reports it */ }
      if (dir) return auditDir(pos[0], opt);
      for (const k of ['summary', 'jobs']) if (k in opt) throw new CliError(`audit: --${k} applies to a folder, and ${pos[0]} is a file`);
      return audit(pos[0], opt);
    }
    case 'simulate': {
      if (pos.length !== 1) throw new CliError(`simulate takes one scenario NAME; see 'navguard simulate --help'`);
      let csv;
      try { csv = ng.simulate(pos[0], opt.seed ?? 1); } catch (e) { throw new CliError(e.message); }
      if (opt.out) writeAtomic(opt.out, csv, '--out'); else writeOut(csv);
      return;
    }
    case 'report': {
      if (pos.length > 1) throw new CliError(`report takes one FILE; see 'navguard report --help'`);
      if (pos.length === 1) {
        if (!opt.html) throw new CliError(`report FILE needs --html OUT.html; see 'navguard report --help'`);
        for (const k of ['seed', 'json', 'quick']) if (k in opt) throw new CliError(`report: --${k} applies to the paper report, not to a FILE`);
        htmlReport(pos[0], opt);
        return;
      }
      for (const k of ['html', 'config', 'fail-on-fault']) if (k in opt) throw new CliError(`report: --${k} needs a FILE; see 'navguard report --help'`);
      const seed = opt.seed ?? 1;
      const sweep = tcSweep(ng, seed, progress);
      const kinds = opt.quick ? null : faultKinds(ng, [1, 2, 3], progress);
      const clean = opt.quick ? null : cleanFlights(ng, [1, 2, 3], progress);
      progressDone();
      writeOut((opt.json ? toJson({ sweep, kinds, clean }) : formatReport({ sweep, kinds, clean })) + '\n');
      return;
    }
    case 'train': {
      if (!pos.length || !opt.out) throw new CliError(`train needs labelled CSV files and --out; see 'navguard train --help'`);
      const config = readConfig(opt.config);
      const out = new AtomicOutput(opt.out, '--out', pos);
      try {
        const files = pos.map((p) => {
          const { fd } = openInput(p);
          try { return new Uint8Array(readFileSync(fd)); } finally { closeSync(fd); }
        });
        let model;
        try { model = ng.trainFromCsv(files, config); } catch (e) { throw new CliError(e.message); }
        out.write(toJson(model) + '\n');
        out.commit();
        process.stderr.write(`wrote ${opt.out}: ${model.provenance}\n`);
      } catch (e) { out.abort(); throw e; }
      return;
    }
    case 'compare':
      if (pos.length) throw new CliError(`compare takes no file (use --logs DIR); see 'navguard compare --help'`);
      return compare(opt);
  }
}

async function main() {
  const [cmd, ...rest] = process.argv.slice(2);
  if (cmd === undefined || cmd === 'help' || cmd === '--help' || cmd === '-h') {
    const topic = cmd === 'help' ? rest[0] : undefined;
    writeOut((topic && Object.hasOwn(COMMANDS, topic) ? COMMANDS[topic].help : USAGE) + '\n');
    return;
  }
  if (cmd === '--version' || cmd === '-V' || cmd === 'version') { writeOut(VERSION + '\n'); return; }
  if (!Object.hasOwn(COMMANDS, cmd)) {
    const s = suggest(cmd, Object.keys(COMMANDS));
    throw new CliError(`unknown command "${cmd}"${s ? ` (did you mean "${s}"?)` : ''}; see 'navguard --help'`);
  }
  const { pos, opt } = parseArgs(cmd, rest, { ...COMMANDS[cmd].flags, version: 'bool' });
  if (opt.help) { writeOut(COMMANDS[cmd].help + '\n'); return; }
  if (opt.version) { writeOut(VERSION + '\n'); return; }
  await run(cmd, pos, opt);
  if (unreadable) process.exitCode = 2;
  else if (opt['fail-on-fault'] && faultsFound) process.exitCode = 1;
}

main().catch((e) => {
  progressDone();
  if (e instanceof CliError) fail(e.message);
  // Anything else is a bug, but still one line and exit 2, not a trace.
  fail(`internal error: ${e && e.message ? e.message : e}`);
});
