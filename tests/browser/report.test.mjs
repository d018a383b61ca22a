// The HTML reports the CLI writes (`navguard report FILE --html`,
// `navguard audit DIR --html`), opened in headless Chromium with every
// network request aborted: they need none, and hold the intervals, the
// plots, the track, and (fleet) one row per log with no-verdict logs marked.
// Needs pkg/ (bash .ci/build) and /usr/bin/chromium; fails when missing.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { mkdtempSync, readFileSync, mkdirSync, copyFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';
import { createRequire } from 'node:module';
import { openOffline } from './offline.mjs';

const repoRoot = join(dirname(fileURLToPath(import.meta.url)), '..', '..');
const cli = join(repoRoot, 'pkg', 'bin', 'navguard.mjs');
const data = join(repoRoot, '..', 'shared', 'data');
const artifacts = join(repoRoot, 'tests', 'artifacts');
const CHROMIUM = process.env.CHROMIUM_PATH || '/usr/bin/chromium';
const { chromium } = createRequire(import.meta.url)(join(repoRoot, 'node_modules', 'playwright-core'));
const tmp = mkdtempSync(join(tmpdir(), 'navguard-html-'));
const navguard = (...args) => execFileSync(process.execPath, [cli, ...args], { encoding: 'utf8', maxBuffer: 1 << 28 });

let browser;
before(async () => {
  browser = await chromium.launch({ executablePath: CHROMIUM, args: ['--headless', '--no-sandbox', '--disable-gpu'] });
  mkdirSync(artifacts, { recursive: true });
});
after(async () => { if (browser) await browser.close(); });

test('report FILE --html: offline, the intervals with their times, plots with data, the track, modes and messages', async () => {
  const log = join(data, 'ardupilot', 'Loiter_RTL.bin');
  const out = join(tmp, 'loiter.html');
  navguard('report', log, '--html', out);
  const json = JSON.parse(navguard('audit', log, '--json'));
  const { ctx, page, requests, errors } = await openOffline(browser, { file: out });
  try {
    assert.deepEqual(requests, []);
    assert.equal(await page.$eval('section.flight', (s) => s.dataset.verdict), 'faults');
    const rows = await page.$$eval('table.faults tr.interval', (trs) => trs.map((tr) => ({ start: Number(tr.dataset.start), end: Number(tr.dataset.end), kind: tr.dataset.kind })));
    assert.equal(rows.length, json.faults.length);
    rows.forEach((r, i) => {
      assert.ok(Math.abs(r.start - (json.faults[i].start - json.startT)) < 1e-9, `${r.start} vs ${json.faults[i].start}`);
      assert.equal(r.kind, json.faults[i].kind);
    });
    // the real GPS loss (boot ~98-104 s) is an interval, shown since the start
    assert.ok(rows.some((r) => r.kind === 'gps_outage' && r.start < 104 - 20.664 && r.end > 98 - 20.664), JSON.stringify(rows));
    const plots = await page.$$eval('svg.plot', (ss) => ss.map((s) => ({ id: s.id, series: Array.from(s.querySelectorAll('path.ln')).map((p) => [p.dataset.label, Number(p.dataset.n)]), faults: s.querySelectorAll('rect.fault').length, modes: s.querySelectorAll('rect.mode').length })));
    assert.deepEqual(plots.map((p) => p.id), ['f-0-F', 'f-0-res', 'f-0-alt', 'f-0-gq']);
    for (const p of plots) {
      assert.ok(p.series.every(([, n]) => n > 100), JSON.stringify(p));
      assert.equal(p.faults, json.faults.length, `${p.id}: fault shading`);
      assert.equal(p.modes, 9, `${p.id}: mode shading`);
    }
    assert.deepEqual(plots[3].series.map(([l]) => l), ['satellites', 'HDOP', 'fix type']);
    assert.deepEqual(plots[2].series.map(([l]) => l), ['GPS altitude', 'baro altitude']);
    const text = await page.textContent('body');
    assert.match(text, /start2014-11-06 16:02:33 UTC/);
    assert.match(text, /receiver qualityHDOP \(unitless/);
    assert.match(text, /Flight modes \(9\)/);
    assert.match(text, /Autopilot messages \(144\)/);
    assert.ok((await page.$eval('svg.track path.ln', (p) => p.getAttribute('d'))).split(/[ML]/).length > 500);
    await page.screenshot({ path: join(artifacts, 'report.png'), fullPage: true });
    if (process.env.UPDATE_SCREENSHOT) copyFileSync(join(artifacts, 'report.png'), join(repoRoot, 'www', 'screenshot-report.png'));
    assert.deepEqual(errors, []);
  } finally {
    await ctx.close();
  }
});

test('audit ../shared/data --html: every log (recursive) in a sortable table linking to its section, no-verdict logs marked', async () => {
  const out = join(tmp, 'fleet.html');
  navguard('audit', data, '--html', out, '--jobs', '2');
  const json = JSON.parse(navguard('audit', data, '--json', '--jobs', '2'));
  assert.ok(json.logs.length >= 13 && json.logs.some((l) => l.file.includes('/px4/')) && json.logs.some((l) => l.file.includes('/ardupilot/')));
  const { ctx, page, requests, errors } = await openOffline(browser, { file: out });
  try {
    assert.deepEqual(requests, []);
    const rows = await page.$$eval('table.fleet tbody tr', (trs) => trs.map((tr) => ({ verdict: tr.dataset.verdict, name: tr.cells[0].textContent, href: tr.querySelector('a').getAttribute('href') })));
    const want = json.logs.map((l) => ({ verdict: l.verdict, name: l.file.slice(data.length + 1) }));
    assert.deepEqual(rows.map(({ verdict, name }) => ({ verdict, name })), want);
    assert.ok(rows.some((r) => r.verdict === 'no verdict'), 'expected no-verdict logs in ../shared/data');
    for (const r of rows) {
      const section = await page.$eval(r.href, (s) => ({ verdict: s.dataset.verdict, badge: s.querySelector('h2 .badge').textContent }));
      assert.equal(section.verdict, r.verdict, r.name);
      assert.equal(section.badge, r.verdict, r.name);
    }
    // a no-verdict log says what was still checked instead of "clean"
    const nv = rows.find((r) => r.verdict === 'no verdict');
    assert.match(await page.$eval(nv.href, (s) => s.textContent), /no verdict is given\. Still checked: IMU/);
    // sortable: by flagged share, descending then ascending
    await page.click('table.fleet th:nth-child(6)');
    await page.click('table.fleet th:nth-child(6)');
    const flagged = await page.$$eval('table.fleet tbody tr', (trs) => trs.map((tr) => Number(tr.cells[5].dataset.sort)));
    assert.deepEqual(flagged, [...flagged].sort((a, b) => b - a));
    await page.click('table.fleet th:nth-child(1)');
    const names = await page.$$eval('table.fleet tbody tr', (trs) => trs.map((tr) => tr.cells[0].textContent));
    assert.deepEqual(names, [...names].sort((a, b) => a.localeCompare(b)));
    await page.screenshot({ path: join(artifacts, 'report-fleet.png') });
    assert.deepEqual(errors, []);
  } finally {
    await ctx.close();
  }
  assert.ok(readFileSync(out, 'utf8').length < 4 << 20, 'the fleet report stays small');
});
