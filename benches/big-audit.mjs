// Bounded-memory check of the CLI audit on a 1 GB navlog CSV.
//
// Writes a ~1 GB CSV (simulated 300 s survey flights, seeds 1.., laid end to
// end with a 20 s logging pause between them, so it reads as one long log),
// then runs `navguard audit FILE --json --per-sample OUT` under
// /usr/bin/time and reports the peak resident memory, time and throughput.
// Exits 1 if the peak RSS exceeds the bound: memory must not grow with the
// file. Usage: node benches/big-audit.mjs [SIZE_MB=1024] [BOUND_MB=256]
import { createRequire } from 'node:module';
import { openSync, writeSync, closeSync, statSync, rmSync, mkdtempSync } from 'node:fs';
import { spawnSync } from 'node:child_process';
import { tmpdir } from 'node:os';
import { join, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';

const root = join(dirname(fileURLToPath(import.meta.url)), '..');
const ng = createRequire(import.meta.url)(join(root, 'pkg'));
const sizeMb = Number(process.argv[2] ?? 1024);
const boundMb = Number(process.argv[3] ?? 256);
const dir = mkdtempSync(join(tmpdir(), 'navguard-big-'));
const file = join(dir, 'big.csv');
const perSample = join(dir, 'big-per-sample.csv');

// One flight, re-timed for each leg (the CSV's first column is t).
const flight = ng.simulate('clean-survey', 1).split('\n');
const header = flight.findIndex((l) => l.startsWith('t,'));
const rows = flight.slice(header + 1).filter((l) => l.length > 0).map((l) => {
  const i = l.indexOf(',');
  return [Number(l.slice(0, i)), l.slice(i)];
});
const span = rows[rows.length - 1][0] - rows[0][0] + 20;

let t0 = performance.now();
const fd = openSync(file, 'w');
writeSync(fd, flight.slice(0, header + 1).join('\n') + '\n');
let bytes = 0, legs = 0, lines = 0;
while (bytes < sizeMb * 1e6) {
  const off = legs * span;
  let buf = '';
  for (const [t, rest] of rows) buf += `${(t + off).toFixed(3)}${rest}\n`;
  bytes += writeSync(fd, buf);
  legs++;
  lines += rows.length;
}
closeSync(fd);
const writeS = (performance.now() - t0) / 1000;
const size = statSync(file).size;
console.error(`wrote ${(size / 1e6).toFixed(0)} MB (${lines} rows, ${legs} legs of ${span.toFixed(0)} s) in ${writeS.toFixed(1)} s`);

t0 = performance.now();
const r = spawnSync('/usr/bin/time', ['-f', '%M', process.execPath, join(root, 'pkg', 'bin', 'navguard.mjs'), 'audit', file, '--json', '--per-sample', perSample], { encoding: 'utf8', maxBuffer: 1 << 26 });
const wall = (performance.now() - t0) / 1000;
if (r.status !== 0) {
  console.error(r.stderr);
  process.exit(1);
}
const peakMb = Number(r.stderr.trim().split('\n').pop()) / 1024;
const report = JSON.parse(r.stdout);
const outSize = statSync(perSample).size;
rmSync(dir, { recursive: true, force: true });
const res = {
  inputMB: +(size / 1e6).toFixed(1),
  rows: report.rows,
  expectedRows: lines,
  dataGaps: report.dataGaps.length,
  faults: report.faults.length,
  flaggedGpsEpochFraction: +report.flaggedGpsEpochFraction.toFixed(5),
  perSampleMB: +(outSize / 1e6).toFixed(1),
  wallS: +wall.toFixed(1),
  MBperS: +(size / 1e6 / wall).toFixed(1),
  rowsPerS: Math.round(report.rows / wall),
  peakRssMB: +peakMb.toFixed(1),
  boundMB: boundMb,
};
console.log(JSON.stringify(res, null, 2));
if (report.rows !== lines) {
  console.error(`audited ${report.rows} rows, wrote ${lines}`);
  process.exit(1);
}
if (peakMb > boundMb) {
  console.error(`peak RSS ${peakMb.toFixed(0)} MB exceeds the ${boundMb} MB bound`);
  process.exit(1);
}
