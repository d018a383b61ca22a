#!/usr/bin/env node
// navguard CLI: audit flight logs, simulate scenarios, reproduce the paper.
//   navguard audit FILE [--json] [--per-sample OUT.csv] [--config CFG.json]
//   navguard simulate NAME [--seed N] [--out FILE.csv]
//   navguard report [--seed N] [--json] [--quick]
//   navguard train LABELLED.csv [...] --out MODEL.json
//   navguard compare [--seeds N] [--methods a,b] [--logs DIR] [--json] [--update-readme FILE]
import { readFileSync, statSync, closeSync } from 'node:fs';
import { Worker } from 'node:worker_threads';
import { availableParallelism } from 'node:os';
import { createRequire } from 'node:module';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';
import { performance } from 'node:perf_hooks';
import { perSampleHeader, perSampleRows } from '../lib/csv.mjs';
import { streamAudit } from '../lib/stream-audit.mjs';
import { tcSweep, faultKinds, cleanFlights, formatReport } from '../lib/report.mjs';
import { CliError, AtomicOutput, openInput, readSmall, walkLogs, writeAtomic } from '../lib/files.mjs';
import { parseArgs, suggest } from '../lib/args.mjs';

const require = createRequire(import.meta.url);
const ng = require(join(dirname(fileURLToPath(import.meta.url)), '..', 'node.cjs'));

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

/**
 * One word for a report: `faults` (at least one interval), `clean`, or
 * `no verdict` when the log has no GPS fix to judge, so a log the detector
 * could not judge is never shown as a clean flight.
 */
function verdictOf(report) {
  if (!report.gpsAvailable) return 'no verdict';
  return report.faults.length > 0 ? 'faults' : 'clean';
}

/** Exit status under --fail-on-fault: 1 when any audited log has faults. */
let faultsFound = false;

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

function audit(file, opt) {
  const config = readConfig(opt.config);
  const { fd, size } = openInput(file);
  let res, perSample = null;
  try {
    // The per-sample file is written beside its target and renamed over it
    // only once the audit succeeded: an output that names the input (or a
    // link to it) is refused, and a failed run leaves no half-written file.
    if (opt['per-sample']) perSample = new AtomicOutput(opt['per-sample'], '--per-sample', [file]);
    progress(`auditing ${file} (${(size / 1e6).toFixed(1)} MB)...`);
    try {
      res = auditStream(file, fd, size, perSample, config);
    } catch (e) {
      if (e instanceof CliError) throw e;
      throw new CliError(`${file}: ${e && e.message ? e.message : e}`);
    }
    if (perSample !== null) perSample.commit();
    perSample = null;
  } finally {
    if (perSample !== null) perSample.abort();
    closeSync(fd);
    progressDone();
  }
  const { report } = res;
  const verdict = verdictOf(report);
  if (verdict === 'faults') faultsFound = true;
  const out = { file, verdict, ...report };
  if (opt.json) {
    writeOut(toJson(out) + '\n');
    return;
  }
  const L = [];
  L.push(`${file}: ${report.format}, ${report.rows} rows, ${report.durationS.toFixed(1)} s: ${verdict}`);
  L.push(`  GPS: ${report.gpsAvailable ? `${report.gpsEpochs} epochs at ${report.gpsRateHz.toFixed(1)} Hz, fix in ${(100 * report.gpsFixFraction).toFixed(1)}% of reports` : 'unavailable'}; IMU ${report.imuRateHz.toFixed(1)} Hz`);
  if (report.missing.length) L.push(`  missing inputs: ${report.missing.join(', ')}`);
  L.push(report.gpsAvailable ? `  flagged GPS epochs: ${(100 * report.flaggedGpsEpochFraction).toFixed(2)}%` : '  flagged GPS epochs: none to judge (no GPS fix in the log)');
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
  const jobs = Math.max(1, Math.min(opt.jobs ?? availableParallelism(), files.length));
  const results = [];
  let next = 0, done = 0;
  const t0 = performance.now();
  await new Promise((resolve) => {
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
  const rows = results.map((r) => r.error ? { file: r.file, verdict: 'unreadable', error: r.error } : {
    file: r.file, verdict: verdictOf(r.report), format: r.report.format, durationS: r.report.durationS, gpsAvailable: r.report.gpsAvailable,
    gpsRateHz: r.report.gpsRateHz, flaggedGpsEpochFraction: r.report.flaggedGpsEpochFraction,
    residualFaults: r.report.faults.filter((f) => f.kind === 'residual').length,
    outages: r.report.faults.filter((f) => f.kind === 'gps_outage').length,
    dataGaps: r.report.dataGaps.length, warnings: r.report.warnings, missing: r.report.missing, ms: r.ms,
  });
  if (rows.some((r) => r.verdict === 'faults')) faultsFound = true;
  const summary = { dir, files: files.length, failed: rows.filter((r) => r.error).length, skipped, wallMs: performance.now() - t0, jobs, logs: rows };
  const json = toJson(summary, 2);
  if (summaryOut !== null) { summaryOut.write(json + '\n'); summaryOut.commit(); }
  if (opt.json) { writeOut(json + '\n'); return; }
  const L = [`${dir}: ${files.length} logs, ${summary.failed} unreadable, ${skipped.length} other files skipped, ${jobs} workers, ${(summary.wallMs / 1000).toFixed(2)} s`];
  L.push('  file                                              format     dur s  GPS Hz  flagged  faults outages gaps  verdict');
  for (const r of rows) {
    const name = r.file.length > 48 ? '...' + r.file.slice(-45) : r.file;
    if (r.error) { L.push(`  ${name.padEnd(48)}  unreadable: ${r.error}`); continue; }
    L.push(`  ${name.padEnd(48)}  ${r.format.padEnd(9)} ${r.durationS.toFixed(1).padStart(6)} ${r.gpsAvailable ? r.gpsRateHz.toFixed(1).padStart(6) : '    no'}  ${r.gpsAvailable ? (100 * r.flaggedGpsEpochFraction).toFixed(2).padStart(6) + '%' : '      -'}  ${String(r.residualFaults).padStart(5)} ${String(r.outages).padStart(7)} ${String(r.dataGaps).padStart(4)}  ${r.verdict}`);
  }
  writeOut(L.join('\n') + '\n');
}

const BEGIN = '<!-- compare:begin (generated by `navguard compare`; do not edit) -->';
const END = '<!-- compare:end -->';

/** Every method over the battery (and real logs): tables to stdout, or into
 * the README between the compare markers. */
function compare(opt) {
  const options = { seeds: opt.seeds ?? 5 };
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
    flags: { json: 'bool', 'per-sample': 'path', config: 'path', summary: 'path', jobs: 'count', 'fail-on-fault': 'bool' },
    help: `navguard audit FILE [--json] [--per-sample OUT.csv] [--config CFG.json]
navguard audit DIR [--json] [--summary OUT.json] [--config CFG.json] [--jobs N]

Audit a flight log (navlog CSV, PX4 ULog or ArduPilot DataFlash, recognised by
content) or every log under a folder (recursively, following links).
  --json             one JSON report on stdout
  --per-sample FILE  one line per input row: t,status,f,r,c,kind,residuals
                     (written atomically; never the input file)
  --config FILE      detector configuration (JSON object)
  --summary FILE     (DIR) the fleet summary as JSON
  --jobs N           (DIR) parallel workers (default: the number of cores)
  --fail-on-fault    exit 1 when a fault interval was found (for scripts)
Each log gets a verdict: faults, clean, or "no verdict" (no GPS fix to judge).
Exit status: 0 when the log was read (1 with --fail-on-fault and faults
found), 2 when it could not be.`,
  },
  simulate: {
    flags: { seed: 'seed', out: 'path' },
    help: `navguard simulate NAME [--seed N] [--out FILE.csv]

Simulate a built-in scenario into navlog CSV (stdout, or FILE written atomically).
Names: ${ng.scenarioNames().join(', ')}`,
  },
  report: {
    flags: { seed: 'seed', json: 'bool', quick: 'bool' },
    help: `navguard report [--seed N] [--json] [--quick]

The paper scenario's TC sweep, the fault kinds and the clean flights.`,
  },
  train: {
    flags: { out: 'path', config: 'path' },
    help: `navguard train LABELLED.csv [...] --out MODEL.json [--config CFG.json]

Train an ANFIS model from labelled navlog CSV files (--out written atomically).`,
  },
  compare: {
    flags: { seeds: 'count', methods: 'list', logs: 'path', json: 'bool', 'update-readme': 'path' },
    help: `navguard compare [--seeds N] [--methods a,b,...] [--logs DIR] [--json] [--update-readme README.md]

Every config.method over the seeded battery (and the logs under DIR).`,
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
      if (pos.length) throw new CliError(`report takes no file; see 'navguard report --help'`);
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
  if (opt['fail-on-fault'] && faultsFound) process.exitCode = 1;
}

main().catch((e) => {
  progressDone();
  if (e instanceof CliError) fail(e.message);
  // Anything else is a bug, but still one line and exit 2, not a trace.
  fail(`internal error: ${e && e.message ? e.message : e}`);
});
