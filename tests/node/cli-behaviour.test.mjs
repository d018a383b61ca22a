// The CLI behaves like the tools its users know (issue 16, item 4): help
// and version everywhere, misspellings caught with a suggestion, a recursive
// DIR audit that counts what it skipped, exit codes 0 clean / 1 faults
// (with --fail-on-fault) / 2 unreadable, "no verdict" distinct from clean in
// every output, quiet on a closed pipe, progress on a terminal only.
import { test, before } from 'node:test';
import assert from 'node:assert/strict';
import { spawnSync, execFileSync } from 'node:child_process';
import { mkdtempSync, readFileSync, writeFileSync, mkdirSync, copyFileSync, readdirSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

const root = join(dirname(fileURLToPath(import.meta.url)), '..', '..');
const cli = join(root, 'pkg', 'bin', 'navguard.mjs');
const data = join(root, '..', 'shared', 'data');
const tmp = mkdtempSync(join(tmpdir(), 'navguard-cli16-'));
const run = (args, opts = {}) => spawnSync(process.execPath, [cli, ...args], { encoding: 'utf8', timeout: 120000, ...opts });
const fleet = join(tmp, 'fleet');
const step = join(fleet, 'flights', 'step.csv');
const clean = join(fleet, 'clean.csv');
const imuOnly = join(fleet, 'imu-only.csv');

before(() => {
  mkdirSync(join(fleet, 'flights'), { recursive: true });
  execFileSync(process.execPath, [cli, 'simulate', 'step', '--seed', '3', '--out', step]);
  execFileSync(process.execPath, [cli, 'simulate', 'clean-paper', '--seed', '1', '--out', clean]);
  const rows = ['t,ax,ay,az,gx,gy,gz,qw,qx,qy,qz,baro'];
  for (let i = 0; i < 500; i++) rows.push(`${(i / 50).toFixed(2)},0,0,-9.81,0,0,0,1,0,0,0,10`);
  writeFileSync(imuOnly, rows.join('\n') + '\n');
  writeFileSync(join(fleet, 'notes.txt'), 'not a log\n');
});

test('--help and --version answer for every command, with exit 0, and run nothing', () => {
  for (const cmd of ['audit', 'simulate', 'report', 'train', 'compare']) {
    for (const args of [[cmd, '--help'], [cmd, '-h'], ['help', cmd]]) {
      const r = run(args, { timeout: 10000 });
      assert.equal(r.status, 0, `${args.join(' ')}: ${r.stderr}`);
      assert.match(r.stdout, new RegExp(`^navguard ${cmd} `), args.join(' '));
      assert.equal(r.stderr, '', args.join(' '));
    }
    assert.match(run([cmd, '--version']).stdout, /^navguard \d+\.\d+\.\d+\n$/);
  }
  assert.match(run(['audit', '--help']).stdout, /--html FILE/);
  assert.match(run(['report', '--help']).stdout, /^navguard report FILE --html OUT\.html/);
  assert.match(run(['--help']).stdout, /navguard report FILE --html OUT\.html/);
});

test('misspelt flags are errors naming the closest flag; a flag of another mode is refused', () => {
  const r = run(['audit', step, '--htm', join(tmp, 'x.html')]);
  assert.equal(r.status, 2);
  assert.match(r.stderr, /^navguard: audit: unknown option --htm \(did you mean --html\?\)/);
  assert.match(run(['report', step]).stderr, /report FILE needs --html OUT\.html/);
  assert.match(run(['report', '--html', join(tmp, 'x.html')]).stderr, /report: --html needs a FILE/);
  assert.match(run(['report', step, '--html', join(tmp, 'x.html'), '--quick']).stderr, /--quick applies to the paper report/);
  assert.deepEqual(readdirSync(tmp).filter((f) => f.endsWith('.html')), []);
});

test('exit codes: 0 clean, 1 faults with --fail-on-fault (0 without: the contract), 2 unreadable (a file, or any log of a folder)', () => {
  assert.equal(run(['audit', clean, '--fail-on-fault']).status, 0);
  assert.equal(run(['audit', step, '--fail-on-fault']).status, 1);
  assert.equal(run(['audit', step]).status, 0, 'the contract: exit 0 when the log was read');
  assert.equal(run(['audit', imuOnly, '--fail-on-fault']).status, 0, 'no verdict is not a fault');
  assert.equal(run(['report', step, '--html', join(tmp, 'f.html'), '--fail-on-fault']).status, 1);
  const broken = join(tmp, 'broken.csv');
  writeFileSync(broken, 't,lat\n1,2,3,4\n');
  assert.equal(run(['audit', broken]).status, 2);
  assert.equal(run(['audit', join(tmp, 'missing.csv')]).status, 2);
  const mixed = join(tmp, 'mixed');
  mkdirSync(mixed);
  copyFileSync(clean, join(mixed, 'a.csv'));
  copyFileSync(broken, join(mixed, 'b.csv'));
  const d = run(['audit', mixed, '--jobs', '1', '--fail-on-fault']);
  assert.equal(d.status, 2, d.stderr);
  assert.match(d.stdout, /2 logs, 1 unreadable/);
  assert.match(d.stdout, /b\.csv\s+unreadable: /);
  const ok = join(tmp, 'ok');
  mkdirSync(ok);
  copyFileSync(clean, join(ok, 'a.csv'));
  assert.equal(run(['audit', ok, '--jobs', '1', '--fail-on-fault']).status, 0);
  copyFileSync(step, join(ok, 'b.csv'));
  assert.equal(run(['audit', ok, '--jobs', '1', '--fail-on-fault']).status, 1);
  assert.equal(run(['audit', ok, '--jobs', '1']).status, 0);
});

test('audit DIR recurses, counts what it skipped, and lists every interval per flight in --json', () => {
  const r = run(['audit', fleet, '--json', '--jobs', '2']);
  assert.equal(r.status, 0, r.stderr);
  const s = JSON.parse(r.stdout);
  assert.deepEqual(s.logs.map((l) => l.file), [clean, step, imuOnly]);
  assert.deepEqual(s.skipped, [{ file: join(fleet, 'notes.txt'), why: 'not a log (no ULog, DataFlash or navlog CSV header)' }]);
  const text = run(['audit', fleet, '--jobs', '1']).stdout;
  assert.match(text, /3 logs, 0 unreadable, 1 other files skipped/);
  // the fleet JSON holds the same intervals as the single-file report
  const single = JSON.parse(run(['audit', step, '--json']).stdout);
  const row = s.logs.find((l) => l.file === step);
  assert.ok(single.faults.length > 0);
  assert.deepEqual(row.faults, single.faults);
  assert.equal(row.residualFaults + row.outages, single.faults.length);
  assert.equal(row.startT, single.startT);
  assert.deepEqual(s.logs.find((l) => l.file === clean).faults, []);
});

test('"no verdict" is distinct from clean in the text report, the folder table, the JSON and the HTML', () => {
  const one = run(['audit', imuOnly]).stdout;
  assert.match(one, /: no verdict\n/);
  assert.match(one, /No GPS fix in this log, .*Still checked: IMU \(50 Hz\): rates and data gaps; barometer/);
  assert.match(run(['audit', clean]).stdout, /: clean\n/);
  const table = run(['audit', fleet, '--jobs', '1']).stdout;
  assert.match(table, /clean\.csv\s+csv\s+[\d.]+\s+[\d.]+\s+0\.00%\s+0\s+0\s+0\s+clean\s/);
  assert.match(table, /imu-only\.csv\s+csv\s+[\d.]+\s+no\s+-\s+0\s+0\s+0\s+no verdict\s/);
  const json = JSON.parse(run(['audit', fleet, '--json', '--jobs', '1']).stdout);
  assert.deepEqual(json.logs.map((l) => l.verdict), ['clean', 'faults', 'no verdict']);
  const html = join(tmp, 'fleet.html');
  assert.equal(run(['audit', fleet, '--jobs', '1', '--html', html]).status, 0);
  const page = readFileSync(html, 'utf8');
  const verdicts = [...page.matchAll(/<tr data-verdict="([^"]+)"><td><a href="#flight-(\d+)">([^<]+)<\/a>/g)].map((m) => [m[3], m[1], m[2]]);
  assert.deepEqual(verdicts, [['clean.csv', 'clean', '0'], ['flights/step.csv', 'faults', '1'], ['imu-only.csv', 'no verdict', '2']]);
  assert.match(page, /<section class="flight" id="flight-2" data-verdict="no verdict">/);
});

test('times since the log\'s start, the UTC start and HDOP labelled as such in the text report', () => {
  const r = run(['audit', join(data, 'ardupilot', 'Loiter_RTL.bin')]);
  assert.equal(r.status, 0, r.stderr);
  assert.match(r.stdout, /start: 2014-11-06 16:02:33 UTC; times below are seconds since the log's start \(boot clock 20\.664 s\)/);
  assert.match(r.stdout, /receiver quality as HDOP/);
  assert.match(r.stdout, /flight modes: 0\.0 s ALT_HOLD, 20\.4 s LOITER, 24\.0 s LAND/);
  assert.match(r.stdout, /autopilot messages: 144 \(3 warnings or errors\)/);
  const j = JSON.parse(run(['audit', join(data, 'ardupilot', 'Loiter_RTL.bin'), '--json']).stdout);
  assert.equal(j.ephSource, 'hdop');
  assert.equal(j.startUtc, '2014-11-06T16:02:33.790Z');
  assert.equal(j.startT, 20.664);
  assert.equal(j.modes.length, 9);
  const u = JSON.parse(run(['audit', join(data, 'px4', 'sample_log_small.ulg'), '--json']).stdout);
  assert.equal(u.ephSource, 'eph');
  assert.match(run(['audit', join(data, 'px4', 'sample_log_small.ulg')]).stdout, /receiver quality as eph \(m\)/);
});

test('quiet on a closed pipe: the folder table and the JSON report', () => {
  for (const args of [`audit "${fleet}" --jobs 1`, `audit "${step}" --json`, `audit "${step}" --per-sample /dev/stdout`]) {
    const r = spawnSync('bash', ['-c', `set -o pipefail; "${process.execPath}" "${cli}" ${args} | head -c 10`], { encoding: 'utf8', timeout: 60000 });
    assert.equal(r.stderr, '', args);
    assert.equal(r.stdout.length, 10, args);
    assert.equal(r.status, 0, args);
  }
});

test('progress on a terminal only: shown on a pty, nothing on stderr when piped', () => {
  const piped = run(['audit', step]);
  assert.equal(piped.stderr, '', 'progress written to a pipe');
  const dir = run(['audit', fleet, '--jobs', '1']);
  assert.equal(dir.stderr, '');
  // `script` runs the command on a pseudo-terminal (stderr.isTTY true)
  const cmd = `"${process.execPath}" "${cli}" audit "${fleet}" --jobs 1 >/dev/null`;
  const tty = spawnSync('script', ['-qec', cmd, '/dev/null'], { encoding: 'utf8', timeout: 60000 });
  assert.equal(tty.status, 0, tty.stdout);
  assert.match(tty.stdout, /\r\x1b\[Kaudited 1\/3: /);
  assert.match(tty.stdout, /\r\x1b\[Kaudited 3\/3: /);
  // the line is cleared at the end
  assert.match(tty.stdout, /\r\x1b\[K(\r\n)?$/);
});

test('report FILE --html: atomic, never the input, a failed run leaves the previous file', () => {
  const out = join(tmp, 'atomic', 'r.html');
  mkdirSync(dirname(out));
  writeFileSync(out, 'previous\n');
  const bad = join(tmp, 'atomic', 'bad.csv');
  writeFileSync(bad, 't;lat\n0;1\n');
  const r = run(['report', bad, '--html', out]);
  assert.equal(r.status, 2);
  assert.equal(readFileSync(out, 'utf8'), 'previous\n');
  assert.deepEqual(readdirSync(dirname(out)).sort(), ['bad.csv', 'r.html']);
  const same = run(['report', step, '--html', step]);
  assert.equal(same.status, 2);
  assert.match(same.stderr, /--html .*refusing to overwrite/);
  assert.match(readFileSync(step, 'utf8'), /^#|^t,/);
  const fl = run(['audit', fleet, '--html', step, '--jobs', '1']);
  assert.equal(fl.status, 2);
  assert.match(fl.stderr, /refusing to overwrite/);
  const ok = run(['report', step, '--html', out]);
  assert.equal(ok.status, 0, ok.stderr);
  assert.match(ok.stderr, /^wrote .*r\.html \(\d+ KiB, 1 log\)\n$/);
  const html = readFileSync(out, 'utf8');
  assert.match(html, /^<!DOCTYPE html>/);
  assert.doesNotMatch(html, /(src|href)="(https?:)?\/\//, 'the report links outside');
  assert.match(html, /Content-Security-Policy" content="default-src 'none'/);
  assert.deepEqual(readdirSync(dirname(out)).sort(), ['bad.csv', 'r.html']);
});

test('the per-sample file ends with the whole-log verdict: real log 09-10 dates each outage from the fix it missed', () => {
  const per = join(tmp, 'per-09-10.csv');
  const r = run(['audit', join(data, 'ardupilot', 'erle_copter_09-10-2014_30.BIN'), '--json', '--per-sample', per]);
  assert.equal(r.status, 0, r.stderr);
  const rep = JSON.parse(r.stdout);
  const lines = readFileSync(per, 'utf8').trim().split('\n');
  assert.match(lines[0], /^t,status,f,r,c,.*,reconciled$/);
  const rows = lines.slice(1).map((l) => l.split(','));
  const rec = rows.map((c) => c[c.length - 1]);
  assert.ok(rec.every((v) => v === '0' || v === '1'));
  // Every row flagged as the samples came is inside the whole-log verdict;
  // the verdict adds the silences before the outages it called (session 28:
  // each about 1.1 s, where the next fix was due), 427 rows in all.
  const flaggedOut = rows.filter((c, i) => c[1] !== '0' && rec[i] === '0').length;
  const added = rows.filter((c, i) => c[1] === '0' && rec[i] === '1');
  assert.equal(flaggedOut, 0);
  assert.equal(added.length, 427);
  // The first outage: causal from its call, reconciled from the silence.
  assert.ok(rep.reconciled[0].start < rep.faults[0].start - 1, JSON.stringify([rep.reconciled[0], rep.faults[0]]));
  assert.ok(added.some((c) => +c[0] >= rep.reconciled[0].start && +c[0] < rep.faults[0].start));
});
