// Memory and per-row cost of a streamed CSV audit, in process (no disk):
// survey flights laid end to end are fed to a StreamAuditor chunk by chunk,
// with the per-sample CSV formatted as the CLI does; every 100 MB it prints
// wasm memory, V8 heap and RSS. Then it times, on one 300 s flight, CSV
// parsing (readLog), parse + detection (StreamAuditor.feed) and per-sample
// formatting. Usage: node --expose-gc benches/stream-memory.mjs [MB=1000]
import { createRequire } from 'node:module';
import { join, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';

const root = join(dirname(fileURLToPath(import.meta.url)), '..');
const ng = createRequire(import.meta.url)(join(root, 'pkg'));
const { perSampleRows } = await import(join(root, 'pkg', 'lib', 'csv.mjs'));
const text = ng.simulate('clean-survey', 1);
const flight = text.split('\n');
const h = flight.findIndex((l) => l.startsWith('t,'));
const rows = flight.slice(h + 1).filter((l) => l).map((l) => { const i = l.indexOf(','); return [Number(l.slice(0, i)), l.slice(i)]; });
const span = rows[rows.length - 1][0] - rows[0][0] + 20;

const run = new ng.StreamAuditor(undefined, true);
run.feed(Buffer.from(flight.slice(0, h + 1).join('\n') + '\n'));
const limit = Number(process.argv[2] ?? 1000) * 1e6;
let bytes = 0, next = 0, leg = 0, outBytes = 0;
while (bytes < limit) {
  let buf = '';
  for (const [t, rest] of rows) buf += `${(t + leg * span).toFixed(3)}${rest}\n`;
  leg++;
  const b = Buffer.from(buf);
  bytes += b.length;
  run.feed(b);
  outBytes += perSampleRows(run.outputs()).length;
  if (bytes >= next) {
    global.gc?.();
    const m = process.memoryUsage();
    console.log(`${(bytes / 1e6).toFixed(0)} MB: wasm ${(ng.wasmMemoryBytes() / 1e6).toFixed(2)} MB, heapUsed ${(m.heapUsed / 1e6).toFixed(1)} MB, rss ${(m.rss / 1e6).toFixed(0)} MB, rows ${run.rows()}`);
    next += 100e6;
  }
}
const r = run.finish();
console.log(`rows ${r.report.rows}, data gaps ${r.report.dataGaps.length}, per-sample ${(outBytes / 1e6).toFixed(0)} MB`);

const one = Buffer.from(text);
const best = (f) => { let b = Infinity; for (let k = 0; k < 5; k++) { const t0 = performance.now(); f(); b = Math.min(b, performance.now() - t0); } return b; };
const n = ng.readLog(one).rows;
const parse = best(() => ng.readLog(one));
let out;
const feed = best(() => { const a = new ng.StreamAuditor(undefined, true); a.feed(one); out = a.outputs(); a.free(); });
const fmt = best(() => perSampleRows(out));
const us = (ms) => (1000 * ms / n).toFixed(1);
console.log(`per row (${n} rows): readLog ${us(parse)} µs, StreamAuditor.feed (parse + detect) ${us(feed)} µs, per-sample formatting ${us(fmt)} µs`);
