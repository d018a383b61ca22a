#!/usr/bin/env node
// navguard CLI: audit flight logs, simulate scenarios, reproduce the paper.
//   navguard audit FILE [--json] [--per-sample OUT.csv] [--config CFG.json]
//   navguard simulate NAME [--seed N] [--out FILE.csv]
//   navguard report [--seed N] [--json] [--quick]
//   navguard train LABELLED.csv [...] --out MODEL.json
import { readFileSync, writeFileSync } from 'node:fs';
import { createRequire } from 'node:module';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';
import { perSampleCsv } from '../lib/csv.mjs';
import { tcSweep, faultKinds, cleanFlights, formatReport } from '../lib/report.mjs';

const require = createRequire(import.meta.url);
const ng = require(join(dirname(fileURLToPath(import.meta.url)), '..', 'navguard.js'));

const USAGE = `usage:
  navguard audit FILE [--json] [--per-sample OUT.csv] [--config CFG.json]
  navguard simulate NAME [--seed N] [--out FILE.csv]     (names: ${ng.scenarioNames().join(', ')})
  navguard report [--seed N] [--json] [--quick]
  navguard train LABELLED.csv [...] --out MODEL.json`;

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

function audit(file, opt) {
  let bytes;
  try { bytes = readFileSync(file); } catch (e) { fail(`${file}: ${e.code === 'ENOENT' ? 'no such file' : e.message}`); }
  const config = readConfig(opt.config);
  progress(`auditing ${file} (${(bytes.length / 1e6).toFixed(1)} MB)...`);
  let res;
  try { res = ng.auditBytes(bytes, config); } catch (e) { progressDone(); fail(`${file}: ${e.message}`); }
  progressDone();
  const { report, columns } = res;
  if (opt['per-sample']) writeFileSync(opt['per-sample'], perSampleCsv(columns));
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

function main() {
  const [cmd, ...rest] = process.argv.slice(2);
  const { pos, opt } = parse(rest);
  switch (cmd) {
    case 'audit':
      if (pos.length !== 1) fail(`audit takes one FILE\n${USAGE}`);
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
    case undefined: case 'help': case '--help': case '-h':
      console.log(USAGE);
      return;
    default:
      fail(`unknown command "${cmd}"\n${USAGE}`);
  }
}

main();
