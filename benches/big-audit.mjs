// Bounded-memory check of the CLI audit on big logs of every format.
//
// Writes, in a temporary folder (never in the repository):
// - csv:       a ~1 GB navlog CSV (simulated 300 s survey flights, seeds 1..,
//              end to end with a 20 s logging pause, so it reads as one log);
// - csv-short: a CSV of 10 M short rows (t,ax,ay,az), the red team's case;
// - ulog:      a ~150 MB ULog of 9-byte messages (sensor_combined with only
//              a uint32 timestamp, plus a GPS fix every 100th message): the
//              tiny-message memory bomb, 16 M rows;
// - dataflash: a ~150 MB DataFlash log of 11-byte IMU messages (TimeUS only)
//              plus a GPS message every 100th: 13 M rows;
// then runs `navguard audit` on each under /usr/bin/time -v: single file
// (`audit FILE --json`, CSVs also with `--per-sample`), a folder holding it
// (`audit DIR --json`, through a symlink) and a folder holding two symlinks
// to it with `--jobs 2`. Prints a table of peak RSS (the whole process: main
// thread and workers), time and rows, and exits 1 if any peak exceeds the
// bound or a row is lost. Usage:
//   node benches/big-audit.mjs [CSV_MB=1024] [BIN_MB=150] [BOUND_MB=300] [only=csv,ulog,...]
import { createRequire } from 'node:module';
import { openSync, writeSync, closeSync, statSync, rmSync, mkdtempSync, mkdirSync, symlinkSync } from 'node:fs';
import { spawnSync } from 'node:child_process';
import { tmpdir } from 'node:os';
import { join, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';

const root = join(dirname(fileURLToPath(import.meta.url)), '..');
const ng = createRequire(import.meta.url)(join(root, 'pkg'));
const csvMb = Number(process.argv[2] ?? 1024);
const binMb = Number(process.argv[3] ?? 150);
const boundMb = Number(process.argv[4] ?? 300);
const only = process.argv[5] ? process.argv[5].split(',') : null;
const dir = mkdtempSync(join(tmpdir(), 'navguard-big-'));

/** Buffered writer: `put(buf)` appends, `close()` returns the bytes written. */
function writer(file) {
  const fd = openSync(file, 'w');
  let chunks = [], held = 0, bytes = 0;
  const flush = () => { if (held) { bytes += writeSync(fd, Buffer.concat(chunks)); chunks = []; held = 0; } };
  return {
    put(b) { chunks.push(b); held += b.length; if (held > 8 << 20) flush(); },
    close() { flush(); closeSync(fd); return bytes; },
  };
}

/** ~1 GB CSV of simulated survey flights; returns the row count. */
function writeCsv(file, mb) {
  const flight = ng.simulate('clean-survey', 1).split('\n');
  const header = flight.findIndex((l) => l.startsWith('t,'));
  const rows = flight.slice(header + 1).filter((l) => l.length > 0).map((l) => {
    const i = l.indexOf(',');
    return [Number(l.slice(0, i)), l.slice(i)];
  });
  const span = rows[rows.length - 1][0] - rows[0][0] + 20;
  const w = writer(file);
  w.put(Buffer.from(flight.slice(0, header + 1).join('\n') + '\n'));
  let bytes = 0, lines = 0;
  for (let leg = 0; bytes < mb * 1e6; leg++) {
    let buf = '';
    for (const [t, rest] of rows) buf += `${(t + leg * span).toFixed(3)}${rest}\n`;
    const b = Buffer.from(buf);
    w.put(b);
    bytes += b.length;
    lines += rows.length;
  }
  w.close();
  return lines;
}

/** 10 M short IMU rows at 100 Hz. */
function writeShortCsv(file, n) {
  const w = writer(file);
  w.put(Buffer.from('t,ax,ay,az\n'));
  for (let i = 0; i < n; i += 100000) {
    let buf = '';
    for (let k = i; k < Math.min(n, i + 100000); k++) buf += `${(k / 100).toFixed(2)},0.1,0,-9.8\n`;
    w.put(Buffer.from(buf));
  }
  w.close();
  return n;
}

const le16 = (v) => { const b = Buffer.alloc(2); b.writeUInt16LE(v); return b; };
const ulogMsg = (type, payload) => Buffer.concat([le16(payload.length), Buffer.from(type), payload]);

/** ULog of 9-byte sensor_combined messages, a GPS fix every 100th; returns rows. */
function writeUlog(file, mb) {
  const w = writer(file);
  const head = Buffer.alloc(16);
  Buffer.from([0x55, 0x4c, 0x6f, 0x67, 0x01, 0x12, 0x35, 0x01]).copy(head);
  w.put(head);
  w.put(ulogMsg('F', Buffer.from('sensor_combined:uint32_t timestamp')));
  w.put(ulogMsg('F', Buffer.from('vehicle_gps_position:uint64_t timestamp;int32_t lat;int32_t lon;int32_t alt;uint8_t fix_type')));
  w.put(ulogMsg('A', Buffer.concat([Buffer.from([0]), le16(0), Buffer.from('sensor_combined')])));
  w.put(ulogMsg('A', Buffer.concat([Buffer.from([0]), le16(1), Buffer.from('vehicle_gps_position')])));
  let bytes = 0, rows = 0;
  // 200 µs steps: 16.7 M messages stay inside a uint32 µs clock.
  for (let i = 1; bytes < mb * 1e6; i++) {
    const imu = Buffer.alloc(9);
    imu.writeUInt16LE(6, 0); imu.write('D', 2); imu.writeUInt16LE(0, 3); imu.writeUInt32LE(i * 200, 5);
    w.put(imu); bytes += 9; rows++;
    if (i % 100 === 0) {
      const g = Buffer.alloc(2 + 8 + 12 + 1);
      g.writeUInt16LE(1, 0); g.writeBigUInt64LE(BigInt(i * 200), 2);
      g.writeInt32LE(473977421 + (i % 7), 10); g.writeInt32LE(85455938, 14); g.writeInt32LE(488000, 18); g.writeUInt8(3, 22);
      const m = ulogMsg('D', g);
      w.put(m); bytes += m.length; rows++;
    }
  }
  w.close();
  return rows;
}

/** DataFlash FMT message (89 bytes). */
function fmt(type, len, name, format, columns) {
  const b = Buffer.alloc(89);
  b[0] = 0xa3; b[1] = 0x95; b[2] = 128; b[3] = type; b[4] = len;
  b.write(name, 5); b.write(format, 9); b.write(columns, 25);
  return b;
}

/** DataFlash of 11-byte IMU messages, a GPS fix every 100th; returns rows. */
function writeDataflash(file, mb) {
  const w = writer(file);
  w.put(fmt(128, 89, 'FMT', 'BBnNZ', 'Type,Length,Name,Format,Columns'));
  w.put(fmt(10, 11, 'IMU', 'Q', 'TimeUS'));
  w.put(fmt(11, 3 + 8 + 1 + 4 + 4 + 4 + 1, 'GPS', 'QBLLeB', 'TimeUS,Status,Lat,Lng,Alt,NSats'));
  let bytes = 0, rows = 0;
  for (let i = 1; bytes < mb * 1e6; i++) {
    const m = Buffer.alloc(11);
    m[0] = 0xa3; m[1] = 0x95; m[2] = 10; m.writeBigUInt64LE(BigInt(i * 200), 3);
    w.put(m); bytes += 11; rows++;
    if (i % 100 === 0) {
      const g = Buffer.alloc(25);
      g[0] = 0xa3; g[1] = 0x95; g[2] = 11; g.writeBigUInt64LE(BigInt(i * 200), 3); g[11] = 3;
      g.writeInt32LE(473977421 + (i % 7), 12); g.writeInt32LE(85455938, 16); g.writeInt32LE(48800, 20); g[24] = 12;
      w.put(g); bytes += 25; rows++;
    }
  }
  w.close();
  return rows;
}

const cli = join(root, 'pkg', 'bin', 'navguard.mjs');

/** Run the CLI under /usr/bin/time -v: { peakMB, wallS, out }. */
function run(args) {
  const r = spawnSync('/usr/bin/time', ['-v', process.execPath, cli, ...args], { encoding: 'utf8', maxBuffer: 1 << 28 });
  const peak = Number(/Maximum resident set size \(kbytes\): (\d+)/.exec(r.stderr)?.[1] ?? NaN) / 1024;
  const wall = /Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (.*)/.exec(r.stderr)?.[1] ?? '?';
  const [a, b, c] = wall.split(':').map(Number);
  const wallS = c === undefined ? a * 60 + b : a * 3600 + b * 60 + c;
  if (r.status !== 0) throw new Error(`navguard ${args.join(' ')}: exit ${r.status}\n${r.stderr}`);
  return { peakMB: peak, wallS, out: JSON.parse(r.stdout) };
}

const cases = [
  ['ulog', 'tiny.ulg', () => writeUlog(join(dir, 'tiny.ulg'), binMb)],
  ['dataflash', 'tiny.bin', () => writeDataflash(join(dir, 'tiny.bin'), binMb)],
  ['csv-short', 'short.csv', () => writeShortCsv(join(dir, 'short.csv'), 10_000_000)],
  ['csv', 'big.csv', () => writeCsv(join(dir, 'big.csv'), csvMb)],
].filter(([name]) => !only || only.includes(name));

const table = [];
let failed = false;
try {
  for (const [name, base, make] of cases) {
    const file = join(dir, base);
    let t0 = performance.now();
    const rows = make();
    const mb = statSync(file).size / 1e6;
    console.error(`${name}: wrote ${mb.toFixed(0)} MB, ${rows} rows in ${((performance.now() - t0) / 1000).toFixed(0)} s`);
    const one = join(dir, `${name}-dir1`), two = join(dir, `${name}-dir2`);
    mkdirSync(one); mkdirSync(two);
    symlinkSync(file, join(one, base));
    symlinkSync(file, join(two, `a-${base}`));
    symlinkSync(file, join(two, `b-${base}`));
    const modes = [['single', [file, '--json']]];
    if (name.startsWith('csv')) modes.push(['single --per-sample', [file, '--json', '--per-sample', join(dir, 'per-sample.csv')]]);
    modes.push(['DIR', [one, '--json']], ['DIR --jobs 2', [two, '--json', '--jobs', '2']]);
    for (const [mode, args] of modes) {
      const r = run(['audit', ...args]);
      const reports = mode.startsWith('DIR') ? r.out.logs : [r.out];
      const audited = mode.startsWith('DIR') ? null : r.out.rows;
      const errors = reports.filter((x) => x.error).map((x) => x.error);
      // the table's rows: audited rows (single) or audited files (DIR)
      const ok = errors.length === 0 && (audited === null || audited === rows) && r.peakMB <= boundMb;
      failed ||= !ok;
      table.push({ log: name, inputMB: +mb.toFixed(0), rows, mode, audited: audited ?? `${reports.length - errors.length}/${reports.length} files`, peakRssMB: +r.peakMB.toFixed(0), wallS: +r.wallS.toFixed(0), ok });
      console.error(JSON.stringify(table[table.length - 1]), errors.length ? errors : '');
    }
    rmSync(file, { force: true });
    rmSync(join(dir, 'per-sample.csv'), { force: true });
  }
} finally {
  rmSync(dir, { recursive: true, force: true });
}
console.log(`| log | input | rows | mode | peak RSS | time |\n|---|---:|---:|---|---:|---:|`);
for (const r of table) console.log(`| ${r.log} | ${r.inputMB} MB | ${r.rows.toLocaleString('en-US')} | \`${r.mode}\` | **${r.peakRssMB} MB** | ${r.wallS} s |`);
if (failed) {
  console.error(`a peak RSS exceeded ${boundMb} MB, a row was lost or a file failed`);
  process.exit(1);
}
