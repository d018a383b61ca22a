// Browser test of the ground-station page (www/) in headless Debian Chromium.
// Run from the repository root: node --test tests/browser/
// Needs www/pkg/ (bash .ci/build) and /usr/bin/chromium; fails (never skips)
// when either is missing.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import http from 'node:http';
import { readFile, mkdir, copyFile, access } from 'node:fs/promises';
import { join, extname, normalize, dirname, sep } from 'node:path';
import { fileURLToPath } from 'node:url';
import { createRequire } from 'node:module';
import { openOffline } from './offline.mjs';

const here = dirname(fileURLToPath(import.meta.url));
const repoRoot = join(here, '..', '..');
const www = join(repoRoot, 'www');
const artifacts = join(repoRoot, 'tests', 'artifacts');
const LOITER = join(repoRoot, '..', 'shared', 'data', 'ardupilot', 'Loiter_RTL.bin');
const CHROMIUM = process.env.CHROMIUM_PATH || '/usr/bin/chromium';
const { chromium } = createRequire(import.meta.url)(join(repoRoot, 'node_modules', 'playwright-core'));
// The snapshot format this source writes (`VERSION` in
// detector/src/snapshot.rs): the page shows what the build reports.
const SNAPSHOT_FORMAT = Number((await readFile(join(repoRoot, 'detector', 'src', 'snapshot.rs'), 'utf8')).match(/pub const VERSION: u32 = (\d+);/)[1]);

const MIME = {
  '.html': 'text/html; charset=utf-8',
  '.js': 'text/javascript; charset=utf-8',
  '.mjs': 'text/javascript; charset=utf-8',
  '.css': 'text/css; charset=utf-8',
  '.wasm': 'application/wasm',
  '.json': 'application/json',
  '.png': 'image/png',
  '.svg': 'image/svg+xml',
  '.ts': 'text/plain; charset=utf-8',
};

let server, base, browser;

before(async () => {
  await access(CHROMIUM).catch(() => { throw new Error(`Chromium not found at ${CHROMIUM}: the browser test needs it (set CHROMIUM_PATH)`); });
  await access(join(www, 'pkg', 'navguard.js')).catch(() => { throw new Error('www/pkg/ is missing: run `bash .ci/build` first'); });
  server = http.createServer(async (req, res) => {
    try {
      const path = decodeURIComponent(new URL(req.url, 'http://x').pathname);
      const file = normalize(join(www, path.endsWith('/') ? path + 'index.html' : path));
      if (file !== www && !file.startsWith(www + sep)) throw Object.assign(new Error('outside'), { code: 'ENOENT' });
      const body = await readFile(file);
      res.writeHead(200, { 'content-type': MIME[extname(file)] || 'application/octet-stream', 'cache-control': 'no-store' });
      res.end(body);
    } catch {
      res.writeHead(404, { 'content-type': 'text/plain' });
      res.end('not found');
    }
  });
  await new Promise((r) => server.listen(0, '127.0.0.1', r));
  base = `http://127.0.0.1:${server.address().port}/`;
  browser = await chromium.launch({
    executablePath: CHROMIUM,
    args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-background-networking', '--disable-component-update', '--disable-sync', '--no-first-run'],
  });
  await mkdir(artifacts, { recursive: true });
});

after(async () => {
  if (browser) await browser.close();
  if (server) await new Promise((r) => server.close(r));
});

async function openPage(tab = 'audit') {
  const page = await browser.newPage({ viewport: { width: 1600, height: 1300 }, acceptDownloads: true });
  const errors = [];
  page.on('pageerror', (e) => errors.push(`pageerror: ${e.message}`));
  page.on('console', (m) => { if (m.type() === 'error') errors.push(`console.error: ${m.text()}`); });
  page.on('requestfailed', (r) => errors.push(`requestfailed: ${r.url()} ${r.failure()?.errorText}`));
  page.on('response', (r) => { if (r.status() >= 400) errors.push(`HTTP ${r.status()}: ${r.url()}`); });
  await page.goto(base);
  // the worker has loaded the wasm module once the scenario list is filled
  await page.waitForFunction(() => !document.querySelector('#scenario').disabled, null, { timeout: 30000 });
  // The research panels (compare, tightly coupled, GAN, figures) sit on a
  // second tab, hidden until it is chosen.
  assert.equal(await page.isVisible('#compare-panel'), false, 'research panels shown on the operator view');
  if (tab === 'research') {
    await page.click('.tabs [data-tab="research"]');
    assert.equal(await page.isVisible('#compare-panel'), true);
    assert.equal(await page.isVisible('#faults'), false);
  }
  return { page, errors };
}

async function waitDone(page) {
  await page.waitForFunction(() => document.body.dataset.state === 'done' || !document.querySelector('#error').hidden, null, { timeout: 120000 });
  const err = await page.$eval('#error', (e) => (e.hidden ? '' : e.textContent));
  assert.equal(err, '', `page showed an error: ${err}`);
}

const faultRows = (page) => page.$$eval('#faults tbody tr[data-index]', (trs) => trs.map((tr) => ({
  start: Number(tr.dataset.start), end: Number(tr.dataset.end), kind: tr.dataset.kind,
})));

async function assertPlots(page) {
  const sizes = await page.$$eval('.uplot canvas', (cs) => cs.map((c) => [c.width, c.height]));
  assert.ok(sizes.length >= 7, `expected at least 7 uPlot canvases, found ${sizes.length}`);
  for (const [w, h] of sizes) assert.ok(w > 0 && h > 0, `canvas has zero size: ${w}x${h}`);
  const ids = await page.$$eval('.plot-host', (hs) => hs.filter((h) => h.querySelector('.uplot canvas')).map((h) => h.id));
  for (const id of ['plot-track', 'plot-band', 'plot-f', 'plot-rc', 'plot-gps', 'plot-rpos', 'plot-rvel']) assert.ok(ids.includes(id), `plot ${id} not rendered`);
  // every time plot, the residual ones included, shares the cursor/zoom sync
  const n = await page.evaluate(() => window.navguard.plots.length);
  assert.equal(n, 6, 'expected 6 synchronised time plots');
}

// Finite samples per series of the residual plots, by legend label.
const residualCounts = (page) => page.evaluate(() => {
  const out = {};
  for (const [host, u] of [['pos', window.navguard.plots[4]], ['vel', window.navguard.plots[5]]]) {
    u.series.forEach((s, i) => { if (i) out[`${host} ${s.label}`] = u.data[i].filter((v) => Number.isFinite(v)).length; });
  }
  return out;
});

// The detector stage reported a real percentage (recorded by the page as the
// worker's progress messages arrive, so this does not depend on timing).
async function detectingProgress(page) {
  const log = await page.evaluate(() => window.navguard.progressLog);
  const det = log.filter((p) => p.stage === 'detecting' && / \d+ %$/.test(p.detail || ''));
  assert.ok(det.length >= 2, `no detecting progress with a percentage: ${JSON.stringify(log)}`);
  assert.equal(det[0].frac, 0);
  assert.equal(det[det.length - 1].frac, 1);
  assert.match(det[det.length - 1].detail, / 100 %$/);
  for (let i = 1; i < det.length; i++) assert.ok(det[i].frac > det[i - 1].frac, `progress went backwards: ${JSON.stringify(det)}`);
  return det;
}

test('ArduPilot Loiter_RTL.bin through the file input: GPS outage found, plots drawn, no errors', async () => {
  const { page, errors } = await openPage();
  try {
    await page.setInputFiles('#file', LOITER);
    await waitDone(page);
    const summary = await page.textContent('#summary');
    assert.match(summary, /ArduPilot DataFlash/);
    // verdict first, with the flight's UTC start; HDOP named as such (no GPA)
    assert.equal(await page.$eval('#verdict', (e) => e.dataset.verdict), 'faults');
    const verdict = await page.textContent('#verdict');
    assert.match(verdict, /^faults\d+ fault intervals?, \d+\.\d s flagged/);
    assert.match(verdict, /started 2014-11-06 16:02:33 UTC/);
    assert.match(verdict, /9 flight modes · 144 autopilot messages \(3 warnings\/errors\)/);
    assert.match(verdict, /receiver quality as HDOP/);
    assert.match(summary, /Receiver qualityHDOP/);
    assert.match(summary, /Start \(UTC\)2014-11-06 16:02:33 UTC/);
    assert.match(summary, /Flight modes \(9\)0\.0 s ALT_HOLD20\.4 s LOITER/);
    assert.match(await page.textContent('#plot-gps .u-legend'), /HDOP/);
    assert.doesNotMatch(await page.textContent('#plot-gps'), /eph/);
    // times shown since the log's start (boot clock 20.664 s at the first row)
    const shown = await page.$$eval('#faults tbody tr[data-index]', (trs) => trs.map((tr) => [Number(tr.dataset.start), Number(tr.cells[1].textContent)]));
    for (const [boot, since] of shown) assert.ok(Math.abs(boot - 20.664 - since) < 0.006, `${boot} shown as ${since}`);
    const tickLabels = await page.evaluate(() => window.navguard.plots[1].axes[0]._values);
    assert.equal(tickLabels[0], '0', `x ticks not in time since start: ${tickLabels}`);

    const rows = await faultRows(page);
    assert.ok(rows.length > 0, 'fault table is empty');
    // acceptance criterion: the real GPS outage at boot time ~97–104 s
    const hit = rows.filter((r) => r.start <= 104 && r.end >= 97);
    assert.ok(hit.length > 0, `no fault interval overlaps the GPS outage 97–104 s; intervals: ${JSON.stringify(rows)}`);

    await assertPlots(page);
    const counts = await residualCounts(page);
    for (const k of ['pos N (m)', 'pos E (m)', 'pos D (m)', 'vel N (m/s)', 'vel E (m/s)', 'vel D (m/s)']) {
      assert.ok(counts[k] > 500, `residual series ${k} has ${counts[k]} samples`);
    }
    assert.ok(counts['pos baro (m)'] > 1000, `baro residual has ${counts['pos baro (m)']} samples`);
    const det = await detectingProgress(page);
    assert.match(det[0].detail, /15,124 samples/);

    // clicking the row zooms every time plot to it (± margin)
    const idx = await page.$$eval('#faults tbody tr[data-index]', (trs) => trs.findIndex((tr) => Number(tr.dataset.start) <= 104 && Number(tr.dataset.end) >= 97));
    await page.click(`#faults tbody tr[data-index="${idx}"]`);
    const scales = await page.evaluate(() => window.navguard.plots.map((u) => [u.scales.x.min, u.scales.x.max]));
    const target = hit[0];
    for (const [min, max] of scales) {
      assert.ok(min <= target.start && max >= target.end && max - min < 60, `plot not zoomed to the interval: [${min}, ${max}]`);
    }
    await page.screenshot({ path: join(artifacts, 'page-zoomed.png'), fullPage: true });

    // double-click resets the zoom on every plot
    const box = await page.$eval('#plot-f .u-over', (e) => { const r = e.getBoundingClientRect(); return { x: r.x + r.width / 2, y: r.y + r.height / 2 }; });
    await page.mouse.dblclick(box.x, box.y);
    const reset = await page.evaluate(() => window.navguard.plots.map((u) => u.scales.x.max - u.scales.x.min));
    for (const span of reset) assert.ok(span > 200, `double-click did not reset the zoom (span ${span} s)`);

    // hovering a residual plot shows the nearest samples in its legend and
    // moves the synchronised cursor on the other time plots
    const over = page.locator('#plot-rpos .u-over');
    const obox = await over.boundingBox();
    await over.hover({ position: { x: obox.width * 0.8, y: obox.height / 2 } });
    const legendVals = await page.$$eval('#plot-rpos .u-legend .u-value', (vs) => vs.map((v) => v.textContent));
    assert.ok(legendVals.slice(1).every((v) => /^-?\d+\.\d\d$/.test(v)), `residual legend values: ${JSON.stringify(legendVals)}`);
    const cursors = await page.evaluate(() => window.navguard.plots.map((u) => u.cursor.left));
    for (const left of cursors) assert.ok(left > 0, `cursor not synchronised: ${JSON.stringify(cursors)}`);
    await page.mouse.move(5, 5);
    // the hover scrolled the page: back to the top for a clean full-page screenshot
    await page.evaluate(() => window.scrollTo(0, 0));

    // per-sample CSV export
    const [dl] = await Promise.all([page.waitForEvent('download'), page.click('#export-csv')]);
    const csv = await readFile(await dl.path(), 'utf8');
    const lines = csv.trimEnd().split('\n');
    assert.equal(lines[0], 't,status,f,r,c,kind,rPn,rPe,rPd,rVn,rVe,rVd,rBaro,reconciled');
    assert.ok(lines.length > 1000);
    const cells = lines.slice(1).map((l) => l.split(','));
    for (const c of cells) assert.equal(c.length, 14, `bad CSV row: ${c.join(',')}`);
    const gpsRows = cells.filter((c) => c[6] !== '');
    assert.ok(gpsRows.length > 500 && gpsRows.length < cells.length / 2, `rows with a GPS residual: ${gpsRows.length} of ${cells.length}`);
    for (const c of gpsRows) for (const v of c.slice(6, 12)) assert.ok(Number.isFinite(Number(v)) && v !== '', `bad residual cell in ${c.join(',')}`);
    assert.ok(cells.some((c) => c[12] !== '' && Number.isFinite(Number(c[12]))), 'no baro residual in the CSV');
    const [dj] = await Promise.all([page.waitForEvent('download'), page.click('#export-json')]);
    const rep = JSON.parse(await readFile(await dj.path(), 'utf8'));
    assert.equal(rep.format, 'dataflash');
    assert.equal(rep.faults.length, rows.length);
    assert.equal(rep.ephSource, 'hdop');
    assert.equal(rep.startUtc, '2014-11-06T16:02:33.790Z');
    // The CSV's last column is the JSON report's whole-log verdict, row by row.
    const inRec = (t) => rep.reconciled.some((f) => f.start <= t && t <= f.end);
    assert.ok(cells.some((c) => c[13] === '1'));
    assert.deepEqual(cells.filter((c) => (c[13] === '1') !== inRec(+c[0])).map((c) => c[0]).slice(0, 5), []);
    // the HTML report the page exports is the CLI's file (same module)
    const [dh] = await Promise.all([page.waitForEvent('download'), page.click('#export-html')]);
    assert.match(dl.suggestedFilename() + dh.suggestedFilename(), /\.report\.html$/);
    const html = await readFile(await dh.path(), 'utf8');
    await assertOfflineReport(html, rows.length, join(artifacts, 'page-report.png'));

    // the export clicks scrolled the page: back to the top
    await page.evaluate(() => window.scrollTo(0, 0));
    const shot = join(artifacts, 'page.png');
    await page.screenshot({ path: shot, fullPage: true });
    // The README's picture is refreshed on request only, so a test run
    // leaves the work tree clean: UPDATE_SCREENSHOT=1 node --test tests/browser/
    if (process.env.UPDATE_SCREENSHOT) await copyFile(shot, join(www, 'screenshot.png'));

    assert.deepEqual(errors, [], `page errors:\n${errors.join('\n')}`);
  } finally {
    await page.close();
  }
});

/** Open an HTML report with every network request aborted: it must need
 * none, list `nIntervals` intervals, and draw its plots and track. */
async function assertOfflineReport(html, nIntervals, shot) {
  const { ctx, page, requests, errors } = await openOffline(browser, { html });
  try {
    assert.deepEqual(requests, [], 'the report fetched something');
    assert.equal(await page.$$eval('table.faults tr.interval', (t) => t.length), nIntervals);
    const plots = await page.$$eval('svg.plot', (ss) => ss.map((s) => ({ id: s.id, n: Array.from(s.querySelectorAll('path.ln')).map((p) => Number(p.dataset.n)) })));
    assert.ok(plots.length >= 4, JSON.stringify(plots));
    for (const p of plots) assert.ok(p.n.length > 0 && p.n.every((n) => n > 10), `empty plot ${JSON.stringify(p)}`);
    assert.ok(await page.$eval('svg.track path.ln', (p) => p.getAttribute('d').length > 1000));
    if (shot) await page.screenshot({ path: shot, fullPage: true });
    assert.deepEqual(errors, []);
    return page;
  } finally {
    await ctx.close();
  }
}

/** Drop a CSV (lines) onto the page as a file named `name`. */
const dropText = (page, name, lines) => page.evaluate(([n, text]) => {
  const dt = new DataTransfer();
  dt.items.add(new File([text], n, { type: 'text/csv' }));
  window.dispatchEvent(new DragEvent('drop', { dataTransfer: dt, bubbles: true, cancelable: true }));
}, [name, lines.join('\n') + '\n']);

test('one spike does not set the residual axis; a log with no GPS says what was still checked', async () => {
  const { page, errors } = await openPage();
  try {
    // 60 s of 5 Hz GPS heading north at 5 m/s with IMU and baro; one GPS
    // row 20 m south of the track (a single spike)
    const lines = ['t,lat,lon,alt,vn,ve,vd,fix,sats,eph,ax,ay,az,gx,gy,gz,qw,qx,qy,qz,baro'];
    for (let i = 0; i <= 3000; i++) {
      const t = i * 0.02;
      const imu = ',0,0,-9.81,0,0,0,1,0,0,0,50';
      if (i % 10 === 0) {
        const north = 5 * t - (i === 1500 ? 20 : 0);
        lines.push(`${t.toFixed(2)},${(31.94 + north / 111320).toFixed(9)},118.79,50,5,0,0,3,11,0.9${imu}`);
      } else lines.push(`${t.toFixed(2)},,,,,,,,,${imu}`);
    }
    await dropText(page, 'spike.csv', lines);
    await waitDone(page);
    const y = await page.evaluate(() => { const u = window.navguard.plots[4]; return { min: u.scales.y.min, max: u.scales.y.max, clipped: u._clipped, lo: Math.min(...u.data[1].filter((v) => v != null)) }; });
    assert.ok(y.lo < -15, `the spike is in the data: ${JSON.stringify(y)}`);
    assert.ok(y.min > -8, `a single spike set the axis: ${JSON.stringify(y)}`);
    assert.ok(y.clipped >= 1, `the clipped spike is not marked: ${JSON.stringify(y)}`);

    // IMU and baro only: no verdict, and the page says what was checked
    const imuOnly = ['t,ax,ay,az,gx,gy,gz,qw,qx,qy,qz,baro'];
    for (let i = 0; i < 500; i++) imuOnly.push(`${(i / 50).toFixed(2)},0,0,-9.81,0,0,0,1,0,0,0,10`);
    await dropText(page, 'imu-only.csv', imuOnly);
    await page.waitForFunction(() => document.querySelector('#verdict').dataset.verdict === 'no verdict', null, { timeout: 60000 });
    const v = await page.textContent('#verdict');
    assert.match(v, /^no verdictNo verdict: no GPS fix in this log/);
    assert.match(v, /Still checked: IMU \(50 Hz\): rates and data gaps; barometer/);
    assert.match(await page.textContent('#faults tbody'), /No verdict: GPS unavailable.*Still checked: IMU/);
    assert.deepEqual(errors, [], `page errors:\n${errors.join('\n')}`);
  } finally {
    await page.close();
  }
});

test('simulated "paper" scenario: outage intervals near 30–40 s; config change reruns', async () => {
  const { page, errors } = await openPage();
  try {
    await page.selectOption('#scenario', 'paper');
    await page.fill('#seed', '1');
    await page.click('#sim-run');
    await waitDone(page);
    const rows = await faultRows(page);
    assert.ok(rows.some((r) => r.start >= 28 && r.start <= 42 && r.end >= 30 && r.start <= 40),
      `no interval near 30–40 s: ${JSON.stringify(rows)}`);
    await assertPlots(page);
    const summary = await page.textContent('#summary');
    assert.match(summary, /navlog CSV/);
    assert.match(summary, /Metrics against labels/);

    // changing the threshold reruns the audit
    const renders = await page.evaluate(() => window.navguard.renders);
    await page.fill('#config [name=threshold]', '0.9');
    await page.waitForFunction((n) => window.navguard.renders > n && document.body.dataset.state === 'done', renders, { timeout: 60000 });
    const cfg = await page.evaluate(() => window.navguard.config);
    assert.equal(cfg.threshold, 0.9);
    const legend = await page.textContent('#plot-f .u-legend');
    assert.match(legend, /threshold 0\.9/);
    await page.screenshot({ path: join(artifacts, 'page-sim.png'), fullPage: true });
    assert.deepEqual(errors, [], `page errors:\n${errors.join('\n')}`);
  } finally {
    await page.close();
  }
});

test('drag and drop a navlog CSV onto the page', async () => {
  const { page, errors } = await openPage();
  try {
    // 60 s of 5 Hz GPS-only flight heading north at 5 m/s, no faults injected
    const lines = ['t,lat,lon,alt,vn,ve,vd,fix,sats,eph'];
    for (let i = 0; i <= 300; i++) {
      const t = i * 0.2;
      lines.push(`${t.toFixed(1)},${(31.94 + (5 * t) / 111320).toFixed(9)},118.79,50,5,0,0,3,11,0.9`);
    }
    await page.evaluate((text) => {
      const dt = new DataTransfer();
      dt.items.add(new File([text], 'dropped.csv', { type: 'text/csv' }));
      window.dispatchEvent(new DragEvent('dragenter', { dataTransfer: dt, bubbles: true, cancelable: true }));
      window.dispatchEvent(new DragEvent('drop', { dataTransfer: dt, bubbles: true, cancelable: true }));
    }, lines.join('\n') + '\n');
    await waitDone(page);
    const summary = await page.textContent('#summary');
    assert.match(summary, /dropped\.csv/);
    assert.match(summary, /navlog CSV/);
    assert.equal(await page.$eval('#drop', (d) => d.hidden), true);
    await assertPlots(page);
    // GPS-only log: GPS residuals, no baro residual
    const counts = await residualCounts(page);
    assert.ok(counts['pos N (m)'] > 250 && counts['vel D (m/s)'] > 250, JSON.stringify(counts));
    assert.equal(counts['pos baro (m)'], 0);
    assert.deepEqual(errors, [], `page errors:\n${errors.join('\n')}`);
  } finally {
    await page.close();
  }
});

test('a long log reports the detecting stage in several slices', async () => {
  const { page, errors } = await openPage();
  try {
    // 45 000 rows of 10 Hz GPS-only flight: slices of 20 000 rows -> 3 steps
    await page.evaluate(() => {
      const lines = ['t,lat,lon,alt,vn,ve,vd,fix,sats,eph'];
      for (let i = 0; i < 45000; i++) {
        const t = i * 0.1;
        lines.push(`${t.toFixed(1)},${(31.94 + (5 * t) / 111320).toFixed(9)},118.79,50,5,0,0,3,11,0.9`);
      }
      const dt = new DataTransfer();
      dt.items.add(new File([lines.join('\n') + '\n'], 'long.csv', { type: 'text/csv' }));
      window.dispatchEvent(new DragEvent('drop', { dataTransfer: dt, bubbles: true, cancelable: true }));
    });
    await waitDone(page);
    const det = await detectingProgress(page);
    const fracs = det.map((p) => p.frac);
    assert.equal(fracs.length, 4, `expected 0 + 3 slices: ${JSON.stringify(det)}`);
    assert.ok(Math.abs(fracs[1] - 20000 / 45000) < 0.01 && Math.abs(fracs[2] - 40000 / 45000) < 0.01, JSON.stringify(fracs));
    assert.match(det[1].detail, /45,000 samples: 44 %$/);
    assert.deepEqual(errors, [], `page errors:\n${errors.join('\n')}`);
  } finally {
    await page.close();
  }
});

// ------------------------------------------------------------ live session

const live = (page) => page.evaluate(() => {
  const h = window.__navguardLive;
  return {
    phase: h.phase, startRow: h.startRow, startRowCount: h.startRowCount, startStats: h.startStats, resumed: h.resumed,
    nextRow: h.nextRow, totalRows: h.totalRows, rowCount: h.rowCount, stats: h.stats, saves: h.saves, lastSaved: h.lastSaved,
    info: h.info, draws: h.draws, plotPoints: h.plotPoints, speed: h.speed,
  };
});

// The stored record (IndexedDB "navguard" / "live-session" / "current"), bytes as a plain array.
const readSaved = (page) => page.evaluate(async () => {
  const r = await window.__navguardLive.readSaved();
  if (r === undefined) return null;
  return { ...r, snapshot: r.snapshot instanceof Uint8Array ? Array.from(r.snapshot) : r.snapshot };
});

async function reloadForOffer(page) {
  await page.reload();
  await page.waitForFunction(() => window.__navguardLive && window.__navguardLive.checked, null, { timeout: 30000 });
}

async function startLiveScenario(page, scenario, seed, speed) {
  await page.selectOption('#scenario', scenario);
  await page.fill('#seed', String(seed));
  await page.selectOption('#live-source', 'sim');
  await page.selectOption('#live-speed', String(speed));
  await page.waitForFunction(() => !document.querySelector('#live-start').disabled, null, { timeout: 30000 });
  await page.click('#live-start');
  await page.waitForFunction(() => window.__navguardLive.phase === 'running', null, { timeout: 30000 });
}

test('live session: snapshot kept in IndexedDB, resumed after a reload and continuing bit-identically', async (t) => {
  const { page, errors } = await openPage();
  try {
    const t0 = Date.now();
    // "paper" seed 1: 12 500 rows at 50 Hz over 250 s, first retrain near row 2 000;
    // at 10x (25 s in all) a save (every 2 s of wall time) lands every ~1 000 rows
    await startLiveScenario(page, 'paper', 1, 10);
    assert.equal(await page.$eval('#live-panel', (e) => e.hidden), false);
    await page.waitForFunction(() => {
      const h = window.__navguardLive;
      return h.lastSaved && h.lastSaved.nextRow > 3000 && h.lastSaved.stats.retrains >= 1;
    }, null, { timeout: 60000 });
    const before = await live(page);
    const wall = (Date.now() - t0) / 1000;
    assert.equal(before.totalRows, 12500);
    assert.ok(before.rowCount >= before.lastSaved.rowCount && before.rowCount === before.stats.rows, JSON.stringify(before));
    assert.ok(before.saves >= 2, `saves: ${before.saves}`);
    // rolling plot: one uPlot, redrawn at most 4 times a second, holding <= 60 s of change points
    assert.ok(before.draws >= 2 && before.draws <= wall * 4 + 2, `${before.draws} redraws in ${wall} s`);
    assert.ok(before.plotPoints > 100, `plot points: ${before.plotPoints}`);
    assert.equal(await page.$$eval('#plot-live .uplot', (u) => u.length), 1);
    // snapshot size and format version shown in the panel
    // The panel redraws on its own throttle, so a save may land between
    // reading the state and reading the text: wait until the text shows the
    // snapshot the panel holds now.
    await page.waitForFunction(() => {
      const h = window.__navguardLive;
      const text = document.querySelector('#live-snap').textContent;
      return h.info && text.startsWith(`${(h.info.bytes / 1024).toFixed(1)} KiB · format v${h.info.version} · `);
    }, null, { timeout: 5000 });
    const snapText = await page.textContent('#live-snap');
    assert.match(snapText, new RegExp(`^\\d+\\.\\d KiB · format v${SNAPSHOT_FORMAT} · navguard \\d+\\.\\d+\\.\\d+`));
    assert.ok(before.info.bytes > 10000 && before.info.version === SNAPSHOT_FORMAT, JSON.stringify(before.info));
    await page.waitForFunction(() => /^\d\d:\d\d:\d\d · [\d,]+ rows · [2-9]\d* saves$/.test(document.querySelector('#live-saved').textContent), null, { timeout: 5000 });
    await page.screenshot({ path: join(artifacts, 'page-live.png'), fullPage: true });

    await reloadForOffer(page);
    await page.waitForSelector('#live-offer:not([hidden])', { timeout: 10000 });
    const saved = await readSaved(page);
    assert.ok(saved, 'no saved live session after the reload');
    assert.equal(saved.schema, 1);
    assert.deepEqual({ kind: saved.source.kind, scenario: saved.source.scenario, seed: saved.source.seed, rows: saved.source.rows }, { kind: 'sim', scenario: 'paper', seed: 1, rows: 12500 });
    assert.equal(saved.speed, 10);
    assert.equal(saved.snapshot.length, saved.info.bytes);
    assert.ok(saved.nextRow >= before.lastSaved.nextRow && saved.nextRow <= before.nextRow + 4000, `saved at ${saved.nextRow}, before reload ${JSON.stringify(before.lastSaved)} / ${before.nextRow}`);
    assert.equal(saved.rowCount, saved.nextRow);
    assert.equal(saved.stats.rows, saved.nextRow);
    assert.ok(saved.stats.retrains >= 1, JSON.stringify(saved.stats));
    // the offer names the saved row count and retrains
    const offer = await page.textContent('#live-resume');
    const hhmmss = new Date(saved.savedAt).toLocaleTimeString('en-GB', { hour12: false });
    assert.equal(offer, `Resume live session (saved ${hhmmss}, ${saved.rowCount.toLocaleString('en-US')} rows, ${saved.stats.retrains} ${saved.stats.retrains === 1 ? 'retrain' : 'retrains'})`);
    assert.match(await page.textContent('#live-offer-detail'), new RegExp(`next row ${saved.nextRow.toLocaleString('en-US')} of 12,500 · snapshot [\\d.]+ KiB, format v${SNAPSHOT_FORMAT}`));
    assert.equal(await page.$eval('#live-panel', (e) => e.hidden), true);

    await page.click('#live-resume');
    await page.waitForFunction(() => window.__navguardLive.phase === 'running', null, { timeout: 30000 });
    assert.equal(await page.$eval('#live-offer', (e) => e.hidden), true);
    const K = 2500;
    await page.waitForFunction((n) => window.__navguardLive.nextRow >= n, saved.nextRow + K, { timeout: 60000 });
    const after = await live(page);
    // (a) the row count continues from the saved index, not from 0
    assert.equal(after.resumed, true);
    assert.equal(after.startRow, saved.nextRow);
    assert.equal(after.startRowCount, saved.rowCount);
    assert.ok(after.rowCount >= saved.rowCount + K, `rows after resume: ${after.rowCount}, saved ${saved.rowCount}`);
    assert.equal(after.rowCount, after.stats.rows);
    // the panel follows within a redraw (at most 4 a second)
    await page.waitForFunction((n) => Number(document.querySelector('#live-rows').textContent.replace(/,/g, '')) >= n, saved.rowCount + K, { timeout: 5000 });
    // (b) the resumed detector's counters are the snapshotted ones
    assert.deepEqual(after.startStats, saved.stats);
    assert.ok(after.stats.retrains >= saved.stats.retrains && after.stats.gpsEpochs > saved.stats.gpsEpochs, JSON.stringify(after.stats));

    // (c) outputs after the resume equal an uninterrupted detector's, computed
    // here with the same package; a fresh detector started at the saved row
    // (no learned state) must differ, so the comparison can fail
    const cmp = await page.evaluate(async ({ nextRow, K, savedStats }) => {
      const rec = await window.__navguardLive.fetchRecord();
      const m = await import('./pkg/navguard.js');
      await m.default();
      await m.loadLab(); // the lab module (simulators, compare, tight) loads on demand
      const log = m.readLog(new TextEncoder().encode(m.simulate('paper', 1)));
      const names = m.columnNames();
      const cols = names.map((k) => log.columns[k] || null);
      const row = new Float64Array(names.length), out = new Float64Array(8);
      const cfg = { tc: 100, window: 10, threshold: 0.5 };
      const ref = new m.Detector(cfg);
      const fresh = new m.Detector(cfg);
      const same = (a, b) => Object.is(a, b);
      let statsAtSave = null, mismatches = 0, firstMismatch = null, freshDiffers = 0, faults = 0, kinds = {};
      for (let i = 0; i < nextRow + K; i++) {
        if (i === nextRow) statsAtSave = ref.stats();
        for (let j = 0; j < cols.length; j++) row[j] = cols[j] ? cols[j][i] : NaN;
        ref.pushRowInto(row, out);
        if (i < nextRow) continue;
        const j = i - nextRow;
        const [, status, f, r, c, kind] = out;
        faults += status;
        kinds[kind] = (kinds[kind] || 0) + 1;
        if (status !== rec.status[j] || kind !== rec.kind[j] || !same(f, rec.f[j]) || !same(r, rec.r[j]) || !same(c, rec.c[j])) {
          mismatches++;
          if (!firstMismatch) firstMismatch = { row: i, ref: [status, kind, f, r, c], live: [rec.status[j], rec.kind[j], rec.f[j], rec.r[j], rec.c[j]] };
        }
        fresh.pushRowInto(row, out);
        if (!same(out[2], rec.f[j]) || out[1] !== rec.status[j]) freshDiffers++;
      }
      const refStats = ref.stats();
      ref.free();
      fresh.free();
      return { startRow: rec.startRow, n: rec.n, statsAtSave, mismatches, firstMismatch, freshDiffers, faults, kinds, refStats, savedStats };
    }, { nextRow: saved.nextRow, K, savedStats: saved.stats });
    t.diagnostic(`resumed at row ${saved.nextRow} (${saved.stats.retrains} retrains); compared ${K} rows: ${cmp.faults} flagged, kinds ${JSON.stringify(cmp.kinds)}; a fresh detector differs on ${cmp.freshDiffers}`);
    assert.equal(cmp.startRow, saved.nextRow);
    assert.ok(cmp.n >= K, `recorded ${cmp.n} rows after the resume`);
    assert.deepEqual(cmp.statsAtSave, saved.stats, 'the snapshot is not the uninterrupted detector at the saved row');
    assert.equal(cmp.mismatches, 0, `outputs differ after the resume: ${JSON.stringify(cmp.firstMismatch)}`);
    assert.ok(cmp.freshDiffers > 100, `a detector without the learned state gives the same outputs (${cmp.freshDiffers} differ): the comparison proves nothing`);
    assert.deepEqual(errors, [], `page errors:\n${errors.join('\n')}`);
  } finally {
    await page.close();
  }
});

test('live session: Discard removes the saved entry', async () => {
  const { page, errors } = await openPage();
  try {
    await startLiveScenario(page, 'gps-only', 3, 10);
    await page.waitForFunction(() => window.__navguardLive.saves >= 1, null, { timeout: 30000 });
    await reloadForOffer(page);
    assert.equal(await page.$eval('#live-offer', (e) => e.hidden), false);
    const saved = await readSaved(page);
    assert.equal(saved.source.scenario, 'gps-only');
    assert.equal(saved.source.seed, 3);
    assert.match(await page.textContent('#live-resume'), new RegExp(` ${saved.rowCount.toLocaleString('en-US')} rows, `));
    await page.click('#live-discard');
    await page.waitForFunction(() => document.querySelector('#live-offer').hidden);
    assert.equal(await readSaved(page), null);
    await reloadForOffer(page);
    assert.equal(await page.$eval('#live-offer', (e) => e.hidden), true);
    assert.equal(await readSaved(page), null);
    assert.equal(await page.evaluate(() => window.__navguardLive.phase), 'idle');
    assert.equal(await page.$eval('#error', (e) => e.hidden), true);
    assert.deepEqual(errors, [], `page errors:\n${errors.join('\n')}`);
  } finally {
    await page.close();
  }
});

// Store a live-session record made in the page: a real snapshot of a detector
// fed `rows` rows of "paper" seed 1, passed through `damage` (a function body
// over `s`, a Uint8Array, returning the bytes to store).
async function storeRecord(page, rows, damage) {
  await page.evaluate(async ({ rows, damage }) => {
    const m = await import('./pkg/navguard.js');
    await m.default();
    await m.loadLab(); // the lab module (simulators, compare, tight) loads on demand
    const log = m.readLog(new TextEncoder().encode(m.simulate('paper', 1)));
    const d = new m.Detector(undefined);
    const cols = {};
    for (const [k, v] of Object.entries(log.columns)) cols[k] = v.subarray(0, rows);
    d.pushColumns(cols);
    const stats = d.stats();
    const s = d.snapshot();
    d.free();
    // helpers for `damage`: FNV-1a 64 (the snapshot checksum) and LEB128
    const fnv = (b) => { let h = 0xcbf29ce484222325n; for (const x of b) { h ^= BigInt(x); h = (h * 0x100000001b3n) & 0xffffffffffffffffn; } return h; };
    const varint = (v) => { const o = []; do { let b = Number(v & 0x7fn); v >>= 7n; if (v) b |= 0x80; o.push(b); } while (v); return o; };
    const bytes = new Function('s', 'fnv', 'varint', damage)(s, fnv, varint);
    const rec = {
      schema: 1, snapshot: bytes, info: { version: 1, crateVersion: m.version(), bytes: bytes.length },
      source: { kind: 'sim', scenario: 'paper', seed: 1, name: 'paper-seed1.csv', rows: log.rows },
      nextRow: rows, rowCount: rows, stats, config: null, speed: 20, savedAt: Date.now(), reason: 'auto',
    };
    const db = await new Promise((res, rej) => { const r = indexedDB.open('navguard'); r.onsuccess = () => res(r.result); r.onerror = () => rej(r.error); });
    await new Promise((res, rej) => {
      const t = db.transaction('live-session', 'readwrite');
      t.objectStore('live-session').put(rec, 'current');
      t.oncomplete = res;
      t.onerror = () => rej(t.error);
    });
    db.close();
  }, { rows, damage });
}

test('live session: a damaged or foreign-version snapshot shows the error banner, is discarded, and throws nothing', async () => {
  const { page, errors } = await openPage();
  try {
    // control: an intact record is offered and resumes at its row
    await storeRecord(page, 3000, 'return s;');
    await reloadForOffer(page);
    assert.equal(await page.$eval('#live-offer', (e) => e.hidden), false);
    assert.match(await page.textContent('#live-resume'), /, 3,000 rows, \d+ retrains?\)$/);
    await page.click('#live-resume');
    await page.waitForFunction(() => window.__navguardLive.phase === 'running', null, { timeout: 30000 });
    assert.equal(await page.evaluate(() => window.__navguardLive.startRowCount), 3000);
    await page.click('#live-stop');
    // idle at once; the saved session is gone once the stop has finished
    await page.waitForFunction(() => window.__navguardLive.phase === 'idle' && !window.__navguardLive.stopping);
    assert.equal(await readSaved(page), null, 'Stop did not remove the saved session');

    // another format version: rejected on load by snapshotInfo, never offered
    // version 99: a future format (one varint byte), whatever this build reads
    await storeRecord(page, 1000, 's = s.slice(); s[1 + s[0]] = 99; return s;');
    await reloadForOffer(page);
    let banner = await page.$eval('#error', (e) => (e.hidden ? '' : e.textContent));
    assert.match(banner, /saved live session was discarded: snapshot: version 99 \(written by navguard [\d.]+\) cannot be read by navguard [\d.]+, which reads version \d+/);
    assert.equal(await page.$eval('#live-offer', (e) => e.hidden), true);
    assert.equal(await readSaved(page), null);

    // a damaged body: the checksum catches it on load
    await storeRecord(page, 1000, 's = s.slice(); s[s.length - 100] ^= 0x5a; return s;');
    await reloadForOffer(page);
    banner = await page.$eval('#error', (e) => (e.hidden ? '' : e.textContent));
    assert.match(banner, /saved live session was discarded: snapshot: checksum mismatch/);
    assert.equal(await readSaved(page), null);

    // a truncated body with a matching checksum passes snapshotInfo, so it is
    // offered; Detector.restore throws on Resume: banner, entry discarded
    await storeRecord(page, 1000, `
      let p = 1 + s[0]; p++; p += 1 + s[p];
      let q = p; while (s[q] & 0x80) q++; q++;
      const body = s.slice(q, q + ((s.length - q) >> 1));
      return new Uint8Array([...s.subarray(0, p), ...varint(fnv(body)), ...body]);`);
    await reloadForOffer(page);
    assert.equal(await page.$eval('#error', (e) => e.hidden), true);
    assert.equal(await page.$eval('#live-offer', (e) => e.hidden), false);
    await page.click('#live-resume');
    await page.waitForFunction(() => !document.querySelector('#error').hidden, null, { timeout: 30000 });
    banner = await page.textContent('#error');
    assert.match(banner, /Could not resume the saved live session, so it was discarded: snapshot: body does not parse/);
    assert.equal(await page.evaluate(() => window.__navguardLive.phase), 'idle');
    assert.equal(await page.$eval('#live-offer', (e) => e.hidden), true);
    assert.equal(await page.$eval('#live-panel', (e) => e.hidden), true);
    await page.waitForFunction(async () => (await window.__navguardLive.readSaved()) === undefined, null, { timeout: 10000 });
    // the audit UI still works afterwards
    await page.selectOption('#scenario', 'gps-only');
    await page.click('#sim-run');
    await waitDone(page);
    assert.deepEqual(errors, [], `page errors:\n${errors.join('\n')}`);
  } finally {
    await page.close();
  }
});

test('live session from a log file: file kept in IndexedDB, pause saves, re-open check when the file is not stored', async () => {
  const { page, errors } = await openPage();
  try {
    // 300 s of 10 Hz GPS-only flight heading north at 5 m/s
    const lines = ['t,lat,lon,alt,vn,ve,vd,fix,sats,eph'];
    for (let i = 0; i < 3000; i++) {
      const t = i * 0.1;
      lines.push(`${t.toFixed(1)},${(31.94 + (5 * t) / 111320).toFixed(9)},118.79,50,5,0,0,3,11,0.9`);
    }
    const csv = Buffer.from(lines.join('\n') + '\n');
    const file = { name: 'flight.csv', mimeType: 'text/csv', buffer: csv };
    await page.selectOption('#live-source', 'file');
    assert.equal(await page.$eval('#live-file-row', (e) => e.hidden), false);
    await page.setInputFiles('#live-file', file);
    await page.selectOption('#live-speed', '10');
    await page.click('#live-start');
    await page.waitForFunction(() => window.__navguardLive.phase === 'running' && window.__navguardLive.saves >= 1, null, { timeout: 30000 });
    assert.equal(await page.evaluate(() => window.__navguardLive.totalRows), 3000);

    // visibilitychange to hidden stores a fresh snapshot
    await page.evaluate(() => {
      Object.defineProperty(document, 'visibilityState', { configurable: true, get: () => 'hidden' });
      document.dispatchEvent(new Event('visibilitychange'));
      delete document.visibilityState;
    });
    await page.waitForFunction(() => window.__navguardLive.lastSaved.reason === 'hidden', null, { timeout: 10000 });

    // pausing stores the exact state: the saved row is the paused row
    await page.click('#live-pause');
    await page.waitForFunction(() => window.__navguardLive.lastSaved.reason === 'pause', null, { timeout: 10000 });
    const paused = await live(page);
    assert.equal(paused.phase, 'paused');
    let saved = await readSaved(page);
    assert.equal(saved.nextRow, paused.nextRow);
    assert.equal(saved.rowCount, paused.rowCount);
    assert.ok(saved.nextRow > 100 && saved.nextRow < 3000, `paused at ${saved.nextRow}`);
    assert.deepEqual(saved.source, { kind: 'file', name: 'flight.csv', size: csv.length, lastModified: saved.source.lastModified, fileStored: true, rows: 3000 });
    await page.waitForTimeout(600);
    assert.equal((await live(page)).nextRow, paused.nextRow, 'rows kept flowing while paused');
    const storedFile = await page.evaluate(() => new Promise((res, rej) => {
      const r = indexedDB.open('navguard');
      r.onerror = () => rej(r.error);
      r.onsuccess = () => {
        const g = r.result.transaction('live-file').objectStore('live-file').get('current');
        g.onsuccess = () => { r.result.close(); res(g.result ? { name: g.result.name, size: g.result.size, bytes: g.result.bytes.byteLength } : null); };
      };
    }));
    assert.deepEqual(storedFile, { name: 'flight.csv', size: csv.length, bytes: csv.length });

    // reload: resumes from the stored file without asking for it
    await reloadForOffer(page);
    assert.match(await page.textContent('#live-offer-detail'), new RegExp(`flight\\.csv .* next row ${saved.nextRow.toLocaleString('en-US')} of 3,000`));
    assert.match(await page.textContent('#live-resume'), new RegExp(` ${saved.rowCount.toLocaleString('en-US')} rows, `));
    await page.click('#live-resume');
    await page.waitForFunction(() => window.__navguardLive.phase === 'running', null, { timeout: 30000 });
    let after = await live(page);
    assert.equal(after.startRow, saved.nextRow);
    assert.deepEqual(after.startStats, saved.stats);
    assert.equal(after.speed, 10);

    // without the stored file, Resume asks for it and checks name and size
    await page.click('#live-pause');
    await page.waitForFunction(() => window.__navguardLive.lastSaved && window.__navguardLive.lastSaved.reason === 'pause', null, { timeout: 10000 });
    saved = await readSaved(page);
    await page.evaluate(() => new Promise((res, rej) => {
      const r = indexedDB.open('navguard');
      r.onerror = () => rej(r.error);
      r.onsuccess = () => { const t = r.result.transaction('live-file', 'readwrite'); t.objectStore('live-file').delete('current'); t.oncomplete = () => { r.result.close(); res(); }; };
    }));
    await reloadForOffer(page);
    await page.click('#live-resume');
    await page.waitForSelector('#live-reopen:not([hidden])', { timeout: 5000 });
    assert.match(await page.textContent('#live-offer-detail'), new RegExp(`re-open flight\\.csv \\(${csv.length.toLocaleString('en-US')} bytes\\)`));
    await page.setInputFiles('#live-reopen-file', { name: 'flight.csv', mimeType: 'text/csv', buffer: csv.subarray(0, csv.length - 40) });
    await page.waitForFunction(() => !document.querySelector('#error').hidden, null, { timeout: 5000 });
    assert.match(await page.textContent('#error'), /not the log of the saved live session: expected flight\.csv/);
    assert.equal(await page.evaluate(() => window.__navguardLive.phase), 'idle');
    assert.equal(await page.$eval('#live-offer', (e) => e.hidden), false);
    assert.ok(await readSaved(page), 'a wrong file discarded the saved session');
    await page.setInputFiles('#live-reopen-file', file);
    await page.waitForFunction(() => window.__navguardLive.phase === 'running', null, { timeout: 30000 });
    after = await live(page);
    assert.equal(after.startRow, saved.nextRow);
    assert.equal(after.startRowCount, saved.rowCount);
    assert.equal(await page.$eval('#error', (e) => e.hidden), true);
    assert.deepEqual(errors, [], `page errors:\n${errors.join('\n')}`);
  } finally {
    await page.close();
  }
});

// ---------------------------------------------------------- compare methods

// Rust's `{:.d$}` (what the CLI prints): ties to even, "–" for NaN.
function rustFixed(x, d) {
  if (!Number.isFinite(x)) return '–';
  const long = x.toFixed(d + 25);
  if (long.endsWith('5' + '0'.repeat(24))) {
    let t = long.slice(0, long.length - 25);
    if (t.endsWith('.')) t = t.slice(0, -1);
    if (Number(t[t.length - 1]) % 2 === 0) return t;
  }
  return x.toFixed(d);
}

async function runCompare(page, seeds) {
  await page.fill('#compare-seeds', String(seeds));
  await page.click('#compare-run');
  await page.waitForFunction(() => {
    const c = window.navguard.compare;
    return c && !c.running && (c.result || /failed|cancelled|interrupted/.test(c.status));
  }, null, { timeout: 180000 });
  const status = await page.evaluate(() => window.navguard.compare.status);
  assert.match(status, /^100 % · done in/, `comparison did not finish: ${status}`);
}

test('compare methods: all 8 methods over seed 1, progress to 100 %, tables match a direct CompareRun', async () => {
  const { page, errors } = await openPage('research');
  try {
    assert.equal(await page.$eval('#compare-seeds', (e) => e.value), '3');
    await runCompare(page, 1);

    // a real progress bar: several slices, increasing, ending at 1
    const prog = await page.evaluate(() => window.navguard.compare.progressLog);
    assert.ok(prog.length >= 3, `expected several progress messages: ${JSON.stringify(prog)}`);
    assert.equal(prog[0].frac, 0);
    assert.equal(prog[prog.length - 1].frac, 1);
    for (let i = 1; i < prog.length; i++) assert.ok(prog[i].frac > prog[i - 1].frac, `progress went backwards: ${JSON.stringify(prog)}`);
    assert.equal(await page.$eval('#compare-bar', (b) => b.value), 1);
    assert.match(await page.textContent('#compare-detail'), /^100 %/);
    assert.equal(await page.$eval('#compare-cancel', (b) => getComputedStyle(b).display), 'none', 'Cancel still shown after the run');

    // (a) one row per method, best F2 highlighted
    const rows = await page.$$eval('#compare-methods tbody tr', (trs) => trs.map((tr) => ({
      method: tr.dataset.method,
      best: tr.classList.contains('best'),
      cells: Array.from(tr.querySelectorAll('td.num')).map((td) => td.textContent),
    })));
    assert.deepEqual(rows.map((r) => r.method), ['anfis', 'chi2', 'nis', 'gate', 'mahalanobis', 'rms', 'knee', 'adaptive']);
    for (const r of rows) {
      assert.equal(r.cells.length, 6);
      for (const c of r.cells.slice(0, 4)) assert.match(c, /^(\d\.\d{4}|–)$/, `${r.method}: ${c}`);
      assert.match(r.cells[4], /^(\d+\.\d|–)$/);
      assert.match(r.cells[5], /^(\d+\.\d\d%|–%)$/);
    }
    const f2s = rows.map((r) => Number(r.cells[3]));
    const bestRows = rows.filter((r) => r.best);
    assert.ok(bestRows.length >= 1);
    for (const b of bestRows) assert.equal(Number(b.cells[3]), Math.max(...f2s.filter(Number.isFinite)));

    // (b) fault kinds × methods
    const kinds = await page.$$eval('#compare-kinds tbody tr', (trs) => trs.map((tr) => [tr.dataset.kind, ...Array.from(tr.querySelectorAll('td.num')).map((td) => td.textContent)]));
    assert.ok(kinds.length >= 5, JSON.stringify(kinds));
    assert.ok(kinds.some((k) => k[0] === 'step') && kinds.some((k) => k[0] === 'outage'), JSON.stringify(kinds));
    for (const k of kinds) {
      assert.equal(k.length, 9);
      for (const c of k.slice(1)) assert.match(c, /^\d+\/\d+ · (\d+\.\d|–)$/, `${k[0]}: ${c}`);
    }
    // no real log added: no (c) table
    assert.equal(await page.$('#compare-logs'), null);

    // the same CompareRun, directly in the page with the same pkg
    const direct = await page.evaluate(async () => {
      const m = await import('./pkg/navguard.js');
      await m.default();
      await m.loadLab(); // the lab module (simulators, compare, tight) loads on demand
      const run = new m.CompareRun({ seeds: 1 });
      let n = 0;
      while (run.step() < 1 && n < 100000) n++;
      const out = run.finish();
      run.free();
      const a = out.comparison.methods.find((x) => x.method === 'anfis');
      return { f2: a.metrics.f2, accuracy: a.metrics.accuracy, methods: out.comparison.methods.length, markdown: out.markdown };
    });
    assert.equal(direct.methods, 8);
    const anfis = rows.find((r) => r.method === 'anfis');
    assert.equal(anfis.cells[3], rustFixed(direct.f2, 4), `anfis F2 shown ${anfis.cells[3]}, direct ${direct.f2}`);
    assert.equal(anfis.cells[0], rustFixed(direct.accuracy, 4));
    // and exactly what the CLI's Markdown (built in Rust) prints for that row
    const mdRow = direct.markdown.split('\n').find((l) => /^\| (\*\*)?anfis(\*\*)? \|/.test(l));
    assert.ok(mdRow, direct.markdown);
    assert.equal(mdRow.split('|')[5].trim(), anfis.cells[3]);
    // the worker's Markdown equals the direct one, and Copy Markdown copies it
    const md = await page.evaluate(() => window.navguard.compare.markdown);
    assert.equal(md, direct.markdown);
    assert.equal(await page.$eval('#compare-md', (e) => e.textContent), direct.markdown);
    await page.context().grantPermissions(['clipboard-read', 'clipboard-write'], { origin: base.replace(/\/$/, '') });
    await page.click('#compare-copy');
    await page.waitForFunction(() => document.querySelector('#compare-copy-state').textContent !== '', null, { timeout: 5000 });
    assert.equal(await page.textContent('#compare-copy-state'), 'copied');
    const clip = await page.evaluate(() => navigator.clipboard.readText().catch((e) => `unreadable: ${e.message}`));
    if (!clip.startsWith('unreadable')) assert.equal(clip, direct.markdown);

    await page.screenshot({ path: join(artifacts, 'page-compare.png'), fullPage: true });
    assert.deepEqual(errors, [], `page errors:\n${errors.join('\n')}`);
  } finally {
    await page.close();
  }
});

test('compare methods: a subset of methods with the opened log adds the real-log table; cancel keeps the worker', async () => {
  const { page, errors } = await openPage('research');
  try {
    assert.equal(await page.$eval('#compare-log', (e) => e.disabled), true);
    // a 60 s GPS-only CSV, opened (and audited) through the file input
    const lines = ['t,lat,lon,alt,vn,ve,vd,fix,sats,eph'];
    for (let i = 0; i <= 600; i++) {
      const t = i * 0.1;
      lines.push(`${t.toFixed(1)},${(31.94 + (5 * t) / 111320).toFixed(9)},118.79,50,5,0,0,3,11,0.9`);
    }
    await page.setInputFiles('#file', { name: 'mine.csv', mimeType: 'text/csv', buffer: Buffer.from(lines.join('\n') + '\n') });
    await waitDone(page);
    assert.equal(await page.$eval('#compare-log', (e) => e.disabled), false);
    assert.match(await page.textContent('#compare-log-name'), /mine\.csv/);

    // cancel a 10-seed run once it has started: the worker (and its log) stay
    await page.fill('#compare-seeds', '10');
    await page.click('#compare-run');
    await page.waitForFunction(() => window.navguard.compare.progressLog.some((p) => p.frac > 0), null, { timeout: 60000 });
    assert.notEqual(await page.$eval('#compare-cancel', (b) => getComputedStyle(b).display), 'none', 'no Cancel button while running');
    await page.click('#compare-cancel');
    await page.waitForFunction(() => !window.navguard.compare.running, null, { timeout: 30000 });
    assert.equal(await page.evaluate(() => window.navguard.compare.status), 'cancelled');
    assert.equal(await page.evaluate(() => window.navguard.compare.result), null);
    assert.equal(await page.evaluate(() => window.navguard.workerHasLog), true);

    // two methods, the opened log included
    for (const m of ['nis', 'gate', 'mahalanobis', 'rms', 'knee', 'adaptive']) await page.uncheck(`#compare-method-list input[value="${m}"]`);
    await page.check('#compare-log');
    await runCompare(page, 1);
    const methods = await page.$$eval('#compare-methods tbody tr', (trs) => trs.map((tr) => tr.dataset.method));
    assert.deepEqual(methods, ['anfis', 'chi2']);
    const logs = await page.$$eval('#compare-logs tbody tr', (trs) => trs.map((tr) => Array.from(tr.cells).map((td) => td.textContent)));
    assert.equal(logs.length, 1);
    assert.match(logs[0][0], /^mine\.csv \(\d+ epochs\)$/);
    for (const c of logs[0].slice(1)) assert.match(c, /^\d+\.\d\d%$/);
    assert.match(await page.evaluate(() => window.navguard.compare.markdown), /Real logs \(no labels\)[\s\S]*\| mine\.csv \(\d+ epochs\) \|/);
    // nothing disabled with no method ticked
    await page.uncheck('#compare-method-list input[value="anfis"]');
    await page.uncheck('#compare-method-list input[value="chi2"]');
    assert.equal(await page.$eval('#compare-run', (b) => b.disabled), true);
    assert.deepEqual(errors, [], `page errors:\n${errors.join('\n')}`);
  } finally {
    await page.close();
  }
});

test('detector config: method chi2 reaches the worker and changes the audit; Defaults restores anfis', async () => {
  const { page, errors } = await openPage();
  try {
    assert.equal(await page.$eval('#config [name=method]', (e) => e.value), 'anfis');
    await page.selectOption('#scenario', 'paper');
    await page.fill('#seed', '1');
    await page.click('#sim-run');
    await waitDone(page);
    const snap = () => page.evaluate(() => {
      const m = window.navguard.result;
      return { method: m.checkedConfig.method, metrics: m.report.metrics, flagged: m.report.flaggedGpsEpochFraction, retrains: m.report.stats.retrains, faults: m.report.faults.length };
    });
    const a = await snap();
    assert.equal(a.method, 'anfis');
    assert.match(await page.textContent('#summary'), /Method\s*anfis/);

    // choosing chi2 reruns the audit with it
    let renders = await page.evaluate(() => window.navguard.renders);
    await page.selectOption('#config [name=method]', 'chi2');
    await page.waitForFunction((n) => window.navguard.renders > n && document.body.dataset.state === 'done', renders, { timeout: 60000 });
    assert.equal((await page.evaluate(() => window.navguard.config)).method, 'chi2');
    const b = await snap();
    assert.equal(b.method, 'chi2', 'the worker did not audit with chi2');
    assert.match(await page.textContent('#summary'), /Method\s*chi2/);
    assert.notDeepEqual(b.metrics, a.metrics, 'chi2 and anfis gave identical metrics');
    assert.ok(b.metrics.tp !== a.metrics.tp || b.metrics.fp !== a.metrics.fp, `tp/fp unchanged: ${JSON.stringify([a.metrics, b.metrics])}`);
    // chi2 decides at score 1: the F plot's decision line says so
    assert.match(await page.textContent('#plot-f .u-legend'), /fault at 1 \(chi2\)/);

    // Defaults puts anfis back and reruns
    renders = await page.evaluate(() => window.navguard.renders);
    await page.click('#config-reset');
    await page.waitForFunction((n) => window.navguard.renders > n && document.body.dataset.state === 'done', renders, { timeout: 60000 });
    assert.equal(await page.$eval('#config [name=method]', (e) => e.value), 'anfis');
    const c = await snap();
    assert.equal(c.method, 'anfis');
    assert.deepEqual(c.metrics, a.metrics);
    assert.deepEqual(errors, [], `page errors:\n${errors.join('\n')}`);
  } finally {
    await page.close();
  }
});

// ------------------------------------------------- tightly coupled GNSS/INS

test('tightly coupled panel: Env 1, 20 m step, seed 7 names the injected satellite at once; navguard-tight figures load', async () => {
  const { page, errors } = await openPage('research');
  try {
    await page.selectOption('#tight-env', '1');
    await page.selectOption('#tight-type', '1');
    await page.fill('#tight-seed', '7');
    await page.click('#tight-run');
    await page.waitForFunction(() => {
      const t = window.navguard.tight;
      return t && !t.running && (t.result || /failed|interrupted/.test(t.status));
    }, null, { timeout: 60000 });
    const status = await page.evaluate(() => window.navguard.tight.status);
    assert.match(status, /^done in/, `tight run did not finish: ${status}`);

    // the same simulation, directly in the page with the same pkg
    const direct = await page.evaluate(async () => {
      const m = await import('./pkg/navguard.js');
      await m.default();
      await m.loadLab(); // the lab module (simulators, compare, tight) loads on demand
      const s = m.tightSimulate(1, 1, 7);
      return { faultyPrn: s.faultyPrn, faultStart: s.faultStart, faultEnd: s.faultEnd };
    });
    assert.ok(Number.isInteger(direct.faultyPrn), JSON.stringify(direct));
    const prnCell = await page.textContent('#tight-table tr[data-key="prn"] td');
    assert.match(prnCell, new RegExp(`^G${direct.faultyPrn} vs G${direct.faultyPrn} ✓$`), `named satellite: ${prnCell}`);
    assert.equal(await page.$eval('#tight-table tr[data-key="prn"] [data-ok]', (e) => e.dataset.ok), 'true');
    assert.equal(await page.textContent('#tight-table tr[data-key="delay"] td'), '0.0 s');
    assert.equal(await page.textContent('#tight-table tr[data-key="first"] td'), `${direct.faultStart.toFixed(1)} s`);
    assert.equal(await page.textContent('#tight-table tr[data-key="before"] td'), '0');
    assert.match(await page.textContent('#tight-table tr[data-key="share"] td'), /^\d+\/\d+ \(\d+\.\d %\)$/);
    const sum = await page.evaluate(() => ({ ...window.navguard.tight.summary, faultStart: window.navguard.tight.result.faultStart }));
    assert.equal(sum.faultStart, direct.faultStart);
    assert.ok(sum.sectionShare > 0.5, JSON.stringify(sum));

    // the statistic plot: a canvas, |λ| against T1 = 3.291 (α 0.001)
    const sizes = await page.$$eval('#tight-plot-lambda .uplot canvas, #tight-plot-rdpop .uplot canvas', (cs) => cs.map((c) => [c.width, c.height]));
    assert.equal(sizes.length, 2, 'expected the |λ| and RDPOP plots');
    for (const [w, h] of sizes) assert.ok(w > 0 && h > 0, `canvas has zero size: ${w}x${h}`);
    assert.match(await page.textContent('#tight-plot-lambda .u-legend'), /T1 = 3\.291/);
    assert.ok(await page.evaluate(() => window.navguard.tight.t1 > 3.29 && window.navguard.tight.t1 < 3.292));

    // the four navguard-tight figures
    await page.waitForFunction(() => Array.from(document.querySelectorAll('#tight-figs img')).every((i) => i.complete), null, { timeout: 10000 });
    const imgs = await page.$$eval('#tight-figs img', (is) => is.map((i) => [i.getAttribute('src'), i.naturalWidth]));
    assert.deepEqual(imgs.map((i) => i[0]), ['figures/tight_fig7_rdpop.svg', 'figures/tight_fig8_env_errors.svg', 'figures/tight_fig11_fault_types.svg', 'figures/tight_fig12_relative_error.svg']);
    for (const [src, w] of imgs) assert.ok(w > 0, `${src} did not load (naturalWidth ${w})`);

    await page.$eval('#tight-panel', (e) => e.scrollIntoView());
    await page.screenshot({ path: join(artifacts, 'page-tight.png'), fullPage: true });
    assert.deepEqual(errors, [], `page errors:\n${errors.join('\n')}`);
  } finally {
    await page.close();
  }
});

test('tightly coupled panel: GAN-FDSR (embedded model) names the injected satellite and plots the GAN score', async () => {
  const { page, errors } = await openPage('research');
  try {
    await page.selectOption('#tight-env', '1');
    await page.selectOption('#tight-type', '1');
    await page.fill('#tight-seed', '7');
    await page.selectOption('#tight-strategy', 'gan');
    await page.click('#tight-run');
    await page.waitForFunction(() => {
      const t = window.navguard.tight;
      return t && !t.running && (t.result || /failed|interrupted/.test(t.status));
    }, null, { timeout: 90000 });
    const status = await page.evaluate(() => window.navguard.tight.status);
    assert.match(status, /^done in/, `tight run did not finish: ${status}`);

    // the same flight through a GAN-FDSR TightDetector directly in the page
    const direct = await page.evaluate(async () => {
      const m = await import('./pkg/navguard.js');
      await m.default();
      await m.loadLab(); // the lab module (simulators, compare, tight) loads on demand
      const s = m.tightSimulate(1, 1, 7);
      const out = new m.TightDetector({ ...s.config, strategy: 'gan' }).pushCsv(s.csv);
      const first = out.find((o) => o.status === 'fault' && o.t >= s.faultStart);
      const scores = out.map((o) => o.ganScoreMax).filter((v) => typeof v === 'number' && Number.isFinite(v));
      return { faultyPrn: s.faultyPrn, faultStart: s.faultStart, firstT: first?.t, firstPrn: first?.faultyPrn, maxScore: Math.max(...scores) };
    });
    assert.equal(direct.firstPrn, direct.faultyPrn, JSON.stringify(direct));
    const prnCell = await page.textContent('#tight-table tr[data-key="prn"] td');
    assert.match(prnCell, new RegExp(`^G${direct.faultyPrn} vs G${direct.faultyPrn} ✓$`), `named satellite: ${prnCell}`);
    assert.equal(await page.textContent('#tight-table tr[data-key="first"] td'), `${direct.firstT.toFixed(1)} s`);
    // measured in Node: 5 s after the onset with seed 7 (FDI: 0 s)
    const delay = await page.textContent('#tight-table tr[data-key="delay"] td');
    assert.equal(delay, `${(direct.firstT - direct.faultStart).toFixed(1)} s`);
    assert.ok(direct.firstT - direct.faultStart <= 5 + 1e-6, delay);
    assert.equal(await page.textContent('#tight-table tr[data-key="before"] td'), '0');
    assert.equal(await page.textContent('#tight-table tr[data-key="other"] td'), '0');
    assert.match(await page.textContent('#tight-table tr[data-key="setup"] td'), /^gan · 3\.291/);
    assert.equal(await page.textContent('#tight-table tr[data-key="gan"] td'), `embedded default · — · ${direct.maxScore.toFixed(3)}`);

    // the GAN score plot: a third synchronised plot with the per-epoch scores
    assert.equal(await page.$eval('#tight-fig-gan', (e) => e.hidden), false);
    const sizes = await page.$$eval('#tight-plot-gan .uplot canvas', (cs) => cs.map((c) => [c.width, c.height]));
    assert.equal(sizes.length, 1, 'expected the GAN score plot');
    assert.ok(sizes[0][0] > 0 && sizes[0][1] > 0, `canvas ${sizes[0]}`);
    assert.match(await page.textContent('#tight-plot-gan .u-legend'), /max GAN score/);
    const st = await page.evaluate(() => ({ n: window.navguard.tight.plots.length, scores: window.navguard.tight.result.epochs.ganScore, epochs: window.navguard.tight.result.epochs.t.length }));
    assert.equal(st.n, 3);
    const finite = st.scores.filter((v) => v != null);
    assert.ok(finite.length > 350 && finite.length <= st.epochs, `${finite.length} scores of ${st.epochs} epochs`);
    assert.equal(Math.max(...finite), direct.maxScore);

    // back to FDI: the GAN plot goes away
    await page.selectOption('#tight-strategy', 'fdi');
    await page.click('#tight-run');
    await page.waitForFunction(() => !window.navguard.tight.running && window.navguard.tight.result.strategy === 'fdi', null, { timeout: 60000 });
    assert.equal(await page.$eval('#tight-fig-gan', (e) => e.hidden), true);
    assert.equal(await page.evaluate(() => window.navguard.tight.plots.length), 2);
    assert.deepEqual(errors, [], `page errors:\n${errors.join('\n')}`);
  } finally {
    await page.close();
  }
});

test('tightly coupled panel: train a GAN in the browser (cancel, then 1 epoch), then run with the trained model', async () => {
  const { page, errors } = await openPage('research');
  try {
    await page.click('#tight-gan summary');
    assert.equal(await page.$eval('#tight-use-trained', (e) => e.disabled), true);
    // Cancel: the training worker is ended at once, the panel says so.
    await page.fill('#tight-gan-epochs', '3');
    await page.click('#tight-gan-train');
    assert.equal(await page.$eval('#tight-gan-cancel', (e) => e.hidden), false);
    await page.click('#tight-gan-cancel');
    assert.match(await page.textContent('#tight-gan-detail'), /^cancelled after 0 epochs$/);
    assert.equal(await page.$eval('#tight-gan-train', (e) => e.disabled), false);
    assert.equal(await page.evaluate(() => window.navguard.tight.gan.result), null);

    // One epoch on one training flight (two calibration flights).
    await page.fill('#tight-gan-epochs', '1');
    await page.fill('#tight-gan-flights', '1');
    await page.click('#tight-gan-train');
    await page.waitForFunction(() => window.navguard.tight.gan.progress.length >= 1 || !window.navguard.tight.gan.running, null, { timeout: 180000 });
    await page.waitForFunction(() => !window.navguard.tight.gan.running, null, { timeout: 180000 });
    const g = await page.evaluate(() => {
      const G = window.navguard.tight.gan;
      return { status: G.status, progress: G.progress, result: G.result && { ...G.result, model: G.result.model.length } };
    });
    assert.match(g.status, /^trained in \d+\.\d s · 1 epoch · /, g.status);
    assert.equal(g.progress.length, 1);
    assert.deepEqual([g.progress[0].epoch, g.progress[0].epochs], [1, 1]);
    for (const k of ['dLoss', 'gLoss', 'dReal', 'dFake']) assert.ok(Number.isFinite(g.progress[0][k]), `${k} ${g.progress[0][k]}`);
    const r = g.result;
    assert.ok(r.model > 1000 && r.t2 > 0 && r.lambda > 0 && r.lambda < 1 && r.parameters > 100 && r.tau >= 1 && r.m >= 2, JSON.stringify(r));
    assert.equal(await page.$eval('#tight-gan-bar', (e) => e.hidden), true);
    // the results as HTML tables
    assert.equal(await page.textContent('#tight-gan-table tr[data-key="t2"] td'), r.t2.toFixed(4));
    assert.equal(await page.textContent('#tight-gan-table tr[data-key="m"] td'), String(r.m));
    assert.equal(await page.textContent('#tight-gan-table tr[data-key="params"] td'), String(r.parameters));
    const t1 = await page.$$eval('#tight-gan-table1 tbody tr', (trs) => trs.map((tr) => Array.from(tr.cells, (c) => c.textContent)));
    assert.equal(t1.length, 9, JSON.stringify(t1));
    for (const row of t1) {
      assert.match(row[0], /^G\d+$/);
      assert.ok(Number(row[1]) >= 1 && Number(row[2]) >= 2 && Number.isFinite(Number(row[3])), JSON.stringify(row));
      // Cao E2 range: near 1 for the simulated (stochastic) series.
      const [lo, hi] = row[4].split('–').map(Number);
      assert.ok(lo > 0.5 && lo <= hi && hi < 1.5, JSON.stringify(row));
    }
    assert.deepEqual(await page.$$eval('#tight-gan-table1 thead th', (ths) => ths.map((th) => th.textContent)), ['Satellite', 'τ', 'm', 'Largest Lyapunov exponent', 'Cao E2 (min–max over d)']);

    // the next run uses the trained model (strategy switched to GAN-FDSR)
    assert.equal(await page.$eval('#tight-use-trained', (e) => !e.disabled && e.checked), true);
    assert.equal(await page.$eval('#tight-strategy', (e) => e.value), 'gan');
    await page.selectOption('#tight-env', '1');
    await page.selectOption('#tight-type', '1');
    await page.fill('#tight-seed', '7');
    await page.click('#tight-run');
    await page.waitForFunction(() => {
      const t = window.navguard.tight;
      return t && !t.running && (t.result || /failed|interrupted/.test(t.status));
    }, null, { timeout: 90000 });
    const status = await page.evaluate(() => window.navguard.tight.status);
    assert.match(status, /^done in/, `tight run did not finish: ${status}`);
    const res = await page.evaluate(() => ({ ganModel: window.navguard.tight.result.ganModel, ganT2: window.navguard.tight.result.ganT2, faultyPrn: window.navguard.tight.result.faultyPrn }));
    assert.deepEqual(res, { ganModel: 'trained', ganT2: r.t2, faultyPrn: res.faultyPrn });
    assert.match(await page.textContent('#tight-table tr[data-key="gan"] td'), new RegExp(`^trained here · ${r.t2.toFixed(3)} · \\d\\.\\d{3}$`));
    assert.match(await page.textContent('#tight-plot-gan .u-legend'), new RegExp(`T2 = ${r.t2.toFixed(3)}`));
    const prnCell = await page.textContent('#tight-table tr[data-key="prn"] td');
    assert.match(prnCell, new RegExp(`^G${res.faultyPrn} vs G${res.faultyPrn} ✓$`), `named satellite: ${prnCell}`);

    await page.$eval('#tight-panel', (e) => e.scrollIntoView());
    await page.screenshot({ path: join(artifacts, 'page-tight-gan.png'), fullPage: true });
    assert.deepEqual(errors, [], `page errors:\n${errors.join('\n')}`);
  } finally {
    await page.close();
  }
});
