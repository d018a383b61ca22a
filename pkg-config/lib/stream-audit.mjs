// Stream a log file from disk through a wasm StreamAuditor in fixed-size
// chunks, so memory stays bounded whatever the file's size and format (a
// ULog file is read twice: the reader's first pass finds which topics have
// data). Used by `navguard audit FILE` and by the `audit DIR` workers.
import { readSync } from 'node:fs';

export const CHUNK = 4 << 20;
/** With per-row outputs, smaller chunks: each chunk's outputs become a JS
 * string (about 100 bytes a row), and a 4 MiB chunk of 20-byte CSV rows
 * would be 200,000 rows, 20 MB of short-lived strings per call. */
export const OUTPUT_CHUNK = 256 << 10;

/**
 * Audit the open file `fd`. `onChunk(run, pos, pass)` is called after each
 * chunk (per-sample output, progress). Returns `run.finish()`:
 * `{ report, columns }`, the columns holding the outputs of the last rows.
 */
export function streamAudit(ng, fd, config, { keepOutputs = false, onChunk } = {}) {
  const run = new ng.StreamAuditor(config, keepOutputs);
  const size = keepOutputs ? OUTPUT_CHUNK : CHUNK;
  try {
    const buf = Buffer.alloc(size);
    for (let pass = 1; ; pass++) {
      for (let pos = 0; ; ) {
        const n = readSync(fd, buf, 0, size, pos);
        if (n === 0) break;
        pos += n;
        run.feed(buf.subarray(0, n));
        if (onChunk) onChunk(run, pos, pass);
      }
      if (!run.endPass()) break;
    }
    return run.finish();
  } finally {
    run.free();
  }
}
