// Fuzz loop over the package's public JS API (issue 17): every exported
// function, constructor and method is called with random argument shapes
// (numbers of every kind, strings, typed arrays of every type, detached
// buffers, huge claimed lengths, Proxies with throwing or revoked traps,
// throwing getters, getters that re-enter the object, cycles, BigInts,
// Symbols, functions). Every throw must be an Error, never a wasm trap, and
// the module must be alive afterwards: a fresh detector still gives exactly
// the reference outputs, and every object in the pool still answers.
//
// Smoke run in `node --test tests/node/` (3 s); longer with
// FUZZ_API_SECONDS=600 node --test tests/node/fuzz-api.test.mjs. A failure
// prints the seed: FUZZ_API_SEED=<seed> replays it.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { createRequire } from 'node:module';
import { join, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';

const root = join(dirname(fileURLToPath(import.meta.url)), '..', '..');
const ng = createRequire(import.meta.url)(join(root, 'pkg'));

const SECONDS = Number(process.env.FUZZ_API_SECONDS ?? 3);
const SEED = Number(process.env.FUZZ_API_SEED ?? Math.floor(Math.random() * 2 ** 31));

// mulberry32: small, seedable.
function rng(seed) {
  let a = seed >>> 0;
  return () => {
    a = (a + 0x6d2b79f5) >>> 0;
    let t = a;
    t = Math.imul(t ^ (t >>> 15), t | 1);
    t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
    return ((t ^ (t >>> 14)) >>> 0) / 2 ** 32;
  };
}

// Fixtures: small valid inputs, so that random calls also reach the
// accepting paths.
const CSV_TEXT = ng.simulate('paper', 1).split('\n').slice(0, 400).join('\n') + '\n';
const CSV = new TextEncoder().encode(CSV_TEXT);
const LOG = ng.readLog(CSV);
const { label: _l, ...COLS } = LOG.columns;
const NAMES = ng.columnNames();
const SNAP = (() => { const d = new ng.Detector(); d.pushColumns(COLS); return d.snapshot(); })();
const TIGHT = ng.tightSimulate(1, 1, 3);
const TIGHT_CSV = TIGHT.csv.split('\n').slice(0, 40).join('\n') + '\n';
const CONFIG_FIELDS = ['method', 'tc', 'q', 'window', 'threshold', 'retrain', 'gpsPosSigma', 'gpsAltSigma', 'gpsVelSigma', 'baroSigma', 'accelNoise', 'cvAccelNoise', 'outageTimeout', 'maxCoast', 'dataGap', 'model'];

function reference() {
  const d = new ng.Detector();
  const r = d.pushColumns(COLS);
  const o = d.push({ t: COLS.t[COLS.t.length - 1] + 0.01, ax: 0, ay: 0, az: -9.81 });
  d.free();
  return [Array.from(r.status), Array.from(r.f), Array.from(r.r), o.f, o.status];
}
const REF = reference();

function detached(Ctor, n) {
  const a = new Ctor(n);
  structuredClone(a.buffer, { transfer: [a.buffer] });
  return a;
}

function makeGen(rand, pool) {
  const pick = (xs) => xs[Math.floor(rand() * xs.length)];
  const int = (n) => Math.floor(rand() * n);
  const numbers = [0, -0, 1, -1, 0.5, 7, 26, 100, 1e6, 2 ** 24 + 1, 2 ** 31, 2 ** 32, 2 ** 53, 1e308, -1e308, NaN, Infinity, -Infinity, 5e-324];
  const reenter = () => {
    const o = pick(pool);
    const keys = o ? Object.getOwnPropertyNames(Object.getPrototypeOf(Object.getPrototypeOf(o)) || {}) : [];
    const k = pick(keys.filter((x) => x !== 'constructor' && !x.startsWith('__')));
    return () => { if (o && typeof o[k] === 'function') return o[k](); return undefined; };
  };
  function value(depth = 0) {
    switch (int(depth > 2 ? 8 : 24)) {
      case 0: return undefined;
      case 1: return null;
      case 2: return pick(numbers);
      case 3: return rand() * 1000 - 500;
      case 4: return pick(['', 'paper', 'gps-only', 'anfis', 'x'.repeat(int(5000)), '\u0000\uffff', '{"tc":1}', 'step']);
      case 5: return pick([true, false]);
      case 6: return pick([Symbol('s'), 10n, -(2n ** 70n)]);
      case 7: return pick([() => 1, function f() { throw new Error('fn'); }, class {}]);
      case 8: { const a = new Float64Array(pick([0, 1, 7, 26, 33, int(300)])); for (let i = 0; i < a.length; i++) a[i] = rand() < 0.3 ? NaN : rand() * 100; return a; }
      case 9: { const r = new Float64Array(26).fill(NaN); r[0] = 1000 + rand() * 1e3; for (let i = 1; i < 26; i++) if (rand() < 0.3) r[i] = rand() * 10 - 5; return r; }
      case 10: return pick([new Uint8Array(int(64)).map(() => int(256)), CSV, CSV.subarray(0, int(CSV.length)), SNAP, SNAP.subarray(0, int(SNAP.length)), Buffer.from(CSV_TEXT.slice(0, 300))]);
      case 11: return pick([new Float32Array(26), new Int32Array(7), new Uint8ClampedArray(5), new BigInt64Array(2), new DataView(new ArrayBuffer(8)), new ArrayBuffer(16)]);
      case 12: return detached(pick([Float64Array, Uint8Array]), pick([0, 7, 26, 100]));
      case 13: return pick([{ length: 1e9 }, Object.assign([], { length: 2 ** 32 - 1 }), Object.assign([], { length: 27 }), { length: -1 }, { length: 7, 0: 1 }]);
      case 14: return Array.from({ length: int(30) }, () => (rand() < 0.7 ? rand() * 10 : value(depth + 1)));
      case 15: { const o = {}; for (let i = int(4); i > 0; i--) o[pick(CONFIG_FIELDS)] = value(depth + 1); return o; }
      case 16: { const o = {}; for (let i = int(6); i > 0; i--) o[pick(NAMES)] = rand() < 0.7 ? rand() * 100 : value(depth + 1); return o; }
      case 17: { const o = {}; for (let i = int(4); i > 0; i--) o[pick(NAMES)] = pick([value(depth + 1), new Float64Array(int(3)), COLS.t, detached(Float64Array, 3)]); return o; }
      case 18: { const k = pick([...CONFIG_FIELDS, ...NAMES, 'seeds', 'trainSeeds', 'length']); return Object.defineProperty({}, k, { enumerable: true, get() { throw pick([new Error('getter'), 'string', 42, null]); } }); }
      case 19: {
        const trap = pick(['get', 'ownKeys', 'getOwnPropertyDescriptor', 'getPrototypeOf', 'has']);
        return new Proxy(pick([{}, [], new Float64Array(26), { t: 1 }]), { [trap]() { throw new Error(`trap ${trap}`); } });
      }
      case 20: { const p = Proxy.revocable(pick([{}, []]), {}); p.revoke(); return p.proxy; }
      case 21: { const k = pick([...NAMES, ...CONFIG_FIELDS]); const f = reenter(); return Object.defineProperty({ t: 2000 }, k, { enumerable: true, get() { f(); return 1; } }); }
      case 22: { const o = { a: 1 }; o.self = o; return pick([o, { model: o }, [o]]); }
      default: return pick([{ valueOf() { throw new Error('valueOf'); } }, { toString() { throw new Error('toString'); } }, Object.create(Float64Array.prototype), Object.create(null)]);
    }
  }
  return { value, pick, int };
}

test(`fuzz the JS API for ${SECONDS} s (seed ${SEED}); every throw is an Error and the module stays alive`, () => {
  const rand = rng(SEED);
  const pool = [];
  // CompareRuns small enough to step (one flight, one method).
  const light = new WeakSet();
  const { value, pick, int } = makeGen(rand, pool);
  const args = (n) => Array.from({ length: int(n + 2) }, () => value());
  const guarded = (f) => {
    try { return f(); } catch { return undefined; }
  };
  const newObject = () => {
    switch (int(6)) {
      case 0: return new ng.Detector(rand() < 0.5 ? undefined : { tc: 1 + int(5), q: 10 + int(100) });
      case 1: return new ng.Auditor(CSV, undefined);
      case 2: return new ng.StreamAuditor(undefined, rand() < 0.5);
      case 3: return new ng.TightDetector(TIGHT.config);
      case 4: return ng.Detector.restore(SNAP);
      default: { const r = new ng.CompareRun({ seeds: 1, methods: ['chi2'] }); light.add(r); return r; }
    }
  };
  // Entry points with their arity. Slow ones (a simulation or training if
  // the arguments happen to be valid) get arguments that cannot be valid.
  // Never undefined, null or {}: a slow entry point would then run for real.
  const bad = () => pick([{ length: 1e9 }, Symbol('x'), 10n, 5, 'x', () => 1, new Proxy({}, { ownKeys() { throw new Error('k'); } }), Object.defineProperty({}, 'epochs', { enumerable: true, get() { throw new Error('g'); } })]);
  const functions = [
    ['auditBytes', () => ng.auditBytes(value(), value())],
    ['readLog', () => ng.readLog(value())],
    ['metrics', () => ng.metrics(value(), value(), value())],
    ['snapshotInfo', () => ng.snapshotInfo(value())],
    ['scenarioNames', () => ng.scenarioNames(...args(1))],
    ['columnNames', () => ng.columnNames(...args(1))],
    ['version', () => ng.version(...args(1))],
    ['wasmMemoryBytes', () => ng.wasmMemoryBytes(...args(1))],
    ['simulate', () => ng.simulate(pick([bad(), 'no-such-scenario']), value())],
    ['simulateScenario', () => ng.simulateScenario(pick([bad(), { name: 'x' }, { duration: -1 }]))],
    ['trainFromCsv', () => ng.trainFromCsv(pick([bad(), [value()], []]), pick([bad(), { tc: 0 }]))],
    ['tightSimulate', () => ng.tightSimulate(pick([0, 6, -1, NaN, value()]), value(), value())],
    ['tightGanTrain', () => ng.tightGanTrain(pick([{ epochs: 0 }, { trainSeeds: [] }, { alpha: 2 }, { hidden: 1e9 }, 5, 'x', bad()]), value())],
    ['new Detector', () => pool.push(new ng.Detector(value()))],
    ['new Auditor', () => pool.push(new ng.Auditor(value(), value()))],
    ['new StreamAuditor', () => pool.push(new ng.StreamAuditor(value(), value()))],
    ['new TightDetector', () => pool.push(new ng.TightDetector(value()))],
    ['new CompareRun', () => pool.push(new ng.CompareRun(pick([value(), { seeds: 0 }, { methods: ['nope'] }])))],
    ['Detector.restore', () => pool.push(ng.Detector.restore(value()))],
    ['TightDetector.withGanModel', () => pool.push(ng.TightDetector.withGanModel(value(), value()))],
  ];
  const slow = new Set(['step', 'finish']);
  let calls = 0;
  let rejected = 0;
  let slowest = [0, ''];
  const check = (what, f) => {
    calls++;
    const t0 = performance.now();
    try {
      f();
    } catch (e) {
      rejected++;
      assert.ok(e instanceof Error, `${what}: threw a non-Error ${String(e)} (seed ${SEED})`);
      assert.ok(!(e instanceof WebAssembly.RuntimeError), `${what}: wasm trap ${e.message} (seed ${SEED})`);
      assert.ok(!/unreachable|out of bounds|recursive use/.test(e.message), `${what}: ${e.message} (seed ${SEED})`);
    } finally {
      const ms = performance.now() - t0;
      if (ms > slowest[0]) slowest = [ms, what];
    }
  };
  const alive = () => {
    assert.deepEqual(reference(), REF, `a fresh detector's outputs changed (seed ${SEED})`);
    for (const o of pool) {
      check(`${o.constructor.name} liveness`, () => (o instanceof ng.Detector ? o.stats() : o instanceof ng.TightDetector ? o.pushCsv('') : o.rows?.()));
    }
  };
  for (let i = 0; i < 4; i++) pool.push(newObject());
  const end = Date.now() + SECONDS * 1000;
  let round = 0;
  while (Date.now() < end) {
    round++;
    if (pool.length > 40) guarded(() => pool.splice(int(pool.length), 1)[0].free());
    if (rand() < 0.05) pool.push(guarded(newObject) ?? new ng.Detector());
    if (rand() < 0.3) {
      const [name, f] = pick(functions);
      check(name, f);
    } else {
      const o = pick(pool);
      const proto = Object.getPrototypeOf(o);
      const methods = Object.getOwnPropertyNames(proto).filter((k) => k !== 'constructor' && !k.startsWith('__') && typeof proto[k] === 'function');
      let k = pick(methods);
      // A compare step or finish runs real flights: rarely.
      if (slow.has(k) && o instanceof ng.CompareRun && (!light.has(o) || rand() > 0.02)) k = 'addLog';
      if (k === 'free' && rand() > 0.05) k = 'stats' in o ? 'stats' : k;
      check(`${o.constructor.name}.${k}`, () => o[k](...args(3)));
      // Rows that are plainly valid as well, so the objects keep moving.
      if (o instanceof ng.Detector && rand() < 0.2) check('Detector.pushColumns (valid)', () => o.pushColumns({ t: Float64Array.of(1e4 + round) }));
    }
    if (round % 500 === 0) alive();
  }
  alive();
  for (const o of pool) guarded(() => o.free());
  const summary = `seed ${SEED}, ${calls} calls, ${rejected} rejected with an Error, ${round} rounds, slowest ${slowest[1]} ${slowest[0].toFixed(0)} ms, wasm memory ${ng.wasmMemoryBytes()} bytes`;
  assert.ok(calls >= 20 && rejected >= 5, summary);
  console.log(`fuzz-api: ${summary}`);
});
