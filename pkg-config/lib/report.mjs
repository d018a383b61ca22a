// The reproduction report: Sun et al. 2017 Table 1 (TC sweep) on the paper
// scenario, per-fault-kind detection and clean-flight false alarms, all run
// through the wasm package exactly as a user would.
import { performance } from 'node:perf_hooks';

/** Sun et al. 2017, Table 1 (TP, FN, FP, TN, accuracy, FAR, MDR, time s). */
export const PAPER_TABLE1 = {
  1: [84, 216, 721, 1479, 0.625, 0.896, 0.72, 102],
  20: [134, 166, 200, 2000, 0.854, 0.599, 0.553, 13],
  50: [110, 190, 70, 2130, 0.896, 0.389, 0.633, 15],
  100: [286, 14, 43, 2157, 0.977, 0.13, 0.047, 11],
  150: [237, 63, 117, 2083, 0.928, 0.331, 0.21, 15],
};

function columnsOf(ng, csvText) {
  const log = ng.readLog(new TextEncoder().encode(csvText));
  return log.columns;
}

/** Run a detector over columns; returns { status, ms }. */
export function runColumns(ng, cols, config) {
  const det = new ng.Detector(config);
  const input = {};
  for (const [k, v] of Object.entries(cols)) if (k !== 'label') input[k] = v;
  const t0 = performance.now();
  const out = det.pushColumns(input);
  const ms = performance.now() - t0;
  const stats = det.stats();
  det.free();
  return { out, ms, stats };
}

export function tcSweep(ng, seed = 1, progress = () => {}) {
  const cols = columnsOf(ng, ng.simulate('paper', seed));
  const rows = [];
  for (const tc of [1, 20, 50, 100, 150]) {
    progress(`TC=${tc}`);
    const { out, ms, stats } = runColumns(ng, cols, { tc });
    const m = ng.metrics(cols.t, cols.label, out.status);
    rows.push({ tc, m, ms, retrains: stats.retrains });
  }
  return rows;
}

export function faultKinds(ng, seeds = [1, 2, 3], progress = () => {}) {
  const kinds = ['step', 'ramp', 'noise', 'frozen', 'zero-velocity', 'baro-stuck', 'accel-bias', 'paper-silent', 'gps-only'];
  const res = [];
  for (const k of kinds) {
    let agg = { tp: 0, fp: 0, fn: 0, tn: 0, intervals: 0, detected: 0, delay: [] };
    for (const s of seeds) {
      progress(`${k} seed ${s}`);
      const cols = columnsOf(ng, ng.simulate(k, s));
      const { out } = runColumns(ng, cols, {});
      const m = ng.metrics(cols.t, cols.label, out.status);
      agg.tp += m.tp; agg.fp += m.fp; agg.fn += m.fn; agg.tn += m.tn;
      agg.intervals += m.faultIntervals; agg.detected += m.detectedIntervals;
      if (Number.isFinite(m.meanDetectionDelay)) agg.delay.push(m.meanDetectionDelay);
    }
    res.push({ kind: k, ...agg });
  }
  return res;
}

export function cleanFlights(ng, seeds = [1, 2, 3], progress = () => {}) {
  const res = [];
  for (const k of ['clean-paper', 'clean-aggressive', 'clean-survey']) {
    let flagged = 0, epochs = 0;
    for (const s of seeds) {
      progress(`${k} seed ${s}`);
      const cols = columnsOf(ng, ng.simulate(k, s));
      const { out } = runColumns(ng, cols, {});
      for (let i = 0; i < cols.t.length; i++) {
        if (!Number.isNaN(cols.label[i])) { epochs++; flagged += out.status[i]; }
      }
    }
    res.push({ kind: k, flagged, epochs, frac: flagged / epochs });
  }
  return res;
}

const pct = (x) => (100 * x).toFixed(1).padStart(5) + '%';

export function formatReport({ sweep, kinds, clean }) {
  const L = [];
  L.push('navguard report: Sun et al. 2017 Table 1 reproduced on the paper scenario (250 s, degraded GPS outages at 30-40, 100-110, 220-230 s; 2,500 labelled epochs, 300 fault)');
  L.push('');
  L.push('  TC  |   TP   FN    FP    TN | accuracy  false-alarm  misdetect | time      || paper: TP  FN  FP   TN   acc    FAR    MDR   time');
  for (const r of sweep) {
    const p = PAPER_TABLE1[r.tc];
    const m = r.m;
    L.push(`${String(r.tc).padStart(5)} | ${String(m.tp).padStart(4)} ${String(m.fn).padStart(4)} ${String(m.fp).padStart(5)} ${String(m.tn).padStart(5)} |   ${m.accuracy.toFixed(3)}     ${m.falseAlarmRate.toFixed(3)}      ${m.misdetectionRate.toFixed(3)}  | ${r.ms.toFixed(1).padStart(6)} ms || ${p.slice(0, 4).map((v) => String(v).padStart(4)).join(' ')}  ${p[4].toFixed(3)}  ${p[5].toFixed(3)}  ${p[6].toFixed(3)}  ${p[7]} s`);
  }
  const best = sweep.find((r) => r.tc === 100).m;
  const ok = (c) => (c ? 'met' : 'MISSED');
  L.push('');
  L.push(`TC=100 against the paper (acc >= 0.977, FAR <= 0.13, MDR <= 0.047): ${ok(best.accuracy >= 0.977 && best.falseAlarmRate <= 0.13 && best.misdetectionRate <= 0.047)}`);
  L.push(`TC=100 against our target (acc >= 0.99, FAR <= 0.05, MDR <= 0.02): accuracy ${ok(best.accuracy >= 0.99)}, false alarm ${ok(best.falseAlarmRate <= 0.05)}, misdetection ${ok(best.misdetectionRate <= 0.02)}`);
  if (kinds) {
    L.push('');
    L.push('Fault kinds (paper flight, fault 120-135 s; baro-stuck inside the climb; seeds 1-3, default config):');
    L.push('  kind            | intervals detected | accuracy  false-alarm  misdetect | mean delay');
    for (const k of kinds) {
      const all = k.tp + k.fp + k.fn + k.tn;
      const acc = (k.tp + k.tn) / all, far = k.tp + k.fp ? k.fp / (k.tp + k.fp) : 0, mdr = k.tp + k.fn ? k.fn / (k.tp + k.fn) : 0;
      const d = k.delay.length ? (k.delay.reduce((a, b) => a + b, 0) / k.delay.length).toFixed(2) + ' s' : '-';
      L.push(`  ${k.kind.padEnd(15)} | ${String(k.detected).padStart(3)} / ${String(k.intervals).padEnd(10)} |   ${acc.toFixed(3)}     ${far.toFixed(3)}      ${mdr.toFixed(3)}  | ${d}`);
    }
  }
  if (clean) {
    L.push('');
    L.push('Fault-free flights (seeds 1-3): flagged GPS epochs (target < 1%)');
    for (const c of clean) L.push(`  ${c.kind.padEnd(17)} ${String(c.flagged).padStart(5)} / ${c.epochs}  ${pct(c.frac)}`);
  }
  return L.join('\n');
}
