// Issue 17 regressions over the built pkg/: binary logs are streamed in
// bounded wasm memory, a ULog that redefines its formats is read with the
// current layout, info messages are capped with a warning, and `audit DIR`
// follows symlinks (and lists broken ones) and gives the single-file reports.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { createRequire } from 'node:module';
import { execFileSync } from 'node:child_process';
import { readFileSync, mkdtempSync, mkdirSync, symlinkSync, copyFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';

const root = join(dirname(fileURLToPath(import.meta.url)), '..', '..');
const ng = createRequire(import.meta.url)(join(root, 'pkg'));
const cli = join(root, 'pkg', 'bin', 'navguard.mjs');
const shared = join(root, '..', 'shared', 'data');

const le16 = (v) => { const b = Buffer.alloc(2); b.writeUInt16LE(v); return b; };
const msg = (type, payload) => Buffer.concat([le16(payload.length), Buffer.from(type), payload]);
const header = () => { const h = Buffer.alloc(16); Buffer.from([0x55, 0x4c, 0x6f, 0x67, 0x01, 0x12, 0x35, 0x01]).copy(h); return h; };
const add = (id, name) => msg('A', Buffer.concat([Buffer.from([0]), le16(id), Buffer.from(name)]));
const data = (id, body) => msg('D', Buffer.concat([le16(id), body]));

/** `n` 9-byte sensor_combined messages, 200 µs apart, a piece at a time. */
function* tinyUlog(n, per = 200000) {
  yield Buffer.concat([header(), msg('F', Buffer.from('sensor_combined:uint32_t timestamp')), add(0, 'sensor_combined')]);
  for (let k = 0; k < n; k += per) {
    const m = Math.min(per, n - k), b = Buffer.alloc(9 * m);
    for (let i = 0; i < m; i++) {
      const o = 9 * i;
      b.writeUInt16LE(6, o); b[o + 2] = 0x44; b.writeUInt16LE(0, o + 3); b.writeUInt32LE((k + i + 1) * 200, o + 5);
    }
    yield b;
  }
}

test('a 36 MB tiny-message ULog streams through StreamAuditor in flat wasm memory', () => {
  // 4 M rows: held whole as rows this was 830 MB; the red team's 144 MB
  // version trapped with `unreachable`.
  const n = 4_000_000;
  const run = new ng.StreamAuditor(undefined, false);
  let peak = 0, start = null, pass = 0;
  do {
    pass++;
    for (const piece of tinyUlog(n)) {
      run.feed(piece);
      start ??= ng.wasmMemoryBytes();
      peak = Math.max(peak, ng.wasmMemoryBytes());
    }
  } while (run.endPass());
  const { report } = run.finish();
  run.free();
  assert.equal(pass, 2);
  assert.equal(report.rows, n);
  assert.equal(report.format, 'ulog');
  // The reorder buffer (65,536 rows, 14 MB) and one 1.8 MB piece at most.
  assert.ok(peak - start < 40e6, `wasm memory grew by ${((peak - start) / 1e6).toFixed(1)} MB`);
});

test('a ULog that redefines its format 200 times is read with the current layout', () => {
  const parts = [header()];
  let t = 0n;
  for (let r = 0; r < 200; r++) {
    const extra = 1 + (r % 5);
    const fields = Array.from({ length: extra }, (_, k) => `float x${k};`).join('');
    parts.push(msg('F', Buffer.from(`sensor_combined:uint64_t timestamp;float[3] gyro_rad;${fields}`)), add(r, 'sensor_combined'));
    for (let i = 0; i < 100; i++) {
      t += 1000n;
      const body = Buffer.alloc(8 + 12 + 4 * extra);
      body.writeBigUInt64LE(t);
      parts.push(data(r, body));
    }
  }
  const { report } = ng.auditBytes(Buffer.concat(parts), {});
  assert.equal(report.rows, 20000);
  assert.ok(!report.warnings.some((w) => w.includes('wrong size')), report.warnings.join('\n'));
  const log = ng.readLog(Buffer.concat(parts));
  assert.deepEqual(log.topicCounts, [['sensor_combined', 20000]]);
});

test('info messages are capped with a warning; the JSON report stays small', () => {
  const parts = [header(), msg('F', Buffer.from('sensor_combined:uint64_t timestamp;float[3] gyro_rad'))];
  for (let i = 0; i < 20000; i++) {
    const key = Buffer.from(`char[300] k${i}`);
    parts.push(msg('I', Buffer.concat([Buffer.from([key.length]), key, Buffer.alloc(300, 0x01)])));
  }
  parts.push(add(0, 'sensor_combined'));
  for (let i = 1; i <= 100; i++) { const b = Buffer.alloc(20); b.writeBigUInt64LE(BigInt(i * 4000)); parts.push(data(0, b)); }
  const { report } = ng.auditBytes(Buffer.concat(parts), {});
  assert.equal(report.meta.filter(([k]) => k.startsWith('k')).length, 256);
  assert.ok(report.meta.every(([, v]) => v.length <= 256));
  assert.ok(report.warnings.includes(`${20000 - 256} info messages not kept in meta (at most 256 are)`), report.warnings.join('\n'));
  assert.ok(JSON.stringify(report).length < 1e6);
});

test('audit DIR follows symlinks, lists broken ones and matches single-file audits', () => {
  const tmp = mkdtempSync(join(tmpdir(), 'navguard-dir-'));
  const d = join(tmp, 'logs');
  mkdirSync(d);
  mkdirSync(join(tmp, 'sub'));
  const ulg = join(shared, 'px4', 'sample_log_small.ulg');
  const bin = join(shared, 'ardupilot', 'Loiter_RTL.bin');
  copyFileSync(join(shared, 'csv', 'ansfl_phantom4_rtk_clean.csv'), join(d, 'a.csv'));
  symlinkSync(ulg, join(d, 'b.ulg'));
  symlinkSync(bin, join(d, 'c.bin'));
  symlinkSync(join(tmp, 'gone.ulg'), join(d, 'd-broken.ulg'));
  symlinkSync(join(tmp, 'sub'), join(d, 'e-folder'));
  const summaryFile = join(tmp, 'summary.json');
  execFileSync('node', [cli, 'audit', d, '--json', '--jobs', '2', '--summary', summaryFile], { encoding: 'utf8' });
  const s = JSON.parse(readFileSync(summaryFile, 'utf8'));
  // The walk follows links: into the (empty) linked folder too; a broken
  // link is listed as skipped, with why.
  assert.equal(s.files, 3);
  assert.equal(s.failed, 0);
  assert.deepEqual(s.skipped, [{ file: join(d, 'd-broken.ulg'), why: 'no such file or directory' }]);
  const by = Object.fromEntries(s.logs.map((r) => [r.file.slice(d.length + 1), r]));
  for (const [name, src] of [['a.csv', join(d, 'a.csv')], ['b.ulg', ulg], ['c.bin', bin]]) {
    const single = JSON.parse(execFileSync('node', [cli, 'audit', src, '--json'], { encoding: 'utf8' }));
    const r = by[name];
    assert.equal(r.format, single.format, name);
    assert.equal(r.durationS, single.durationS, name);
    assert.equal(r.flaggedGpsEpochFraction, single.flaggedGpsEpochFraction, name);
    assert.deepEqual(r.warnings, single.warnings, name);
    assert.equal(r.residualFaults, single.faults.filter((f) => f.kind === 'residual').length, name);
  }
  // Single-file mode streams binary logs too: same report as auditBytes.
  const whole = ng.auditBytes(readFileSync(bin), {}).report;
  const single = JSON.parse(execFileSync('node', [cli, 'audit', bin, '--json'], { encoding: 'utf8' }));
  assert.equal(single.rows, whole.rows);
  assert.deepEqual(single.faults, whole.faults);
});
