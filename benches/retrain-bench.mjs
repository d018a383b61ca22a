// Audit time for the most retraining-hungry config, { tc: 1, q: 100000 }, at
// 1x, 2x and 4x the log length (issue 17 item 9): linear, where a retrain at
// every fault epoch over growing databases made it quadratic. The flight is
// a survey with a 10 m GPS step for 15 s of every 40 s (a fault episode
// every 40 s). Run: npm run bench:retrain (builds first); `node
// benches/retrain-bench.mjs [base seconds]` on a built pkg/.
import { createRequire } from 'node:module';
import { join, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';
import { performance } from 'node:perf_hooks';

const root = join(dirname(fileURLToPath(import.meta.url)), '..');
const ng = createRequire(import.meta.url)(join(root, 'pkg'));
const base = Number(process.argv[2] ?? 600);

function flight(duration) {
  const faults = [];
  for (let s = 40; s + 20 < duration; s += 40) faults.push({ kind: 'step', start: s, end: s + 15, magnitude: 10 });
  const sc = { name: 'retrain-bench', seed: 7, duration, trajectory: 'survey', imuRate: 50, gpsRate: 10, baroRate: 10, gpsVelocity: true, outages: [], outageMode: 'silent', faults };
  return new TextEncoder().encode(ng.simulateScenario(sc));
}

function best(k, f) {
  let b = Infinity;
  let out;
  for (let i = 0; i < k; i++) {
    const t0 = performance.now();
    out = f();
    b = Math.min(b, performance.now() - t0);
  }
  return [b, out];
}

const rows = [];
for (const k of [1, 2, 4]) {
  const bytes = flight(base * k);
  for (const [name, cfg] of [['{tc:1, q:100000}', { tc: 1, q: 100000 }], ['default', undefined]]) {
    const [ms, { report }] = best(3, () => ng.auditBytes(bytes, cfg));
    rows.push({ k, name, rows: report.rows, ms, retrains: report.stats.retrains });
  }
}
console.log(`| log | config | rows | audit (ms, best of 3) | µs per row | accepted retrains |`);
console.log(`|---|---|---:|---:|---:|---:|`);
for (const r of rows) console.log(`| ${r.k}x (${base * r.k} s) | ${r.name} | ${r.rows} | ${r.ms.toFixed(0)} | ${(1000 * r.ms / r.rows).toFixed(2)} | ${r.retrains} |`);
const q = rows.filter((r) => r.name !== 'default');
console.log(`\n{tc:1, q:100000}: time ratio 2x/1x ${(q[1].ms / q[0].ms).toFixed(2)}, 4x/1x ${(q[2].ms / q[0].ms).toFixed(2)} (linear: 2 and 4; quadratic: 4 and 16)`);
