// Contract tests (../shared/contract/README.md §2, §3) over the built pkg/.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { createRequire } from 'node:module';
import { execFileSync, spawnSync } from 'node:child_process';
import { mkdtempSync, readFileSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';

const root = join(dirname(fileURLToPath(import.meta.url)), '..', '..');
const require = createRequire(import.meta.url);
const ng = require(join(root, 'pkg'));
const cli = join(root, 'pkg', 'bin', 'navguard.mjs');
const tmp = mkdtempSync(join(tmpdir(), 'navguard-'));

function columns(name, seed) {
  const log = ng.readLog(new TextEncoder().encode(ng.simulate(name, seed)));
  const { label, ...cols } = log.columns;
  return { cols, label };
}

test('push and pushColumns give the same statuses and F for the same rows', () => {
  const { cols } = columns('frozen', 4);
  const a = new ng.Detector({ tc: 50 });
  const out = a.pushColumns(cols);
  const b = new ng.Detector({ tc: 50 });
  const names = Object.keys(cols);
  const n = cols.t.length;
  assert.equal(out.status.length, n);
  let faults = 0;
  for (let i = 0; i < n; i++) {
    const s = {};
    for (const k of names) if (!Number.isNaN(cols[k][i])) s[k] = cols[k][i];
    const r = b.push(s);
    assert.equal(r.status, out.status[i], `row ${i}`);
    assert.equal(Object.is(r.f, out.f[i]), true, `row ${i}: f ${r.f} vs ${out.f[i]}`);
    faults += r.status;
  }
  assert.ok(faults > 0, 'the frozen-GPS scenario raised no fault at all');
  a.free(); b.free();
});

test('pushColumns in several batches equals one batch', () => {
  const { cols } = columns('noise', 5);
  const whole = new ng.Detector({}).pushColumns(cols);
  const det = new ng.Detector({});
  const n = cols.t.length, cut = [0, 1, 777, 5000, n];
  const parts = [];
  for (let j = 0; j + 1 < cut.length; j++) {
    const b = {};
    for (const [k, v] of Object.entries(cols)) b[k] = v.subarray(cut[j], cut[j + 1]);
    parts.push(...det.pushColumns(b).status);
  }
  assert.deepEqual(Uint8Array.from(parts), whole.status);
});

test('snapshot, Detector.restore and continue equals an uninterrupted run (object push)', () => {
  const { cols } = columns('step', 6);
  const names = Object.keys(cols);
  const n = cols.t.length;
  const row = (i) => {
    const s = {};
    for (const k of names) if (!Number.isNaN(cols[k][i])) s[k] = cols[k][i];
    return s;
  };
  const whole = new ng.Detector({ tc: 20 });
  const ref = [];
  for (let i = 0; i < n; i++) ref.push(whole.push(row(i)));
  let det = new ng.Detector({ tc: 20 });
  const got = [];
  for (const cut of [Math.floor(n / 3), Math.floor((2 * n) / 3), n]) {
    while (got.length < cut) got.push(det.push(row(got.length)));
    const snap = det.snapshot();
    assert.ok(snap instanceof Uint8Array && snap.length > 1000);
    assert.equal(ng.snapshotInfo(snap).version, 33);
    det.free();
    det = ng.Detector.restore(snap);
    assert.ok(det instanceof ng.Detector);
    assert.equal(det.rowCount(), cut);
  }
  for (let i = 0; i < n; i++) {
    assert.equal(got[i].status, ref[i].status, `row ${i}`);
    assert.ok(Object.is(got[i].f, ref[i].f), `row ${i}: f ${got[i].f} vs ${ref[i].f}`);
  }
  assert.ok(ref.some((r) => r.status === 1), 'the step scenario raised no fault');
  assert.throws(() => ng.Detector.restore(new Uint8Array([1, 2, 3])), /snapshot/);
  whole.free(); det.free();
});

test('bad input throws an Error naming field and row; the detector stays usable', () => {
  const det = new ng.Detector();
  det.push({ t: 0, lat: 31.94, lon: 118.79, alt: 20 });
  const cases = [
    [{ t: NaN }, /'t'/],
    [{ t: -1 }, /row 1.*'t'.*backwards/],
    [{ t: 1, lat: 31.9 }, /'lon'/],
    [{ t: 1, lat: 95, lon: 1, alt: 1 }, /'lat'/],
    [{ t: 1, vn: 'fast', ve: 0, vd: 0 }, /'vn'.*number/],
    [{ t: 1, ax: Infinity, ay: 0, az: 0 }, /'ax'/],
    [{ t: 1, baro: 1e300 }, /'baro'/],
    [{ t: 1, qw: 5, qx: 0, qy: 0, qz: 0 }, /'qw'/],
    ['not an object', /plain object/],
  ];
  for (const [s, re] of cases) {
    assert.throws(() => det.push(s), (e) => e instanceof Error && re.test(e.message), JSON.stringify(s));
  }
  assert.throws(() => det.pushColumns({ t: new Float64Array([1, 2]), baro: new Float64Array([1]) }), /'baro'.*length/);
  assert.throws(() => det.pushColumns({ t: [1, 2] }), /Float64Array/);
  assert.throws(() => det.pushColumns({ t: new Float64Array([2, 1]) }), /backwards.*batch index 1/);
  assert.throws(() => new ng.Detector({ tc: 0 }), /config\.tc.*got 0/);
  assert.throws(() => new ng.Detector({ windw: 5 }), /config\.windw.*unknown/);
  assert.throws(() => new ng.Detector({ method: 'magic' }), /config\.method/);
  const ok = det.push({ t: 0.1, lat: 31.94, lon: 118.79, alt: 20 });
  assert.equal(ok.status, 0);
  assert.equal(det.stats().rows, 2, 'rejected rows must not count, accepted ones must stay');
});

test('audit command on a simulated CSV: JSON report, per-sample CSV, metrics', () => {
  const csv = join(tmp, 'step.csv');
  execFileSync('node', [cli, 'simulate', 'step', '--seed', '6', '--out', csv]);
  const per = join(tmp, 'per.csv');
  const out = execFileSync('node', [cli, 'audit', csv, '--json', '--per-sample', per], { encoding: 'utf8' });
  const rep = JSON.parse(out);
  assert.equal(rep.file, csv);
  assert.equal(rep.format, 'csv');
  assert.equal(rep.rows, 12500);
  assert.ok(rep.faults.length >= 1 && rep.faults.some((f) => f.end >= 120 && f.start <= 135), JSON.stringify(rep.faults));
  for (const k of ['accuracy', 'falseAlarmRate', 'misdetectionRate', 'precision', 'recall', 'meanDetectionDelay']) assert.ok(k in rep.metrics, k);
  const lines = readFileSync(per, 'utf8').trim().split('\n');
  assert.equal(lines[0], 't,status,f,r,c,kind,rPn,rPe,rPd,rVn,rVe,rVd,rBaro,reconciled');
  // The last column is the whole-log verdict: 1 exactly on the rows inside
  // the report's reconciled intervals.
  const inRec = (t) => rep.reconciled.some((f) => f.start <= t && t <= f.end);
  const rows = lines.slice(1).map((l) => l.split(','));
  assert.ok(rows.filter((c) => c[13] === '1').length >= 700);
  assert.deepEqual(rows.filter((c) => (c[13] === '1') !== inRec(+c[0])), []);
  // A GPS epoch inside the 10 m step carries a large position residual.
  const inside = lines.slice(1).map((l) => l.split(',')).filter((c) => +c[0] >= 121 && +c[0] < 122 && c[6] !== '');
  assert.ok(inside.length >= 5 && inside.every((c) => Math.hypot(+c[6], +c[7]) > 5), inside.slice(0, 3).join(' | '));
  assert.equal(lines.length, 12501);
});

test('audit exits 2 with a one-line reason for unreadable files, 0 otherwise', () => {
  const missing = spawnSync('node', [cli, 'audit', join(tmp, 'nope.csv')], { encoding: 'utf8' });
  assert.equal(missing.status, 2);
  assert.match(missing.stderr.trim(), /^navguard: .*no such file$/);
  const garbage = join(tmp, 'garbage.bin');
  writeFileSync(garbage, Buffer.from([0x00, 0xff, 0x13, 0x37, 0x42, 0x00]));
  const g = spawnSync('node', [cli, 'audit', garbage], { encoding: 'utf8' });
  assert.equal(g.status, 2);
  assert.equal(g.stderr.trim().split('\n').length, 1);
  const semi = join(tmp, 'semi.csv');
  writeFileSync(semi, 't;lat;lon\n0;1;2\n');
  const s = spawnSync('node', [cli, 'audit', semi], { encoding: 'utf8' });
  assert.equal(s.status, 2);
  assert.match(s.stderr, /delimiter/);
});

test('compare: every requested method over the battery; --update-readme rewrites only the marked table', () => {
  const out = execFileSync(process.execPath, [cli, 'compare', '--seeds', '1', '--methods', 'anfis,chi2', '--json'], { encoding: 'utf8' });
  const c = JSON.parse(out);
  assert.deepEqual(c.methods.map((m) => m.method), ['anfis', 'chi2']);
  assert.equal(c.flights, 15);
  const [anfis, chi2] = c.methods;
  assert.ok(anfis.metrics.tp > 0 && anfis.metrics.f2 > 0.5, JSON.stringify(anfis.metrics));
  assert.equal(anfis.kinds.find((k) => k.group === 'outage').detected, 6);
  assert.notEqual(anfis.metrics.f2, chi2.metrics.f2, 'two methods gave identical F2: is config.method applied?');
  const md = join(tmp, 'README.md');
  writeFileSync(md, 'intro\n<!-- compare:begin (generated by `navguard compare`; do not edit) -->\nold table\n<!-- compare:end -->\noutro\n');
  execFileSync(process.execPath, [cli, 'compare', '--seeds', '1', '--methods', 'gate', '--update-readme', md]);
  const text = readFileSync(md, 'utf8');
  assert.ok(text.startsWith('intro\n') && text.endsWith('<!-- compare:end -->\noutro\n'), text);
  assert.ok(!text.includes('old table') && /\| \*\*gate\*\* \| 0\.\d{4} \|/.test(text), text);
  const bad = spawnSync(process.execPath, [cli, 'compare', '--methods', 'magic'], { encoding: 'utf8' });
  assert.equal(bad.status, 2);
  assert.match(bad.stderr, /magic/);
});

test('compare --battery: every method on the same flights of the randomised battery (issue 14)', () => {
  const out = execFileSync(process.execPath, [cli, 'compare', '--battery', 'eval', '--flights', '3', '--methods', 'anfis,gate', '--json'], { encoding: 'utf8' });
  const c = JSON.parse(out);
  assert.equal(c.split, 'eval');
  assert.equal(c.flights, 3);
  assert.deepEqual(c.methods.map((m) => m.method), ['anfis', 'gate']);
  const n = (m) => m.metrics.tp + m.metrics.fp + m.metrics.tn + m.metrics.fn;
  assert.ok(n(c.methods[0]) > 100 && n(c.methods[0]) === n(c.methods[1]), JSON.stringify(c.methods.map((m) => m.metrics)));
  // Eval flight 0 has a GPS outage: every method flags it.
  for (const m of c.methods) assert.ok(m.kinds.find((k) => k.group === 'outage').detected >= 1, JSON.stringify(m.kinds));
  const md = execFileSync(process.execPath, [cli, 'compare', '--battery', 'tune', '--flights', '1', '--methods', 'anfis'], { encoding: 'utf8' });
  assert.match(md, /^1 flights of the randomised battery's tune split/);
  for (const [args, re] of [[['--battery', 'eval', '--seeds', '2'], /--seeds does not go with --battery/], [['--flights', '2'], /--flights goes with --battery/], [['--battery', 'holdout'], /compare options\.battery/]]) {
    const bad = spawnSync(process.execPath, [cli, 'compare', ...args], { encoding: 'utf8' });
    assert.equal(bad.status, 2, bad.stderr);
    assert.match(bad.stderr, re);
  }
});

test('TypeScript types describe config, sample and results (no any)', () => {
  const dts = readFileSync(join(root, 'pkg', 'index.d.ts'), 'utf8');
  assert.match(dts, /push\(sample: NavSample\): PushResult/);
  assert.match(dts, /pushColumns\(columns: NavColumns\): ColumnsResult/);
  // Optional arguments are optional (issue 16): `new Detector()`, `auditBytes(bytes)`.
  assert.match(dts, /constructor\(config\?: DetectorConfig\)/);
  assert.match(dts, /export function auditBytes\(bytes: Uint8Array, config\?: DetectorConfig\): AuditResult/);
  // The package's internals are not API.
  assert.doesNotMatch(dts, /__memory|__ioOffset|__pushIo|initSync|Symbol\.dispose/);
  assert.match(dts, /export interface DetectorConfig/);
  assert.doesNotMatch(dts.split('\n').filter((l) => /push|constructor|auditBytes/.test(l)).join('\n'), /\bany\b/);
});
