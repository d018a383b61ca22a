// The HTML report module on its own (pkg-config/lib/html-report.mjs, no
// wasm): verdict words, labels, spike-preserving thinning, robust axes, and
// the interval table with and without the severity fields.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

const root = join(dirname(fileURLToPath(import.meta.url)), '..', '..');
const H = await import(join(root, 'pkg-config', 'lib', 'html-report.mjs'));

const base = {
  format: 'dataflash', rows: 100, durationS: 50, gpsEpochs: 250, gpsRateHz: 5, imuRateHz: 50, gpsAvailable: true,
  gpsFixFraction: 1, flaggedGpsEpochFraction: 0.02, faults: [], dataGaps: [], missing: [], warnings: [], meta: [],
  stats: {}, startT: 100, ephSource: 'hdop', modes: [{ t: 100, mode: 'LOITER' }, { t: 120, mode: 'RTL' }],
  messages: [{ t: 130, level: 'error', text: 'ERR GPS: code 2' }],
};
const fault = { start: 110, end: 112.5, kind: 'residual', peakF: 0.97, driver: 'gps_position', indicator: 'R', rows: 13 };

test('verdicts: faults, clean, no verdict (no GPS), unreadable; every table counts the causal faults', () => {
  assert.equal(H.verdictOf({ ...base, faults: [fault] }), 'faults');
  assert.equal(H.verdictOf(base), 'clean');
  assert.equal(H.verdictOf({ ...base, gpsAvailable: false, faults: [] }), 'no verdict');
  assert.equal(H.verdictOf(null), 'unreadable');
  assert.deepEqual(H.faultList({ ...base, faults: [fault, fault], reconciled: [fault] }), [fault, fault]);
  assert.equal(H.reconciledCount({ ...base, faults: [fault, fault], reconciled: [fault] }), 1);
  assert.equal(H.reconciledCount(base), null);
  assert.equal(H.qualityLabel(base), 'HDOP');
  assert.equal(H.qualityLabel({ ...base, ephSource: 'eph' }), 'eph (m)');
  assert.equal(H.fmtUtc('2014-11-06T16:02:33.790Z'), '2014-11-06 16:02:33 UTC');
  assert.equal(H.fmtUtc(undefined), null);
  assert.equal(H.fmtSince(83.44), '83.4 s');
  assert.equal(H.fmtSince(725.25), '12:05.3');
});

test('the verdict word counts the reconciled intervals too; the CLI lists them when they differ', () => {
  // A drag-off the detector followed and dated only at its end: no causal
  // interval, one reconciled. The flight is not clean.
  const dated = { ...fault, start: 102, end: 112.5 };
  assert.equal(H.verdictOf({ ...base, faults: [], reconciled: [dated] }), 'faults');
  assert.equal(H.verdictOf({ ...base, faults: [], reconciled: [] }), 'clean');
  assert.deepEqual(H.reconciledIfDifferent({ ...base, faults: [], reconciled: [dated] }), [dated]);
  assert.equal(H.reconciledIfDifferent({ ...base, faults: [fault], reconciled: [fault] }), null);
  assert.equal(H.reconciledIfDifferent(base), null);
  // Times since the log's start (t0 = 100 s), kind, severity, offset.
  assert.equal(
    H.intervalLine({ ...dated, severity: 'major', peakOffset: 7.25, offsetUnit: 'm' }, 100),
    '         2.00 -     12.50 s  residual    major  peak offset 7.3 m  peak F 0.97  driver gps_position (R)',
  );
});

test('thinning keeps a single spike; the robust range leaves it out', () => {
  const t = Array.from({ length: 10000 }, (_, i) => i / 100);
  const v = t.map((x) => Math.sin(x));
  v[5000] = -20;
  const th = H.thin(t, v, 10, 400);
  assert.ok(th.t.length <= 400 && th.t.length >= 300, `${th.t.length} points`);
  assert.equal(Math.min(...th.v), -20);
  assert.equal(th.t[th.v.indexOf(-20)], 40, 'times shifted by t0');
  const [lo, hi] = H.robustRange(v);
  assert.ok(lo > -2 && lo < -1 && hi > 1 && hi < 2, `${lo} ${hi}`);
  // no spike: the full range (plus a 4 % margin)
  const [a, b] = H.robustRange(v.map((x) => (x === -20 ? 0 : x)));
  assert.ok(Math.abs(a + 1.08) < 0.01 && Math.abs(b - 1.08) < 0.01, `${a} ${b}`);
  const svg = H.svgPlot({ id: 'p', title: 't', ylabel: 'm', series: [{ label: 'x', ...th }], x0: 0, x1: 100 });
  assert.match(svg, /1 point off scale/);
});

test('the interval table shows severity and peak offset when the report has them, and renders without', () => {
  const plain = H.renderReport({ version: '0.0.0', generated: 'now', flights: [{ name: 'a.bin', report: { ...base, faults: [fault] } }] });
  assert.doesNotMatch(plain, /<th>severity<\/th>/);
  assert.match(plain, /<tr class="interval" data-start="10" data-end="12.5" data-kind="residual"><td class="num">1<\/td><td class="num" data-sort="10">10\.0 s<\/td><td class="num" data-sort="12.5">12\.5 s<\/td><td class="num">2\.50<\/td>/);
  const sev = { ...fault, severity: 'high', peakOffset: 23.4, offsetUnit: 'm', durationS: 2.5 };
  const rich = H.renderReport({ version: '0.0.0', generated: 'now', flights: [{ name: 'a.bin', report: { ...base, faults: [sev] } }] });
  assert.match(rich, /<th>severity<\/th><th class="num">peak offset<\/th>/);
  assert.match(rich, /<td class="sev-high">high<\/td><td class="num">23\.4 m<\/td>/);
  // modes, messages and the HDOP label, times since the start
  assert.match(rich, /<td class="num">0\.0 s<\/td><td>LOITER<\/td>.*<td class="num">20\.0 s<\/td><td>RTL<\/td>/s);
  assert.match(rich, /<td class="num">30\.0 s<\/td><td>error<\/td><td>ERR GPS: code 2<\/td>/);
  assert.match(rich, /HDOP \(unitless/);
  const nogps = H.renderReport({ flights: [{ name: 'b.ulg', report: { ...base, gpsAvailable: false, missing: ['gps'] } }, { name: 'c.bin', error: 'truncated header' }] });
  assert.match(nogps, /data-verdict="no verdict"/);
  assert.match(nogps, /Still checked: IMU \(50 Hz\): rates and data gaps; barometer/);
  assert.match(nogps, /<tr data-verdict="unreadable"><td><a href="#flight-1">c\.bin<\/a>/);
  assert.match(nogps, /2 logs: 1 no verdict, 1 unreadable/);
});

test('the reconciled intervals are listed, folded, when they differ from the causal ones', () => {
  // A drag-off dated from 102 s at its end, 110 s, over the causal
  // interval its return opened: one reconciled interval, 102-112.5 s.
  const dated = { ...fault, start: 102, end: 112.5, rows: 13, severity: 'high', peakOffset: 7.2, offsetUnit: 'm', durationS: 10.5 };
  const html = H.renderReport({ version: '0.0.0', generated: 'now', flights: [{ name: 'a.bin', report: { ...base, faults: [fault], reconciled: [dated] } }] });
  assert.match(html, /<h3>Fault intervals \(1; 1 reconciled over the whole log, below\)<\/h3>/);
  assert.match(html, /<details class="reconciled"><summary>Reconciled over the whole log: 1 interval<\/summary>/);
  assert.match(html, /<tr class="reconciled-interval" data-start="2" data-end="12.5" data-kind="residual">/);
  // The causal table is untouched: one `tr.interval`, the causal one.
  assert.equal((html.match(/<tr class="interval"/g) || []).length, 1);
  // The same intervals: nothing more is shown.
  const same = H.renderReport({ version: '0.0.0', generated: 'now', flights: [{ name: 'a.bin', report: { ...base, faults: [fault], reconciled: [fault] } }] });
  assert.doesNotMatch(same, /details class="reconciled"/);
  assert.match(same, /<h3>Fault intervals \(1\)<\/h3>/);
  assert.equal(H.reconciledTable({ ...base, faults: [fault] }, 100), '');
});
