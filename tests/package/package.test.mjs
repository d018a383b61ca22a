// The npm package as its users get it (issue 16): Node ESM and CJS with
// named exports, `tsc --strict` on the public types, an esbuild bundle and a
// Vite build (no configuration) run in headless Chromium, and the tarball
// installed into a clean folder, its CLI run with npx. Each also checks
// that `new Detector()` plus reading a real log loads only the core wasm
// module, and the lab module only on a lab call (issue 15).
// Run from the repository root after `bash .ci/build`: node --test tests/package/
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import http from 'node:http';
import { execFileSync, spawnSync } from 'node:child_process';
import { mkdtempSync, mkdirSync, writeFileSync, symlinkSync, readFileSync, copyFileSync, statSync, readdirSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, dirname, extname, normalize, sep } from 'node:path';
import { fileURLToPath } from 'node:url';
import { createRequire } from 'node:module';

const here = dirname(fileURLToPath(import.meta.url));
const root = join(here, '..', '..');
const pkg = join(root, 'pkg');
const bin = join(root, 'node_modules', '.bin');
const LOG = join(root, '..', 'shared', 'data', 'px4', 'sample_log_small.ulg');
const CHROMIUM = process.env.CHROMIUM_PATH || '/usr/bin/chromium';
const CORE_WASM = statSync(join(pkg, 'navguard_core_bg.wasm')).size;
const AUDIT_WASM = statSync(join(pkg, 'navguard_audit_bg.wasm')).size;
const LAB_WASM = statSync(join(pkg, 'navguard_lab_bg.wasm')).size;
// Issue 15's acceptance: `new Detector()` plus `readLog` of a real log
// load at most 300 KB of wasm, every module they instantiate counted: the
// core module alone (checked below), 298,887 B. It got there with the
// threshold pools and the model embedded (no simulator, no JSON parser in
// the core), snapshots and the config read by hand-written code (no serde
// deserializer), the log readers built for size, the detector in a crate
// of its own at opt-level 3 while the facade, snapshot and restore are
// built for size, results built as JS objects by hand (no
// serde-wasm-bindgen), the readers' few sorts through one merge sort, the
// threshold pools embedded packed (LZ77, codec::unpack), no `{:?}` of text
// (no Unicode tables), std rebuilt with the module (.ci/build: -Z
// build-std, panic=immediate-abort), the audits in a module of their own,
// the core's floats parsed and printed without std's tables
// (logs/src/decimal.rs), talc as its allocator and the detector's cold
// functions built for size, unrolled no more than their size level
// allows, the DataFlash counts without a B-tree and binaryen's
// --low-memory-unused and --merge-similar-functions (README, Speed and
// size). The size7 branch met issue 15's goal (306,869 B), session 9's
// detector work took the core past it (312,314 B), the size8 branch back
// under it with 8.3 KB to spare (298,887 B); session 10's detector work
// (the vertical ramp arm, its return on a jump back, the σ_Δ warm-up,
// the baro levels' error model) adds 2,131 B: 301,018 B. Session 11's
// (kept offsets, the tracks' origin) adds 1,077 B: 302,095 B; session 12's
// (the offset kept on an unflagged fault's end, the origin measured on the
// level before the jump, with the jump-size scale) 920 B: 303,015 B, and
// its vertical drag-off end (a second `DragEnd`, not a generic copy, which
// cost 1,956 B) about 660 B more: 303,721 B. Session 13's receiver speed
// claim (a 28th column, the DataFlash `UBX3` record, the usual claim's
// state and codec, the scaled velocity tests with their window maxima,
// not on declared fixes; the drift test's claim as a prior) adds 2,492 B:
// 306,213 B, its baro hold 253 B more, its review 22 B: 306,488 B, 712 B
// under the goal. Session 14's four rules (the baro drift's plateau, the
// GPS altitude's vertical return, the long coast, the track's quick
// origin) add 305 B: 306,793 B, 407 B under the goal, 207 B under this
// guard. Session 15's rules (the short shape for a drag-off's end, the
// drag end armed inside an episode, the IMU baseline rate's bound, the
// drag end's forgetting per second) add 459 B, and wasm-opt's --converge
// on the core takes 293 B off: 306,959 B, 241 B under the goal, 41 B
// under this guard. Session 16's baro jump hold (`barojump`, the baro kept
// withheld while still off) adds 1,043 B, and three per-GPS-epoch stages
// built for size (`Detector::gps_epoch`, `Consistency::tests`,
// `Episode::step`: #[optimize(size)]) take 976 B off: 307,026 B, 174 B
// under the goal. The guard is raised to the goal (307,200 B), with the
// reason: the size-for-speed trade that remains (the rest of the per-epoch
// consistency code, 13–15% of `pushColumns`, README) is a worse one than
// this rule's missed baro steps. Session 17's track departure adds 332 B
// and its GPS track σ learning 353 B, paid by building the other methods'
// per-epoch code for size (`nis`, `PoolState::decide`,
// `Methods::other_method`) and not inlining `VelocityTrack::learn`:
// 307,173 B, 27 B under the goal. Session 18's fast ramp arm adds 1.9 KB,
// paid by building more per-GPS-epoch work for size (`DriftTest::push`,
// `IndicatorEngine::observe_pv`, `VelocityTrack::step` and `learn`, the
// ramp's `push` and `learn`) and the other methods' (`MahaWindow`,
// `Evaluator::push`), and by inlining `ModeThreshold`'s codec: 307,031 B,
// 169 B under the goal. `Kf::scalar_update` built for size would give 2.6
// KB but cost 10% of `pushColumns`. Session 19's IMU learning bound and
// bias roll-back and hold add 0.5 KB, paid by building `Window::note`,
// `VelocityTrack::departure_net`, `BaroJump::epoch` and `DragEnd::arm` and
// `confirmed` for size, and the review's `jumped_back` on `dot` 26 B:
// 307,068 B, 132 B under the goal (`DragEnd::learn`
// too would cost 11% of `pushColumns`). Session 23's IMU window judged by
// its slope, with its refitted threshold pools (36 B more packed), is paid
// by building the one-time constructors `IndicatorEngine::new` and
// `LagTest::new` for size: 306,869 B, 331 B under the goal. Session 24's
// short mean off the GPS velocity track (1.5 KB) is paid by building
// `VelocityTrack::mean_sigmas` and `Kf::check_health` for size: 307,111 B,
// 89 B under. Session 25's degraded stretch and the baro hold's motion
// allowance (1.5 KB) are paid by building `declares_degraded`,
// `baro_levels`, `unflagged_fault_ended` and `RampTest::clear` for size
// and by sharing `drift::allowance` and the levels' error model:
// 307,153 B, 47 B under. Session 26's dating of faults seen to end is
// left out of the core (the detector crate's `dated` feature); its hooks
// are paid by building `Episode::ended_off_track` for size: 307,179 B,
// 21 B under. Session 27's held start of the baro drift window passes
// the window's span to `Window::enter`, built for size now: 307,048 B,
// 152 B under. Session 28's dating of slow faults, frozen fixes and stuck
// baros passes closures the core's `Dating` never calls: 307,046 B.
// Session 29's IMU arming on refused windows and the track's departure
// judged from 10 s of age: 307,119 B, 81 B under.
// The budget
// guards today's size plus 0.5 KB: a
// change that crosses it must find the bytes elsewhere, or raise it with
// the reason, never past the goal, which the last test asserts.
const FIRST_USE_GOAL = 307_200;
const CORE_WASM_BUDGET = 307_200;
const { chromium } = createRequire(import.meta.url)(join(root, 'node_modules', 'playwright-core'));

let work, project, browser;

before(async () => {
  work = mkdtempSync(join(tmpdir(), 'navguard-pkg-'));
  // A user's project with the built package installed (as a link).
  project = join(work, 'project');
  mkdirSync(join(project, 'node_modules'), { recursive: true });
  symlinkSync(pkg, join(project, 'node_modules', 'navguard'), 'dir');
  for (const f of readdirSync(join(here, 'app'))) copyFileSync(join(here, 'app', f), join(project, f));
  writeFileSync(join(project, 'package.json'), JSON.stringify({ name: 'user-app', private: true, type: 'module' }));
  browser = await chromium.launch({ executablePath: CHROMIUM, args: ['--headless', '--no-sandbox', '--disable-gpu'] });
});

after(async () => {
  if (browser) await browser.close();
  if (work) rmSync(work, { recursive: true, force: true });
});

// Counts the bytes of every wasm module compiled in this Node process.
const COUNT_WASM = `
let wasmBytes = 0;
const RawModule = WebAssembly.Module;
WebAssembly.Module = function (bytes, ...rest) { wasmBytes += bytes.byteLength; return new RawModule(bytes, ...rest); };
WebAssembly.Module.prototype = RawModule.prototype;
`;
const USE = `
const bytes = readFileSync(${JSON.stringify(LOG)});
const det = new Detector();
const log = readLog(bytes);
const res = det.pushColumns(log.columns);
const firstUse = { bytes: wasmBytes, modules: loadedModules() };
const audit = auditBytes(bytes);
const afterAudit = { bytes: wasmBytes, modules: loadedModules() };
const csv = simulate('paper', 1);
console.log(JSON.stringify({ firstUse, afterAudit, all: { bytes: wasmBytes, modules: loadedModules() }, rows: log.rows, auditRows: audit.report.rows,
  flagged: res.status.reduce((a, b) => a + b, 0), csvLines: csv.split('\\n').length, init: typeof init, dispose: typeof det[Symbol.dispose] }));
`;

// What `new Detector()` plus `readLog` compiled, per run (Node ESM, CJS,
// esbuild and Vite in Chromium), for the acceptance test at the end.
const firstUseBytes = {};

// `new Detector()` plus `readLog`: the core module alone, within its budget.
function checkFirstUse(where, modules, bytes) {
  assert.deepEqual(modules, { core: true, audit: false, lab: false }, 'a Detector and a log must load neither the audit nor the lab module');
  assert.equal(bytes, CORE_WASM, 'wasm compiled for new Detector() + readLog = the core module');
  assert.ok(bytes <= CORE_WASM_BUDGET, `core module ${bytes} B > budget ${CORE_WASM_BUDGET} B`);
  firstUseBytes[where] = bytes;
}

function checkNode(where, out) {
  const r = JSON.parse(out);
  checkFirstUse(where, r.firstUse.modules, r.firstUse.bytes);
  assert.deepEqual(r.afterAudit.modules, { core: true, audit: true, lab: false }, 'an audit loads the audit module, not the lab');
  assert.equal(r.afterAudit.bytes, CORE_WASM + AUDIT_WASM);
  assert.deepEqual(r.all.modules, { core: true, audit: true, lab: true });
  assert.equal(r.all.bytes, CORE_WASM + AUDIT_WASM + LAB_WASM);
  assert.ok(r.rows > 1000 && r.auditRows === r.rows, JSON.stringify(r));
  assert.ok(r.csvLines > 1000, 'simulate gave a flight');
  assert.equal(r.init, 'function');
  return r;
}

test('Node ESM: named imports from "navguard"; the lab module loads on the first lab call', () => {
  const src = `import { readFileSync } from 'node:fs';\nimport init, { Detector, readLog, auditBytes, simulate, loadedModules } from 'navguard';\n${COUNT_WASM}${USE}`;
  writeFileSync(join(project, 'esm.mjs'), src);
  checkNode('Node ESM', execFileSync(process.execPath, ['esm.mjs'], { cwd: project, encoding: 'utf8' }));
});

test('Node CJS: require("navguard") and require of the package folder (contract §2)', () => {
  const src = `const { readFileSync } = require('node:fs');\n${COUNT_WASM}const { default: init, Detector, readLog, auditBytes, simulate, loadedModules } = require('navguard');\n${USE}`;
  writeFileSync(join(project, 'cjs.cjs'), src);
  const a = checkNode('Node CJS', execFileSync(process.execPath, ['cjs.cjs'], { cwd: project, encoding: 'utf8' }));
  const b = JSON.parse(execFileSync(process.execPath, ['-e', `${COUNT_WASM}const { default: init, Detector, readLog, auditBytes, simulate, loadedModules } = require(${JSON.stringify(pkg)}); const { readFileSync } = require('node:fs');${USE}`], { encoding: 'utf8' }));
  assert.deepEqual(b, a, 'require(pkg folder) = require("navguard")');
});

test('tsc --strict on a .mts: new Detector(), pushColumns, readLog, auditBytes, snapshots; no @types/node, no DOM lib', () => {
  const compilerOptions = { strict: true, noEmit: true, module: 'nodenext', moduleResolution: 'nodenext', target: 'es2022', lib: ['es2022'], types: [] };
  writeFileSync(join(project, 'tsconfig.json'), JSON.stringify({ compilerOptions, files: ['use.mts'] }));
  const r = spawnSync(join(bin, 'tsc'), ['--strict', '-p', 'tsconfig.json'], { cwd: project, encoding: 'utf8' });
  assert.equal(r.status, 0, r.stdout + r.stderr);
});

// Serves `dir` plus /log (the real flight log), runs the page, returns
// what main.js found.
async function runInChromium(where, dir) {
  const server = http.createServer((req, res) => {
    const path = new URL(req.url, 'http://x').pathname;
    try {
      if (path === '/log') return res.end(readFileSync(LOG));
      const file = normalize(join(dir, path === '/' ? 'index.html' : path));
      if (!file.startsWith(dir + sep)) throw new Error('outside');
      const type = { '.html': 'text/html', '.js': 'text/javascript', '.wasm': 'application/wasm' }[extname(file)] || 'application/octet-stream';
      const body = readFileSync(file);
      res.writeHead(200, { 'content-type': type });
      res.end(body);
    } catch {
      res.writeHead(404);
      res.end();
    }
    return undefined;
  });
  await new Promise((r) => server.listen(0, '127.0.0.1', r));
  const page = await browser.newPage();
  const errors = [];
  page.on('pageerror', (e) => errors.push(e.message));
  page.on('response', (r) => { if (r.status() >= 400) errors.push(`HTTP ${r.status()} ${r.url()}`); });
  await page.addInitScript(() => {
    globalThis.__wasmBytes = 0;
    const raw = WebAssembly.instantiate;
    WebAssembly.instantiate = function (src, imports) {
      if (src && typeof src.byteLength === 'number') globalThis.__wasmBytes += src.byteLength;
      return raw.call(this, src, imports);
    };
  });
  try {
    await page.goto(`http://127.0.0.1:${server.address().port}/`);
    await page.waitForFunction(() => globalThis.__result, null, { timeout: 120000 });
    const r = await page.evaluate(() => globalThis.__result);
    assert.deepEqual(errors, []);
    assert.equal(r.error, undefined, r.error);
    assert.match(r.beforeInit, /await init\(\)/);
    assert.equal(r.format, 'ulog');
    assert.ok(r.rows > 1000);
    assert.equal(r.pushSame, r.pushN, 'push and pushColumns give the same statuses');
    checkFirstUse(where, r.firstUse, r.wasmBytesFirstUse);
    assert.match(r.auditBeforeLoad, /await loadAudit\(\)/);
    assert.equal(r.auditRows, r.rows);
    assert.ok(r.statsKeys.includes('gpsEpochs') && r.statsKeys.includes('filterResets'), r.statsKeys.join());
    assert.match(r.freed, /was freed/);
    assert.match(r.reentry, /called while Detector\.push is running/);
    assert.equal(r.rowsAfterReentry, 0);
    for (const k of ['Detector', 'auditBytes', 'readLog', 'StreamAuditor', 'TightDetector', 'CompareRun', 'simulate', 'init', 'loadAudit', 'loadLab', 'default']) assert.ok(r.exports.includes(k), k);
    assert.ok(!r.exports.some((k) => k.startsWith('__') || k === 'initSync'), r.exports.join());
    assert.deepEqual(r.beforeLab, { core: true, audit: true, lab: false });
    assert.match(r.labBeforeLoad, /await loadLab\(\)/);
    assert.equal(r.wasmBytesCore, CORE_WASM + AUDIT_WASM, 'only the core and audit modules were compiled before loadLab()');
    assert.ok(r.simLines > 1000);
    assert.deepEqual(r.afterLab, { core: true, audit: true, lab: true });
    assert.equal(r.wasmBytesAll, CORE_WASM + AUDIT_WASM + LAB_WASM);
    return r;
  } finally {
    await page.close();
    server.close();
  }
}

test('esbuild, no configuration: the bundle runs in Chromium', async () => {
  const out = join(work, 'esbuild');
  execFileSync(join(bin, 'esbuild'), ['main.js', '--bundle', '--format=esm', `--outfile=${join(out, 'main.js')}`, '--log-level=warning'], { cwd: project, stdio: 'pipe' });
  copyFileSync(join(project, 'index.html'), join(out, 'index.html'));
  await runInChromium('Chromium, esbuild', out);
});

test('Vite build, no configuration: the build runs in Chromium', async () => {
  const out = join(work, 'vite');
  execFileSync(process.execPath, [join(root, 'node_modules', 'vite', 'bin', 'vite.js'), 'build', '--outDir', out, '--logLevel', 'error'], { cwd: project, stdio: 'pipe' });
  await runInChromium('Chromium, Vite', out);
});

// npm without the machine's user config (a clean machine's npm). For the
// publish dry run it holds a placeholder token: a publisher is logged in,
// and npm's only warning otherwise is "requires you to be logged in" (the
// dry run never sends it anywhere).
// The `npm_config_*` variables a parent `npm test` exports (this machine's
// own settings, such as nodedir, which npm 11 warns about) are dropped too.
const cleanEnv = Object.fromEntries(Object.entries(process.env).filter(([k]) => !/^npm_config_/i.test(k)));

function npm(args, cwd) {
  const userconfig = join(work, 'npmrc');
  writeFileSync(userconfig, '//registry.npmjs.org/:_authToken=placeholder-for-dry-run\n');
  return spawnSync('npm', args, { cwd, encoding: 'utf8', env: { ...cleanEnv, npm_config_userconfig: userconfig, npm_config_update_notifier: 'false', npm_config_fund: 'false', npm_config_audit: 'false' } });
}

test('npm publish --dry-run is clean; the tarball installs into a clean folder and `npx navguard audit LOG` works', () => {
  const dry = npm(['publish', '--dry-run'], pkg);
  assert.equal(dry.status, 0, dry.stderr);
  assert.doesNotMatch(dry.stderr, /\bwarn/i, dry.stderr);
  for (const f of ['LICENSE-MIT', 'LICENSE-APACHE', 'README.md', 'index.d.ts', 'node.cjs', 'navguard_core_bg.wasm', 'navguard_lab_bg.wasm']) assert.match(dry.stderr, new RegExp(`\\b${f.replace('.', '\\.')}\\b`), f);
  const packed = npm(['pack', '--pack-destination', work], pkg);
  assert.equal(packed.status, 0, packed.stderr);
  const tgz = readdirSync(work).find((f) => /^navguard-.*\.tgz$/.test(f));
  const clean = join(work, 'clean');
  mkdirSync(clean);
  assert.equal(npm(['init', '-y'], clean).status, 0);
  const inst = npm(['install', join(work, tgz)], clean);
  assert.equal(inst.status, 0, inst.stderr);
  const run = spawnSync('npx', ['navguard', 'audit', LOG, '--json'], { cwd: clean, encoding: 'utf8', env: { ...cleanEnv, npm_config_userconfig: join(work, 'npmrc') } });
  // 0: clean, 1: faults found (issue 16 item 4); 2 would be unreadable.
  assert.ok(run.status === 0 || run.status === 1, `exit ${run.status}: ${run.stderr}`);
  assert.ok(run.stdout.trim().startsWith('{'), run.stderr);
  const r = JSON.parse(run.stdout);
  assert.equal(r.format, 'ulog');
  assert.ok(r.rows > 1000);
});

// Issue 15's acceptance, over every run above.
test('issue 15: new Detector() + readLog load <= 300 KB of wasm in Node and Chromium', () => {
  assert.deepEqual(Object.keys(firstUseBytes).sort(), ['Chromium, Vite', 'Chromium, esbuild', 'Node CJS', 'Node ESM']);
  for (const [where, bytes] of Object.entries(firstUseBytes)) assert.ok(bytes <= FIRST_USE_GOAL, `${where}: ${bytes} B > ${FIRST_USE_GOAL} B`);
});
