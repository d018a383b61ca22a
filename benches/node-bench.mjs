// wasm benchmarks over the built pkg/: push and pushColumns throughput, the
// whole paper scenario with retraining, .wasm size, and memory over a long
// stream. Run: npm run bench (builds first).
import { createRequire } from 'node:module';
import { statSync, readdirSync, readFileSync } from 'node:fs';
import { join, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';
import { performance } from 'node:perf_hooks';

const root = join(dirname(fileURLToPath(import.meta.url)), '..');
const ng = createRequire(import.meta.url)(join(root, 'pkg'));
const log = ng.readLog(new TextEncoder().encode(ng.simulate('paper', 1)));
const { label, ...cols } = log.columns;
const n = cols.t.length;

function best(k, f) {
  let b = Infinity;
  for (let i = 0; i < k; i++) { const t0 = performance.now(); f(); b = Math.min(b, performance.now() - t0); }
  return b;
}

const whole = best(15, () => { const d = new ng.Detector({ tc: 100 }); d.pushColumns(cols); d.free(); });
const noRetrain = best(25, () => { const d = new ng.Detector({ retrain: false }); d.pushColumns(cols); d.free(); });
const names = Object.keys(cols);
const objs = Array.from({ length: n }, (_, i) => { const s = {}; for (const k of names) if (!Number.isNaN(cols[k][i])) s[k] = cols[k][i]; return s; });
const push = best(5, () => { const d = new ng.Detector({ retrain: false }); for (const s of objs) d.push(s); d.free(); });

// Long stream: 10 million rows in batches of the paper scenario with time shifted.
const det = new ng.Detector({});
const batch = {};
for (const k of names) batch[k] = new Float64Array(cols[k]);
const mem0 = ng.__wasm ? 0 : 0;
const reps = Math.ceil(10_000_000 / n);
let memStart = 0, memEnd = 0;
const wasmMem = () => (ng.wasmMemoryBytes ? ng.wasmMemoryBytes() : process.memoryUsage().arrayBuffers);
const t0 = performance.now();
for (let r = 0; r < reps; r++) {
  for (let i = 0; i < n; i++) batch.t[i] = cols.t[i] + r * 250.0;
  det.pushColumns(batch);
  if (r === 10) memStart = wasmMem();
}
memEnd = wasmMem();
const longMs = performance.now() - t0;

// Log parsing in wasm (readLog: parse plus column extraction), MB/s per file.
const parse = {};
for (const dir of ['px4', 'ardupilot']) {
  const d = join(root, '..', 'shared', 'data', dir);
  for (const f of readdirSync(d)) {
    const bytes = readFileSync(join(d, f));
    if (bytes.length < 100000) continue;
    const ms = best(5, () => ng.readLog(bytes));
    parse[f] = Math.round(bytes.length / 1e6 / (ms / 1000));
  }
}

// Snapshot and restore of a detector that has run the paper scenario.
const sd = new ng.Detector({});
sd.pushColumns(cols);
const snap = sd.snapshot();
const snapshotMs = best(50, () => sd.snapshot());
const restoreMs = best(50, () => ng.Detector.restore(snap).free());
sd.free();
// GAN-FDSR (tightly coupled, Env 1, 20 m step, 420 GNSS epochs of 9
// satellites, 8,400 rows): per-epoch inference against FDI, and in-wasm
// training of the default-size model (2 + 2 flights).
const tsim = ng.tightSimulate(1, 1, 7);
const tightRows = (strategy) => best(3, () => new ng.TightDetector({ ...tsim.config, strategy }).pushCsv(tsim.csv));
const gnssEpochs = 420;
const fdiMs = tightRows('fdi');
const ganMs = tightRows('gan');
const trainEpochs = 5;
let t = performance.now();
const trained = ng.tightGanTrain({ epochs: trainEpochs });
const ganTrainMs = performance.now() - t;

// One .wasm per module (core, lab); an older single-module build has navguard_bg.wasm.
const wasmFiles = readdirSync(join(root, 'pkg')).filter((f) => f.endsWith('.wasm'));
const wasmModules = Object.fromEntries(wasmFiles.map((f) => [f, statSync(join(root, 'pkg', f)).size]));
const wasmSize = Object.values(wasmModules).reduce((a, b) => a + b, 0);
const fmt = (x) => Math.round(x).toLocaleString('en-US');
console.log(JSON.stringify({
  rows: n,
  paperScenarioTc100Ms: +whole.toFixed(2),
  pushColumnsRowsPerS: Math.round(n / (noRetrain / 1000)),
  pushRowsPerS: Math.round(n / (push / 1000)),
  longStreamRows: reps * n,
  longStreamRowsPerS: Math.round((reps * n) / (longMs / 1000)),
  memoryBytesAfter10Batches: memStart,
  memoryBytesAtEnd: memEnd,
  wasmBytes: wasmSize,
  wasmModules,
  readLogMBPerS: parse,
  snapshotBytes: snap.length,
  snapshotMs: +snapshotMs.toFixed(3),
  restoreMs: +restoreMs.toFixed(3),
  tightFdiMsPerGnssEpoch: +(fdiMs / gnssEpochs).toFixed(3),
  tightGanMsPerGnssEpoch: +(ganMs / gnssEpochs).toFixed(3),
  ganTrainMs: Math.round(ganTrainMs),
  ganTrainEpochs: trainEpochs,
  ganTrainWindows: trained.trainWindows,
}, null, 2));
console.error(`pushColumns ${fmt(n / (noRetrain / 1000))} rows/s, push ${fmt(n / (push / 1000))} rows/s, paper scenario ${whole.toFixed(1)} ms, .wasm ${Object.entries(wasmModules).map(([f, b]) => `${f} ${fmt(b)} B`).join(', ')}`);
