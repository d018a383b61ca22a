// worker_threads worker for `navguard audit DIR`: audits one file per
// message with its own wasm instance, streamed from disk in chunks as
// single-file mode does (memory does not grow with the file), and posts back
// the report (no columns).
import { parentPort } from 'node:worker_threads';
import { openSync, fstatSync, closeSync, readFileSync } from 'node:fs';
import { createRequire } from 'node:module';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';
import { streamAudit } from './stream-audit.mjs';
import { flightSeries } from './html-report.mjs';

const require = createRequire(import.meta.url);
const ng = require(join(dirname(fileURLToPath(import.meta.url)), '..', 'index.js'));

parentPort.on('message', ({ file, config, series }) => {
  const t0 = performance.now();
  let fd = null;
  try {
    fd = openSync(file, 'r');
    const size = fstatSync(fd).size;
    if (series) {
      // The HTML report's plots need every row: the log is read whole
      // (auditBytes gives the same report as the stream).
      const bytes = new Uint8Array(readFileSync(fd));
      const log = ng.readLog(bytes);
      const { report, columns } = ng.auditBytes(bytes, config);
      parentPort.postMessage({ file, bytes: size, ms: performance.now() - t0, report, series: flightSeries(log.columns, columns, report) });
      return;
    }
    const { report } = streamAudit(ng, fd, config);
    parentPort.postMessage({ file, bytes: size, ms: performance.now() - t0, report });
  } catch (e) {
    parentPort.postMessage({ file, ms: performance.now() - t0, error: String(e && e.message ? e.message : e) });
  } finally {
    if (fd !== null) closeSync(fd);
  }
});
