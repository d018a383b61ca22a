// Small CSV writers for the CLI (the reader is in the wasm core).

/** Per-sample output CSV: header t,status,f,r,c,kind. */
export function perSampleCsv(cols) {
  const n = cols.t.length;
  const parts = ['t,status,f,r,c,kind\n'];
  let chunk = '';
  for (let i = 0; i < n; i++) {
    chunk += `${cols.t[i]},${cols.status[i]},${fmt(cols.f[i])},${fmt(cols.r[i])},${fmt(cols.c[i])},${cols.kind[i]}\n`;
    if (chunk.length > 1 << 16) { parts.push(chunk); chunk = ''; }
  }
  parts.push(chunk);
  return parts.join('');
}

function fmt(v) {
  return Number.isFinite(v) ? Number(v.toFixed(5)).toString() : '';
}
