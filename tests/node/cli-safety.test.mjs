// The CLI never loses a user's file and never hangs or dies with a stack
// trace on a hostile invocation (issue 17, findings 1, 8, 10, 11): each case
// exits 2 with one line naming the problem, and every input is
// byte-identical afterwards.
import { test, before } from 'node:test';
import assert from 'node:assert/strict';
import { spawnSync, execFileSync } from 'node:child_process';
import { mkdtempSync, readFileSync, writeFileSync, symlinkSync, linkSync, readdirSync, mkdirSync, existsSync, copyFileSync, lstatSync } from 'node:fs';
import { createHash } from 'node:crypto';
import { tmpdir } from 'node:os';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

const root = join(dirname(fileURLToPath(import.meta.url)), '..', '..');
const cli = join(root, 'pkg', 'bin', 'navguard.mjs');
const tmp = mkdtempSync(join(tmpdir(), 'navguard-cli-'));
const log = join(tmp, 'flight.csv');
let logHash;

const sha = (p) => createHash('sha256').update(readFileSync(p)).digest('hex');
const run = (args, opts = {}) => spawnSync(process.execPath, [cli, ...args], { encoding: 'utf8', timeout: 60000, ...opts });

/** Exit 2, one line on stderr matching `re`, no stack trace. */
function refused(r, re) {
  assert.equal(r.status, 2, `exit ${r.status} signal ${r.signal}\nstdout: ${r.stdout}\nstderr: ${r.stderr}`);
  const lines = r.stderr.trim().split('\n');
  assert.equal(lines.length, 1, r.stderr);
  assert.match(lines[0], /^navguard: /);
  assert.match(lines[0], re);
  assert.doesNotMatch(r.stderr, /\n\s+at /);
}

before(() => {
  execFileSync(process.execPath, [cli, 'simulate', 'step', '--seed', '3', '--out', log]);
  logHash = sha(log);
  assert.ok(readFileSync(log).length > 100000);
});

test('--per-sample naming the input (directly, by a symlink, by a hard link) is refused and the log is untouched', () => {
  const viaLink = join(tmp, 'link.csv');
  symlinkSync(log, viaLink);
  const hard = join(tmp, 'hard.csv');
  linkSync(log, hard);
  for (const out of [log, viaLink, hard, join(tmp, '.', 'flight.csv')]) {
    refused(run(['audit', log, '--per-sample', out]), /refusing to overwrite/);
    assert.equal(sha(log), logHash, out);
  }
  // The other way round: auditing the link with the real path as output.
  refused(run(['audit', viaLink, '--per-sample', log]), /refusing to overwrite/);
  assert.equal(sha(log), logHash);
});

test('--per-sample is written atomically: a failed audit leaves the previous file and no temporary file', () => {
  const out = join(tmp, 'atomic', 'per.csv');
  mkdirSync(dirname(out));
  writeFileSync(out, 'previous\n');
  const bad = join(tmp, 'atomic', 'bad.csv');
  writeFileSync(bad, 't;lat;lon;alt\n0;1;2;3\n');
  refused(run(['audit', bad, '--per-sample', out]), /delimiter/);
  assert.equal(readFileSync(out, 'utf8'), 'previous\n');
  assert.deepEqual(readdirSync(dirname(out)).sort(), ['bad.csv', 'per.csv']);
  const ok = run(['audit', log, '--per-sample', out]);
  assert.equal(ok.status, 0, ok.stderr);
  const lines = readFileSync(out, 'utf8').trim().split('\n');
  assert.equal(lines.length, 12501);
  assert.deepEqual(readdirSync(dirname(out)).sort(), ['bad.csv', 'per.csv']);
});

test('flag values are checked: --jobs abc, --jobs 0, --seed -1, a missing value, a repeated flag', () => {
  refused(run(['audit', tmp, '--jobs', 'abc']), /--jobs "abc": must be a whole number >= 1/);
  refused(run(['audit', tmp, '--jobs', '0']), /--jobs "0"/);
  refused(run(['simulate', 'step', '--seed', '-1']), /unknown option -1|--seed "-1"/);
  refused(run(['simulate', 'step', '--seed', '1.5']), /--seed "1.5"/);
  refused(run(['audit', log, '--config']), /--config needs a value/);
  refused(run(['audit', log, '--json', '--json']), /--json given twice/);
  refused(run(['compare', '--seeds', 'x']), /--seeds "x"/);
});

test('unknown and misspelt flags are errors with a suggestion; --help and --version answer', () => {
  refused(run(['audit', log, '--per-sampel', join(tmp, 'x.csv')]), /unknown option --per-sampel \(did you mean --per-sample\?\)/);
  assert.ok(!existsSync(join(tmp, 'x.csv')));
  refused(run(['audti', log]), /unknown command "audti" \(did you mean "audit"\?\)/);
  for (const cmd of ['audit', 'simulate', 'report', 'train', 'compare']) {
    const h = run([cmd, '--help']);
    assert.equal(h.status, 0, cmd);
    assert.match(h.stdout, new RegExp(`^navguard ${cmd} `), cmd);
  }
  const v = run(['--version']);
  assert.equal(v.status, 0);
  const version = JSON.parse(readFileSync(join(root, 'pkg', 'package.json'), 'utf8')).version;
  assert.equal(v.stdout.trim(), `navguard ${version}`);
  assert.equal(run(['audit', '--version']).stdout.trim(), `navguard ${version}`);
});

test('a FIFO, a device and a folder are refused as inputs without blocking', () => {
  const fifo = join(tmp, 'pipe.csv');
  execFileSync('mkfifo', [fifo]);
  refused(run(['audit', fifo], { timeout: 20000 }), /not a regular file \(a FIFO\)/);
  refused(run(['audit', log, '--config', '/dev/zero'], { timeout: 20000 }), /--config|not a regular file \(a device\)/);
  refused(run(['audit', log, '--config', fifo], { timeout: 20000 }), /not a regular file \(a FIFO\)/);
  refused(run(['train', '/dev/zero', '--out', join(tmp, 'm.json')], { timeout: 20000 }), /not a regular file/);
});

test('an oversized --config is refused by size, a broken one by its JSON error', () => {
  const big = join(tmp, 'big.json');
  writeFileSync(big, Buffer.alloc(17 << 20, 0x20));
  refused(run(['audit', log, '--config', big]), /bytes, more than the 16777216-byte limit/);
  const broken = join(tmp, 'broken.json');
  writeFileSync(broken, '{"tc": ');
  refused(run(['audit', log, '--config', broken]), /--config .*broken\.json: /);
});

test('--summary into a missing folder is one line and exit 2; --summary naming a log in the folder is refused', () => {
  const fleet = join(tmp, 'fleet');
  mkdirSync(fleet);
  copyFileSync(log, join(fleet, 'a.csv'));
  refused(run(['audit', fleet, '--summary', '/nonexistent/x.json', '--jobs', '1']), /--summary \/nonexistent\/x\.json: no such file or directory/);
  refused(run(['audit', fleet, '--summary', join(fleet, 'a.csv'), '--jobs', '1']), /refusing to overwrite/);
  assert.equal(sha(join(fleet, 'a.csv')), logHash);
});

test('audit DIR recurses, follows a symlink to a good log, and counts what it skipped', () => {
  const fleet = join(tmp, 'fleet2');
  mkdirSync(join(fleet, 'sub'), { recursive: true });
  copyFileSync(log, join(fleet, 'sub', 'deep.csv'));
  symlinkSync(log, join(fleet, 'linked.csv'));
  symlinkSync(join(tmp, 'nowhere.csv'), join(fleet, 'broken.csv'));
  writeFileSync(join(fleet, 'notes.txt'), 'not a log\n');
  const summary = join(tmp, 'summary.json');
  const r = run(['audit', fleet, '--json', '--jobs', '1', '--summary', summary]);
  assert.equal(r.status, 0, r.stderr);
  const s = JSON.parse(r.stdout);
  assert.deepEqual(s.logs.map((l) => l.file), [join(fleet, 'linked.csv'), join(fleet, 'sub', 'deep.csv')]);
  assert.ok(s.logs.every((l) => l.format === 'csv' && l.durationS > 100), JSON.stringify(s.logs));
  assert.deepEqual(s.skipped.map((k) => k.file).sort(), [join(fleet, 'broken.csv'), join(fleet, 'notes.txt')]);
  assert.deepEqual(JSON.parse(readFileSync(summary, 'utf8')).logs, s.logs);
  assert.equal(sha(log), logHash);
});

test('--per-sample /dev/stdout writes to the pipe and leaves /dev/stdout as it was', () => {
  // Regression: the output went to a temporary file in /dev renamed over
  // /dev/stdout; run as root, that turned the link into a regular file
  // holding the output, and nothing reached the pipe.
  const before = lstatSync('/dev/stdout');
  const r = run(['audit', log, '--per-sample', '/dev/stdout'], { maxBuffer: 1 << 26 });
  assert.equal(r.status, 0, r.stderr);
  const lines = r.stdout.split('\n');
  const head = lines.indexOf('t,status,f,r,c,kind,rPn,rPe,rPd,rVn,rVe,rVd,rBaro,reconciled');
  assert.ok(head >= 0, r.stdout.slice(0, 300));
  assert.equal(lines.slice(head + 1).filter((l) => /^[0-9.]+,[01],/.test(l)).length, 12500);
  const after = lstatSync('/dev/stdout');
  assert.deepEqual([after.isSymbolicLink(), after.isFile(), after.ino], [before.isSymbolicLink(), before.isFile(), before.ino]);
  // Its scratch file (the first pass, in the temporary folder) is gone.
  assert.deepEqual(readdirSync(tmpdir()).filter((n) => n.startsWith('.stdout.navguard-')), []);
});

test('train --out naming an input is refused', () => {
  refused(run(['train', log, '--out', log]), /refusing to overwrite/);
  assert.equal(sha(log), logHash);
});

test('a closed pipe ends quietly', () => {
  const r = spawnSync('bash', ['-c', `set -o pipefail; "${process.execPath}" "${cli}" simulate paper | head -3`], { encoding: 'utf8', timeout: 60000 });
  assert.equal(r.stdout.split('\n').length, 4, r.stdout);
  assert.equal(r.stderr, '');
  assert.equal(r.status, 0);
});

test('a log with no GPS is "no verdict", never clean; --fail-on-fault exits 1 only when faults were found', () => {
  const noGps = join(tmp, 'imu-only.csv');
  const rows = ['t,ax,ay,az,gx,gy,gz,qw,qx,qy,qz,baro'];
  for (let i = 0; i < 500; i++) rows.push(`${(i / 50).toFixed(2)},0,0,-9.81,0,0,0,1,0,0,0,10`);
  writeFileSync(noGps, rows.join('\n') + '\n');
  const r = run(['audit', noGps, '--json', '--fail-on-fault']);
  assert.equal(r.status, 0, r.stderr);
  const rep = JSON.parse(r.stdout);
  assert.equal(rep.verdict, 'no verdict');
  assert.equal(rep.gpsAvailable, false);
  assert.match(run(['audit', noGps]).stdout, /flagged GPS epochs: none to judge/);
  // The simulated step flight has a labelled 10 m step: faults.
  const f = run(['audit', log, '--json', '--fail-on-fault']);
  assert.equal(f.status, 1, f.stderr);
  assert.equal(JSON.parse(f.stdout).verdict, 'faults');
  assert.equal(run(['audit', log, '--json']).status, 0, 'without the flag the contract exit code is 0');
  const fleet = join(tmp, 'fleet3');
  mkdirSync(fleet);
  copyFileSync(noGps, join(fleet, 'a.csv'));
  const d = run(['audit', fleet, '--json', '--jobs', '1', '--fail-on-fault']);
  assert.equal(d.status, 0, d.stderr);
  assert.deepEqual(JSON.parse(d.stdout).logs.map((l) => l.verdict), ['no verdict']);
  assert.match(run(['audit', fleet, '--jobs', '1']).stdout, /imu-only|a\.csv.* -\s+0\s+0\s+0\s+no verdict/);
});
