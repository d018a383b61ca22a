// Assemble the publishable package in pkg/: wasm-pack's output plus the
// hand-written files of pkg-config/ (CLI, JS helpers) and its package.json
// fields. Run by .ci/build after `wasm-pack build --target nodejs`.
import { readFileSync, writeFileSync, mkdirSync, copyFileSync } from 'node:fs';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

const here = dirname(fileURLToPath(import.meta.url));
const pkg = join(here, '..', 'pkg');
const generated = JSON.parse(readFileSync(join(pkg, 'package.json'), 'utf8'));
const extra = JSON.parse(readFileSync(join(here, 'package.json'), 'utf8'));
const { extraFiles, ...fields } = extra;
for (const f of extraFiles) {
  mkdirSync(dirname(join(pkg, f)), { recursive: true });
  copyFileSync(join(here, f), join(pkg, f));
}
const merged = { ...generated, ...fields, files: [...new Set([...(generated.files || []), ...extraFiles])] };
writeFileSync(join(pkg, 'package.json'), JSON.stringify(merged, null, 2) + '\n');
