// Small CSV writers for the CLI (the reader is in the wasm core).

const RESID = ['rPn', 'rPe', 'rPd', 'rVn', 'rVe', 'rVd', 'rBaro'];

/** Per-sample output CSV: t,status,f,r,c (contract), then kind and the
 * residuals per axis (m, m/s; empty where the row had no such measurement). */
export function perSampleCsv(cols) {
  return perSampleHeader() + perSampleRows(cols);
}

export function perSampleHeader() {
  return ['t,status,f,r,c,kind', ...RESID].join(',') + '\n';
}

/** The rows of one batch of outputs (no header), for streamed writing. */
export function perSampleRows(cols) {
  const n = cols.t.length;
  const parts = [];
  let chunk = '';
  for (let i = 0; i < n; i++) {
    let line = `${cols.t[i]},${cols.status[i]},${fmt(cols.f[i])},${fmt(cols.r[i])},${fmt(cols.c[i])},${cols.kind[i]}`;
    for (const k of RESID) line += ',' + fmt(cols[k][i]);
    chunk += line + '\n';
    if (chunk.length > 1 << 16) { parts.push(chunk); chunk = ''; }
  }
  parts.push(chunk);
  return parts.join('');
}

function fmt(v) {
  return Number.isFinite(v) ? Number(v.toFixed(5)).toString() : '';
}
