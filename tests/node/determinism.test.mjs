// Native and wasm builds give identical verdicts and F values on every file
// in ../shared/data and on the simulated paper scenario (FNV-1a over every
// row's status and F bits; see examples/verdicts.rs).
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { createRequire } from 'node:module';
import { execFileSync } from 'node:child_process';
import { readdirSync, readFileSync, writeFileSync, mkdtempSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';

const root = join(dirname(fileURLToPath(import.meta.url)), '..', '..');
const ng = createRequire(import.meta.url)(join(root, 'pkg'));
const shared = join(root, '..', 'shared', 'data');

function fingerprint(cols) {
  let h = 0xcbf29ce484222325n;
  const mix = (b) => { h ^= BigInt(b); h = (h * 0x100000001b3n) & 0xffffffffffffffffn; };
  const buf = new DataView(new ArrayBuffer(8));
  let flagged = 0;
  for (let i = 0; i < cols.t.length; i++) {
    mix(cols.status[i]);
    flagged += cols.status[i];
    buf.setFloat64(0, cols.f[i], true);
    for (let k = 0; k < 8; k++) mix(buf.getUint8(k));
  }
  return `${cols.t.length}\t${flagged}\t${h.toString(16).padStart(16, '0')}`;
}

test('native and wasm agree bit for bit on every shared log and the paper scenario', () => {
  const files = [];
  for (const dir of ['px4', 'ardupilot', 'csv']) {
    for (const f of readdirSync(join(shared, dir))) files.push(join(shared, dir, f));
  }
  const sim = join(mkdtempSync(join(tmpdir(), 'navguard-det-')), 'paper.csv');
  writeFileSync(sim, ng.simulate('paper', 1));
  files.push(sim);
  const native = execFileSync('cargo', ['run', '-q', '--release', '-p', 'navguard-examples', '--example', 'verdicts', '--', ...files], { cwd: root, encoding: 'utf8', maxBuffer: 1 << 24 });
  const lines = native.trim().split('\n');
  assert.equal(lines.length, files.length);
  for (let i = 0; i < files.length; i++) {
    const [path, ...rest] = lines[i].split('\t');
    assert.equal(path, files[i]);
    const { columns } = ng.auditBytes(readFileSync(files[i]), {});
    assert.equal(fingerprint(columns), rest.join('\t'), files[i]);
  }
});
