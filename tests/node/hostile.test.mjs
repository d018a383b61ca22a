// Issue 17, the public JS API under hostile use (items 2-6, 12b): each bad
// call throws an Error (never a wasm RuntimeError), and afterwards the same
// detector and a fresh one still work, their outputs equal, number for
// number, to those of detectors that never saw the bad call.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { createRequire } from 'node:module';
import { join, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';

const root = join(dirname(fileURLToPath(import.meta.url)), '..', '..');
const ng = createRequire(import.meta.url)(join(root, 'pkg'));

const log = ng.readLog(new TextEncoder().encode(ng.simulate('paper', 1)));
const { label: _label, ...COLS } = log.columns;
const N = COLS.t.length;

/** Rows a..b of the paper flight as a columnar batch (copies). */
function part(a, b) {
  return Object.fromEntries(Object.entries(COLS).map(([k, v]) => [k, v.slice(a, b)]));
}

/** Rows a..b as plain sample objects (absent = NaN left out). */
function samples(a, b) {
  const out = [];
  for (let i = a; i < b; i++) {
    const s = {};
    for (const [k, v] of Object.entries(COLS)) if (!Number.isNaN(v[i])) s[k] = v[i];
    out.push(s);
  }
  return out;
}

/** Everything a detector says about rows a..b: batch path, then push path. */
function outputs(det, a, b) {
  const mid = Math.floor((a + b) / 2);
  const r = det.pushColumns(part(a, mid));
  const pushed = samples(mid, b).map((s) => det.push(s));
  return {
    status: [...r.status, ...pushed.map((o) => o.status)],
    f: [...r.f, ...pushed.map((o) => o.f)],
    r: [...r.r, ...pushed.map((o) => o.r)],
    c: [...r.c, ...pushed.map((o) => o.c)],
  };
}

/** Rows before the bad call (0-20 s at 50 Hz): the compared 2000 rows after
 * it (20-60 s) hold the paper flight's first fault (degraded GPS at 30-40 s),
 * whose flags the comparison needs. */
const WARM = 1000;

function expectError(f, pattern) {
  let thrown = null;
  try {
    f();
  } catch (e) {
    thrown = e;
  }
  assert.ok(thrown !== null, 'the call must throw');
  assert.ok(thrown instanceof Error, `an Error, got ${thrown}`);
  assert.ok(!(thrown instanceof WebAssembly.RuntimeError), `not a wasm trap: ${thrown.message}`);
  if (pattern) assert.match(thrown.message, pattern);
  return thrown;
}

/**
 * The acceptance check: `bad(det)` throws an Error (repeated `times`); the
 * same detector and a fresh one then give exactly what detectors that never
 * saw it give.
 */
function survives(bad, { times = 1, pattern, config } = {}) {
  const det = new ng.Detector(config);
  const ref = new ng.Detector(config);
  assert.deepEqual(outputs(det, 0, WARM), outputs(ref, 0, WARM));
  const rows = det.rowCount();
  for (let i = 0; i < times; i++) expectError(() => bad(det), pattern);
  assert.equal(det.rowCount(), rows, 'a rejected call consumes no row');
  const a = outputs(det, WARM, WARM + 2000);
  const b = outputs(ref, WARM, WARM + 2000);
  assert.equal(a.status.length, 2000);
  assert.deepEqual(a, b, 'the same detector continues as if the bad call never happened');
  assert.ok(a.status.some((s) => s === 1), 'the compared stretch has faults (the check can fail)');
  const fresh = outputs(new ng.Detector(config), 0, 3000);
  assert.deepEqual(fresh, outputs(new ng.Detector(config), 0, 3000), 'a fresh detector still works');
  ref.free();
  det.free();
}

function detachedF64(n) {
  const a = new Float64Array(n);
  structuredClone(a.buffer, { transfer: [a.buffer] });
  assert.equal(a.length, 0);
  return a;
}

test('item 2: a config whose getter or Proxy trap throws is a config Error, 500 times, and the module lives on', () => {
  const before = outputs(new ng.Detector(), 0, 3000);
  const hostile = [
    [{ get tc() { throw new Error('boom'); } }, /config\.tc: reading it threw: boom/],
    [{ get model() { throw 'not even an Error'; } }, /config\.model: reading it threw: not even an Error/],
    [new Proxy({}, { ownKeys() { throw new Error('trap'); } }), /config: listing its fields threw: trap/],
    [new Proxy({ tc: 5 }, { get() { throw new Error('get trap'); } }), /config\.\w+: reading it threw: get trap/],
    [{ model: { anfis: new Proxy({}, { ownKeys() { throw new Error('deep'); } }) } }, /config\.model\.anfis: listing its fields threw: deep/],
    [(() => { const p = Proxy.revocable({}, {}); p.revoke(); return p.proxy; })(), /config: listing its fields threw/],
    [{ tc: 10n }, /config\.tc: a bigint is not plain data/],
    [{ q: NaN }, /config\.q: must be a finite number, got NaN/],
  ];
  for (const [cfg, pattern] of hostile) {
    for (let i = 0; i < 500; i++) expectError(() => new ng.Detector(cfg), pattern);
  }
  // Through every entry point that takes a config.
  const bytes = new TextEncoder().encode(ng.simulate('gps-only', 2));
  const cfg = hostile[0][0];
  for (let i = 0; i < 200; i++) {
    expectError(() => ng.auditBytes(bytes, cfg), /config\.tc/);
    expectError(() => new ng.Auditor(bytes, cfg), /config\.tc/);
    expectError(() => new ng.StreamAuditor(cfg), /config\.tc/);
    expectError(() => ng.trainFromCsv([bytes], cfg), /config\.tc/);
    expectError(() => new ng.TightDetector(hostile[2][0]), /tight config: listing its fields threw/);
    expectError(() => new ng.CompareRun({ get seeds() { throw new Error('s'); } }), /compare options\.seeds: reading it threw/);
    expectError(() => ng.simulateScenario(hostile[3][0]), /scenario/);
  }
  // The module is alive and gives what it gave before.
  assert.equal(ng.readLog(bytes).rows, ng.readLog(bytes).rows);
  assert.equal(ng.simulate('paper', 1).length > 0, true);
  assert.deepEqual(outputs(new ng.Detector(), 0, 3000), before);
  survives((d) => new ng.Detector({ tc: 1, get q() { d.push({ t: 0 }); return 500; } }), { pattern: /config\.q: reading it threw/ });
  // A config read through getters that do not throw is read once per field.
  let reads = 0;
  const counted = { get tc() { reads++; return 100; } };
  const d = new ng.Detector(counted);
  assert.equal(reads, 1);
  assert.equal(d.config().tc, 100);
});

test('item 2: configs that only look hostile still check to the same config', () => {
  const viaProxy = new ng.Detector(new Proxy({ tc: 7, q: 300 }, {}));
  const plain = new ng.Detector({ tc: 7, q: 300 });
  assert.deepEqual(viaProxy.config(), plain.config());
  class Cfg { get window() { return 12; } }
  assert.equal(new ng.Detector(new Cfg()).config().window, 12);
  expectError(() => new ng.Detector({ bogus: 1 }), /config\.bogus: unknown field/);
});

test('item 3: a detached buffer to pushColumns is an Error, 1100 times, detector not left borrowed', () => {
  survives((d) => d.pushColumns({ t: detachedF64(8) }), { times: 1100, pattern: /column 't': unreadable \(detached buffer\?\)/ });
  survives((d) => { const b = part(2000, 2100); b.ax = detachedF64(100); d.pushColumns(b); }, { pattern: /column 'ax'/ });
  survives((d) => d.pushColumns({ t: new Float64Array([1e9]), get baro() { throw new Error('getter'); } }), { times: 300, pattern: /column 'baro': reading it threw: getter/ });
  survives((d) => d.pushColumns({ t: new Proxy(new Float64Array(3), {}) }), { pattern: /column 't': must be a Float64Array/ });
  survives((d) => d.pushColumns({ t: Object.create(Float64Array.prototype) }), { pattern: /column 't': must be a Float64Array/ });
  survives((d) => d.pushRow(detachedF64(ng.columnNames().length)), { times: 300, pattern: /unreadable/ });
  survives((d) => ng.metrics(detachedF64(1), new Float64Array(1), new Uint8Array(1)) && d.rowCount(), { pattern: /metrics: t: unreadable/ });
});

test('item 4: pushRowInto with a wrong out throws before it consumes the row', () => {
  const good = () => {
    const r = new Float64Array(ng.columnNames().length).fill(NaN);
    r[0] = COLS.t[1999] + 0.001;
    return r;
  };
  for (const [out, pattern] of [
    [[0, 0, 0, 0, 0, 0, 0], /out: must be a Float64Array/],
    [new Float32Array(7), /out: must be a Float64Array/],
    [new Float64Array(6), /at least 7 elements, got 6/],
    [detachedF64(7), /got 0 \(a detached buffer has 0\)/],
    [{ length: 7 }, /out: must be a Float64Array/],
    [null, /out: must be a Float64Array/],
  ]) {
    survives((d) => d.pushRowInto(good(), out), { times: 50, pattern });
  }
  // A good out still works and agrees with push.
  const a = new ng.Detector();
  const b = new ng.Detector();
  const out = new Float64Array(7);
  for (const s of samples(0, 500)) {
    const r = new Float64Array(ng.columnNames().length).fill(NaN);
    ng.columnNames().forEach((c, i) => { if (c in s) r[i] = s[c]; });
    a.pushRowInto(r, out);
    const o = b.push(s);
    assert.deepEqual([...out], [o.t, o.status, o.f, o.r, o.c, o.kind, o.gpsEpoch ? 1 : 0]);
  }
});

test('item 5: a huge length is an Error naming the limit, not an abort', () => {
  survives((d) => d.pushRow({ length: 1e9 }), { times: 20, pattern: /pushRow: row: must be a Float64Array or an array of numbers/ });
  survives((d) => d.pushRow(Object.assign([], { length: 1e9 })), { times: 20, pattern: new RegExp(`length 1000000000 exceeds the limit of ${ng.columnNames().length}`) });
  survives((d) => d.pushRow(new Float64Array(1e6)), { pattern: new RegExp(`1000000 elements exceed the limit of ${ng.columnNames().length}`) });
  survives((d) => d.pushRowInto({ length: 1e9 }, new Float64Array(7)), { pattern: /pushRowInto: row/ });
  survives(() => ng.metrics(Object.assign([], { length: 2 ** 31 }), [], []), { pattern: /exceeds the limit/ });
  survives(() => ng.readLog(Object.assign([], { length: 2 ** 32 - 1 })), { pattern: /readLog: bytes: length \d+ exceeds the limit/ });
  survives(() => ng.snapshotInfo({ length: 1e9 }), { pattern: /snapshotInfo: snapshot: must be a Uint8Array/ });
  survives(() => ng.simulate('x'.repeat(1e6), 1), { pattern: /simulate: name: 1000000 characters exceed the limit of 4096/ });
});

test('item 6: a 10 M-row batch runs in bounded wasm memory; beyond the limit an Error names it', () => {
  const n = 10_000_000;
  const t = new Float64Array(n);
  for (let i = 0; i < n; i++) t[i] = i * 0.01;
  const d = new ng.Detector();
  const before = ng.wasmMemoryBytes();
  const r = d.pushColumns({ t });
  assert.equal(r.status.length, n);
  assert.equal(d.rowCount(), n);
  // 16 MB of growth at most (the chunk scratch is ~1 MB), not 4 GB.
  assert.ok(ng.wasmMemoryBytes() - before <= 16 << 20, `wasm memory grew by ${ng.wasmMemoryBytes() - before} bytes`);
  d.free();
  survives((det) => det.pushColumns({ t: new Float64Array(2 ** 24 + 1) }), { pattern: /16777217 elements exceed the limit of 16777216 per call/ });
  // Across chunk borders the batch path equals the row-by-row path.
  const a = new ng.Detector();
  const b = new ng.Detector();
  const big = a.pushColumns(part(0, N));
  const rows = samples(0, N).map((s) => b.push(s));
  assert.deepEqual([...big.f], rows.map((o) => o.f));
  assert.deepEqual([...big.status], rows.map((o) => o.status));
  // A bad row in a later chunk rejects the whole batch: nothing is pushed.
  const bad = part(0, N);
  bad.t[N - 10] = bad.t[N - 11] - 1;
  const c = new ng.Detector();
  expectError(() => c.pushColumns(bad), /time goes backwards.*batch index 12490/);
  assert.equal(c.rowCount(), 0);
});

test('item 9: {tc: 1, q: 100000} is accepted and retrains', () => {
  const d = new ng.Detector({ tc: 1, q: 100000 });
  d.pushColumns(part(0, N));
  assert.ok(d.stats().retrains >= 1, JSON.stringify(d.stats()));
});

test('item 12b: a push re-entered from a sample getter throws, and the outer row is not replaced', () => {
  const [outer, inner] = samples(2000, 2002);
  // The getter lets the re-entry error through: the outer push throws it.
  survives((d) => d.push({ ...outer, get baro() { return d.push(inner).f; } }), { times: 20, pattern: /Detector\.push: called while Detector\.push is running on the same object/ });
  survives((d) => d.push({ ...outer, get baro() { d.pushColumns(part(2001, 2002)); return 1; } }), { pattern: /Detector\.pushColumns: called while Detector\.push is running/ });
  survives((d) => d.pushColumns({ ...part(2000, 2002), get ax() { d.push(inner); return undefined; } }), { pattern: /column 'ax': reading it threw: Detector\.push: called while Detector\.pushColumns is running/ });
  // The getter swallows the re-entry error: the outer row is pushed as given.
  const d = new ng.Detector();
  const ref = new ng.Detector();
  outputs(d, 0, 2000);
  outputs(ref, 0, 2000);
  let refused = null;
  const o = d.push({ ...outer, get t() { try { d.push(inner); } catch (e) { refused = e; } return outer.t; } });
  assert.match(refused.message, /called while Detector\.push is running/);
  assert.deepEqual(o, ref.push(outer));
  assert.deepEqual(outputs(d, 2001, 3000), outputs(ref, 2001, 3000));
});

test('a freed object, a double free and a method on the wrong object are Errors (no table leak)', () => {
  const d = new ng.Detector();
  d.free();
  d.free();
  for (let i = 0; i < 3000; i++) {
    expectError(() => d.pushRow(new Float64Array(26)), /this Detector was freed/);
    expectError(() => d.push({ t: 1 }), /this Detector was freed/);
  }
  expectError(() => ng.Detector.prototype.pushColumns.call({}, { t: new Float64Array(1) }), /'this' is not a Detector/);
  survives((det) => det.pushColumns({ get t() { det.free(); return new Float64Array(1); } }), { pattern: /Detector\.free: called while Detector\.pushColumns is running/ });
  // A restored detector is guarded and fast like a new one.
  const a = new ng.Detector();
  outputs(a, 0, 1000);
  const b = ng.Detector.restore(a.snapshot());
  assert.deepEqual(outputs(a, 1000, 2000), outputs(b, 1000, 2000));
  b.free();
  expectError(() => b.push({ t: 1 }), /freed/);
});

test('a sample whose getter or Proxy trap throws is an Error naming the row and field', () => {
  survives((d) => d.push({ t: 1e6, get ax() { throw new Error('bad sensor'); } }), { times: 300, pattern: /sample: field 'ax': reading it threw: bad sensor/ });
  survives((d) => d.push(new Proxy({ t: 1e6 }, { ownKeys() { throw 42; } })), { pattern: /sample: listing its fields: reading it threw: 42/ });
  survives((d) => d.push({ t: 'soon' }), { pattern: /field 't': must be a number/ });
});
