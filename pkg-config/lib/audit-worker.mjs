// worker_threads worker for `navguard audit DIR`: audits one file per
// message with its own wasm instance and posts back the report (no columns).
import { parentPort } from 'node:worker_threads';
import { readFileSync } from 'node:fs';
import { createRequire } from 'node:module';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

const require = createRequire(import.meta.url);
const ng = require(join(dirname(fileURLToPath(import.meta.url)), '..', 'index.js'));

parentPort.on('message', ({ file, config }) => {
  const t0 = performance.now();
  try {
    const bytes = readFileSync(file);
    const { report } = ng.auditBytes(bytes, config);
    parentPort.postMessage({ file, bytes: bytes.length, ms: performance.now() - t0, report });
  } catch (e) {
    parentPort.postMessage({ file, ms: performance.now() - t0, error: String(e && e.message ? e.message : e) });
  }
});
