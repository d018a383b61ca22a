// Stream a log file from disk through a wasm StreamAuditor in fixed-size
// chunks, so memory stays bounded whatever the file's size and format (a
// ULog file is read twice: the reader's first pass finds which topics have
// data). Used by `navguard audit FILE` and by the `audit DIR` workers.
import { readSync } from 'node:fs';

export const CHUNK = 4 << 20;

/**
 * Audit the open file `fd`. `onChunk(run, pos, pass)` is called after each
 * chunk (per-sample output, progress). Returns `run.finish()`:
 * `{ report, columns }`, the columns holding the outputs of the last rows.
 */
export function streamAudit(ng, fd, config, { keepOutputs = false, onChunk } = {}) {
  const run = new ng.StreamAuditor(config, keepOutputs);
  try {
    const buf = Buffer.alloc(CHUNK);
    for (let pass = 1; ; pass++) {
      for (let pos = 0; ; ) {
        const n = readSync(fd, buf, 0, CHUNK, pos);
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
