// The HTML flight report: one self-contained file (inline CSS, inline SVG
// plots, a few lines of inline script to sort the fleet table), no network.
// Plain ES module with no imports, so the CLI (`navguard report FILE --html`,
// `navguard audit DIR --html`) and the page (www/report-html.js links here)
// build the very same file from the same inputs.
//
//   flightSeries(logColumns, auditColumns, report) -> series (plain arrays)
//   renderReport({ title, version, generated, flights: [{ name, report, series, error }] }) -> html

/**
 * One word for a report: `faults` (at least one interval, causal or
 * reconciled over the whole log: a drag-off the detector followed and
 * dated only at its end is a fault of the flight), `clean`, or
 * `no verdict` when the log has no GPS fix to judge, so a log the detector
 * could not judge is never shown as a clean flight.
 */
export function verdictOf(report) {
  if (!report) return 'unreadable';
  if (!report.gpsAvailable) return 'no verdict';
  return faultList(report).length > 0 || reconciledCount(report) > 0 ? 'faults' : 'clean';
}

/**
 * The intervals to show: the causal `faults`, as the streaming API and
 * `audit --json` give them, so every table counts the same intervals.
 * (`report.reconciled` joins flicker of one kind and adds the spans the
 * detector dated once a fault ended, such as a drag-off from its onset;
 * `reconciledCount` says how many intervals that leaves.)
 */
export function faultList(report) {
  return (report && report.faults) || [];
}

/**
 * The whole-log reconciled intervals when they differ from the causal ones
 * (other spans or another count), else null: what the HTML report folds
 * under its causal table and the CLI lists after its own.
 */
export function reconciledIfDifferent(report) {
  const rec = report && Array.isArray(report.reconciled) ? report.reconciled : null;
  const faults = faultList(report);
  const same = (a, b) => a.start === b.start && a.end === b.end;
  return !rec || (rec.length === faults.length && rec.every((r, i) => same(r, faults[i]))) ? null : rec;
}

/**
 * One interval as a line of the CLI's text report: times in s since `t0`,
 * kind, severity and peak offset when given, peak F, driver.
 */
export function intervalLine(f, t0) {
  const sev = typeof f.severity === 'string' ? `  ${f.severity}` : '';
  const off = Number.isFinite(f.peakOffset) ? `  peak offset ${f.peakOffset.toFixed(1)} ${f.offsetUnit || ''}` : '';
  return `    ${(f.start - t0).toFixed(2).padStart(9)} - ${(f.end - t0).toFixed(2).padStart(9)} s  ${f.kind.padEnd(10)}${sev}${off}  peak F ${f.peakF.toFixed(2)}  driver ${f.driver} (${f.indicator})`;
}

/**
 * A per-row lookup of the whole-log verdict: `t` (the log's s) → 1 inside
 * a reconciled interval (`start ≤ t ≤ end`), else 0. Falls back to the
 * causal intervals for a report without `reconciled`. The intervals are
 * merged once and searched by bisection, so rows may come in any order.
 * It is the `reconciled` column of the per-sample CSV (CLI and page).
 */
export function reconciledAt(report) {
  const src = report && Array.isArray(report.reconciled) ? report.reconciled : faultList(report);
  const spans = src.map((f) => [f.start, f.end]).filter(([a, b]) => a <= b).sort((x, y) => x[0] - y[0]);
  const merged = [];
  for (const [a, b] of spans) {
    const last = merged[merged.length - 1];
    if (last && a <= last[1]) last[1] = Math.max(last[1], b);
    else merged.push([a, b]);
  }
  return (t) => {
    let lo = 0, hi = merged.length;
    while (lo < hi) {
      const mid = (lo + hi) >> 1;
      if (merged[mid][0] <= t) lo = mid + 1; else hi = mid;
    }
    return lo > 0 && t <= merged[lo - 1][1] ? 1 : 0;
  };
}

/** How many intervals the whole-log reconciliation leaves, or null. */
export function reconciledCount(report) {
  return report && Array.isArray(report.reconciled) ? report.reconciled.length : null;
}

/** What the receiver-quality value is: "HDOP" (unitless) or "eph (m)". */
export function qualityLabel(report) {
  return report && report.ephSource === 'hdop' ? 'HDOP' : 'eph (m)';
}

/** Seconds since the log's start, e.g. "83.4 s" or "12:03.4" past 10 min. */
export function fmtSince(s) {
  if (!Number.isFinite(s)) return '-';
  if (Math.abs(s) < 600) return `${s.toFixed(1)} s`;
  const m = Math.floor(s / 60);
  return `${m}:${(s - 60 * m).toFixed(1).padStart(4, '0')}`;
}

/** "2014-11-06 16:02:33 UTC" from the report's ISO start, or null. */
export function fmtUtc(iso) {
  return typeof iso === 'string' && iso.length >= 19 ? `${iso.slice(0, 10)} ${iso.slice(11, 19)} UTC` : null;
}

/** What was still checked in a log with no GPS fix (no residual verdicts). */
export function checkedWithoutGps(report) {
  const missing = new Set(report.missing || []);
  const have = [];
  if (!missing.has('imu')) have.push(`IMU (${Number.isFinite(report.imuRateHz) ? report.imuRateHz.toFixed(0) + ' Hz' : 'present'}): rates and data gaps`);
  if (!missing.has('baro')) have.push('barometer: read and propagated by the filter');
  if (!missing.has('attitude')) have.push('attitude: present');
  const gaps = (report.dataGaps || []).length;
  return `No GPS fix in this log, so no position or velocity check could be made and no verdict is given. Still checked: ${have.length ? have.join('; ') : 'nothing (no IMU or baro either)'}; ${gaps} data gap${gaps === 1 ? '' : 's'}.`;
}

// ------------------------------------------------------------------ series

const R_EARTH = 6378137.0; // WGS-84 equatorial radius, m

/**
 * Finite samples of `v` (by `t`), at most `max` of them: when there are
 * more, each of max/2 time buckets keeps its minimum and maximum in time
 * order, so a single spike survives the thinning. Times are shifted by `t0`.
 */
export function thin(t, v, t0, max = 1200) {
  const idx = [];
  for (let i = 0; i < t.length; i++) if (Number.isFinite(v[i]) && Number.isFinite(t[i])) idx.push(i);
  const out = { t: [], v: [] };
  if (idx.length <= max) {
    for (const i of idx) { out.t.push(round(t[i] - t0, 3)); out.v.push(round(v[i], 4)); }
    return out;
  }
  const b = Math.max(1, Math.floor(max / 2));
  const ta = t[idx[0]], tb = t[idx[idx.length - 1]];
  const w = (tb - ta) / b || 1;
  let k = 0;
  for (let j = 0; j < b && k < idx.length; j++) {
    const end = j === b - 1 ? Infinity : ta + (j + 1) * w;
    let lo = -1, hi = -1;
    for (; k < idx.length && t[idx[k]] < end; k++) {
      const i = idx[k];
      if (lo < 0 || v[i] < v[lo]) lo = i;
      if (hi < 0 || v[i] > v[hi]) hi = i;
    }
    if (lo < 0) continue;
    for (const i of lo === hi ? [lo] : lo < hi ? [lo, hi] : [hi, lo]) { out.t.push(round(t[i] - t0, 3)); out.v.push(round(v[i], 4)); }
  }
  return out;
}

function round(x, d) {
  const p = 10 ** d;
  return Math.round(x * p) / p;
}

/** `v` minus its first finite value (altitude change), same length. */
function relative(v) {
  if (!v) return null;
  let v0 = NaN;
  for (const x of v) if (Number.isFinite(x)) { v0 = x; break; }
  return Array.from(v, (x) => x - v0);
}

/**
 * Plot data for one flight, plain arrays (JSON-safe, small): times are
 * seconds since the log's start (`report.startT`).
 * `log`: readLog()'s columns; `out`: the audit's per-row columns.
 */
export function flightSeries(log, out, report, max = 1200) {
  const t0 = Number.isFinite(report.startT) ? report.startT : (out.t && out.t.length ? out.t[0] : 0);
  const lt = log.t || [];
  const s = { t0 };
  s.f = thin(out.t, out.f, t0, max);
  s.resid = {};
  for (const k of ['rPn', 'rPe', 'rPd', 'rBaro']) if (out[k]) s.resid[k] = thin(out.t, out[k], t0, max);
  s.alt = {};
  if (log.alt) s.alt.gps = thin(lt, relative(log.alt), t0, max);
  if (log.baro) s.alt.baro = thin(lt, relative(log.baro), t0, max);
  s.quality = {};
  for (const k of ['sats', 'eph', 'fix']) if (log[k]) s.quality[k] = thin(lt, log[k], t0, max);
  // Track: N/E metres around the first fix (or the log's own pn/pe).
  const n = new Float64Array(lt.length).fill(NaN), e = new Float64Array(lt.length).fill(NaN);
  let lat0 = NaN, lon0 = NaN, c0 = 1;
  for (let i = 0; i < lt.length; i++) {
    if (log.fix && log.fix[i] < 2) continue;
    if (log.lat && log.lon && Number.isFinite(log.lat[i]) && Number.isFinite(log.lon[i])) {
      if (Number.isNaN(lat0)) { lat0 = log.lat[i]; lon0 = log.lon[i]; c0 = Math.cos(lat0 * Math.PI / 180); }
      n[i] = (log.lat[i] - lat0) * Math.PI / 180 * R_EARTH;
      e[i] = (log.lon[i] - lon0) * Math.PI / 180 * R_EARTH * c0;
    } else if (log.pn && log.pe && Number.isFinite(log.pn[i]) && Number.isFinite(log.pe[i])) {
      n[i] = log.pn[i];
      e[i] = log.pe[i];
    }
  }
  // Every k-th position (a track needs its shape, not each sample), plus
  // the largest jump in each stretch so a position spike stays visible.
  const idx = [];
  for (let i = 0; i < lt.length; i++) if (Number.isFinite(n[i]) && Number.isFinite(e[i])) idx.push(i);
  const k = Math.max(1, Math.ceil(idx.length / (2 * max)));
  s.track = { t: [], n: [], e: [], anchor: Number.isNaN(lat0) ? null : [round(lat0, 7), round(lon0, 7)] };
  for (let j = 0; j < idx.length; j += k) {
    let pick = idx[j], best = -1;
    for (let q = j; q < Math.min(idx.length, j + k); q++) {
      const i = idx[q], p = idx[Math.max(0, q - 1)];
      const jump = Math.hypot(n[i] - n[p], e[i] - e[p]);
      if (jump > best) { best = jump; pick = i; }
    }
    s.track.t.push(round(lt[pick] - t0, 3));
    s.track.n.push(round(n[pick], 2));
    s.track.e.push(round(e[pick], 2));
  }
  return s;
}

// ------------------------------------------------------------------ SVG plots

const COLORS = ['#1f77b4', '#d62728', '#2ca02c', '#9467bd', '#ff7f0e', '#8c564b'];

function esc(s) {
  return String(s).replace(/[&<>"']/g, (c) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;', "'": '&#39;' })[c]);
}

/** Round tick steps: 1, 2, 5 x 10^k, about `n` ticks over [a, b]. */
export function ticks(a, b, n = 5) {
  if (!(b > a)) return [a];
  const raw = (b - a) / n;
  const p = 10 ** Math.floor(Math.log10(raw));
  const step = [1, 2, 5, 10].map((m) => m * p).find((s) => s >= raw) || 10 * p;
  const out = [];
  for (let x = Math.ceil(a / step) * step; x <= b + step * 1e-9; x += step) out.push(Math.abs(x) < step * 1e-9 ? 0 : x);
  return out;
}

function fmtTick(x) {
  const a = Math.abs(x);
  if (a !== 0 && (a >= 1e5 || a < 1e-3)) return x.toExponential(0);
  return String(round(x, 3));
}

/**
 * A y range that single spikes do not set: the 1st to 99th percentile of all
 * values, widened by a quarter of its span (and to take in 0 when it is
 * near), or the full range when that is no wider than twice the percentile
 * range. Values outside are drawn at the edge with a clip marker.
 */
export function robustRange(values, zero = false) {
  const v = values.filter(Number.isFinite).sort((a, b) => a - b);
  if (!v.length) return [0, 1];
  const q = (p) => v[Math.min(v.length - 1, Math.max(0, Math.round(p * (v.length - 1))))];
  let lo = v[0], hi = v[v.length - 1];
  const plo = q(0.01), phi = q(0.99);
  const span = phi - plo;
  if (v.length >= 20 && span > 0 && hi - lo > 2 * span * 1.5) {
    lo = plo - 0.25 * span;
    hi = phi + 0.25 * span;
    lo = Math.max(lo, v[0]);
    hi = Math.min(hi, v[v.length - 1]);
  }
  if (zero) { lo = Math.min(lo, 0); hi = Math.max(hi, 0); }
  if (hi - lo < 1e-9) { lo -= 0.5; hi += 0.5; }
  const pad = 0.04 * (hi - lo);
  return [lo - pad, hi + pad];
}

/**
 * An inline SVG time plot. `series`: [{ label, t, v, color }]; `shades`:
 * [{ start, end, fill, title }] (fault intervals, modes); `marks`:
 * [{ t, title }] (messages); x range [x0, x1] (s since start) shared by
 * every plot of a flight so they line up.
 */
export function svgPlot({ id, title, ylabel, series, shades = [], marks = [], x0, x1, zero = false, height = 170, width = 900, names = false }) {
  const L = 58, R = 12, T = 22, B = 26;
  const W = width - L - R, H = height - T - B;
  const all = [];
  for (const s of series) for (const y of s.v) all.push(y);
  const [y0, y1] = robustRange(all, zero);
  const X = (x) => L + ((x - x0) / (x1 - x0 || 1)) * W;
  const Y = (y) => T + (1 - (y - y0) / (y1 - y0 || 1)) * H;
  const parts = [];
  parts.push(`<svg xmlns="http://www.w3.org/2000/svg" class="plot" id="${esc(id)}" viewBox="0 0 ${width} ${height}" width="100%" role="img" aria-label="${esc(title)}">`);
  parts.push(`<text x="${L}" y="14" class="pt">${esc(title)}</text>`);
  for (const s of shades) {
    const a = Math.max(x0, s.start), b = Math.min(x1, s.end);
    if (b < a) continue;
    parts.push(`<rect x="${X(a).toFixed(1)}" y="${T}" width="${Math.max(1.5, X(b) - X(a)).toFixed(1)}" height="${H}" fill="${s.fill}" class="${s.cls || ''}"><title>${esc(s.title || '')}</title></rect>`);
    if (names && s.name && X(b) - X(a) > 7 * s.name.length) parts.push(`<text x="${(X(a) + 3).toFixed(1)}" y="${T + H - 4}" class="mn">${esc(s.name)}</text>`);
  }
  for (const y of ticks(y0, y1, 4)) {
    parts.push(`<line x1="${L}" x2="${L + W}" y1="${Y(y).toFixed(1)}" y2="${Y(y).toFixed(1)}" class="grid"/><text x="${L - 4}" y="${(Y(y) + 3).toFixed(1)}" class="yt">${fmtTick(y)}</text>`);
  }
  for (const x of ticks(x0, x1, 8)) {
    parts.push(`<line x1="${X(x).toFixed(1)}" x2="${X(x).toFixed(1)}" y1="${T + H}" y2="${T + H + 4}" class="axis"/><text x="${X(x).toFixed(1)}" y="${T + H + 15}" class="xt">${fmtTick(x)}</text>`);
  }
  parts.push(`<text x="12" y="${T + H / 2}" class="yl" transform="rotate(-90 12 ${T + H / 2})">${esc(ylabel)}</text>`);
  parts.push(`<rect x="${L}" y="${T}" width="${W}" height="${H}" class="frame"/>`);
  let clipped = 0;
  series.forEach((s, k) => {
    const color = s.color || COLORS[k % COLORS.length];
    // A pause of more than 5 x the median sample interval (and 1 s) breaks the line.
    const dts = [];
    for (let i = 1; i < s.t.length; i++) dts.push(s.t[i] - s.t[i - 1]);
    dts.sort((a, b) => a - b);
    const brk = Math.max(1, 5 * (dts[dts.length >> 1] || 0));
    let d = '';
    const clips = [];
    for (let i = 0; i < s.t.length; i++) {
      let y = s.v[i];
      if (y > y1 || y < y0) { clips.push([s.t[i], y > y1]); y = Math.min(y1, Math.max(y0, y)); }
      const cmd = i === 0 || s.t[i] - s.t[i - 1] > brk ? 'M' : 'L';
      d += `${cmd}${X(s.t[i]).toFixed(1)} ${Y(y).toFixed(1)}`;
    }
    if (d) parts.push(`<path d="${d}" stroke="${color}" class="ln" data-label="${esc(s.label)}" data-n="${s.t.length}"/>`);
    clipped += clips.length;
    for (const [t, up] of clips.slice(0, 200)) {
      const x = X(t), y = up ? T + 1 : T + H - 1;
      parts.push(`<path d="M${(x - 4).toFixed(1)} ${y + (up ? 6 : -6)}L${x.toFixed(1)} ${y}L${(x + 4).toFixed(1)} ${y + (up ? 6 : -6)}Z" fill="${color}" class="clip"><title>${esc(s.label)}: off scale at ${round(t, 2)} s</title></path>`);
    }
  });
  for (const m of marks) {
    if (m.t < x0 || m.t > x1) continue;
    parts.push(`<line x1="${X(m.t).toFixed(1)}" x2="${X(m.t).toFixed(1)}" y1="${T}" y2="${T + H}" class="mark ${m.cls || ''}"><title>${esc(m.title)}</title></line>`);
  }
  // legend
  let lx = L + W;
  const legend = [];
  for (let k = series.length - 1; k >= 0; k--) {
    const label = series[k].label;
    lx -= 18 + 7.2 * label.length;
    legend.push(`<rect x="${lx.toFixed(0)}" y="6" width="10" height="10" fill="${series[k].color || COLORS[k % COLORS.length]}"/><text x="${(lx + 13).toFixed(0)}" y="14" class="lg">${esc(label)}</text>`);
  }
  parts.push(...legend);
  if (clipped) parts.push(`<text x="${L + 4}" y="${T + 12}" class="cl">${clipped} point${clipped === 1 ? '' : 's'} off scale (marked ▲▼)</text>`);
  parts.push('</svg>');
  return parts.join('');
}

/** The track (N/E m), flagged stretches in red. */
export function svgTrack({ id, track, faults, t0 = 0, size = 420 }) {
  const { n, e, t } = track;
  const P = 34;
  if (!n.length) return `<p class="muted">No position to draw a track.</p>`;
  let nmin = Math.min(...n), nmax = Math.max(...n), emin = Math.min(...e), emax = Math.max(...e);
  const span = Math.max(nmax - nmin, emax - emin, 1);
  const cn = (nmin + nmax) / 2, ce = (emin + emax) / 2;
  nmin = cn - span / 2; nmax = cn + span / 2; emin = ce - span / 2; emax = ce + span / 2;
  const S = size - 2 * P;
  const X = (x) => P + ((x - emin) / span) * S;
  const Y = (y) => P + (1 - (y - nmin) / span) * S;
  const flagged = (x) => faults.some((f) => x >= f.start - t0 && x <= f.end - t0);
  let dOk = '', dBad = '';
  for (let i = 0; i < n.length; i++) {
    const bad = flagged(t[i]);
    const seg = `${i === 0 || t[i] - t[i - 1] > 5 ? 'M' : 'L'}${X(e[i]).toFixed(1)} ${Y(n[i]).toFixed(1)}`;
    if (bad) dBad += (i > 0 && flagged(t[i - 1]) ? seg : seg.replace(/^L/, 'M'));
    dOk += seg;
  }
  const parts = [`<svg xmlns="http://www.w3.org/2000/svg" class="track" id="${esc(id)}" viewBox="0 0 ${size} ${size}" width="${size}" role="img" aria-label="track">`];
  parts.push(`<rect x="${P}" y="${P}" width="${S}" height="${S}" class="frame"/>`);
  for (const v of ticks(emin, emax, 4)) parts.push(`<text x="${X(v).toFixed(1)}" y="${size - P + 14}" class="xt">${fmtTick(round(v, 1))}</text>`);
  for (const v of ticks(nmin, nmax, 4)) parts.push(`<text x="${P - 4}" y="${(Y(v) + 3).toFixed(1)}" class="yt">${fmtTick(round(v, 1))}</text>`);
  parts.push(`<text x="${size / 2}" y="${size - 4}" class="xt">east (m)</text><text x="10" y="${size / 2}" class="yl" transform="rotate(-90 10 ${size / 2})">north (m)</text>`);
  parts.push(`<path d="${dOk}" class="ln" stroke="#1f77b4"/>`);
  if (dBad) parts.push(`<path d="${dBad}" class="ln bad" stroke="#d62728"/>`);
  parts.push(`<circle cx="${X(e[0]).toFixed(1)}" cy="${Y(n[0]).toFixed(1)}" r="4" fill="#2ca02c"><title>start</title></circle>`);
  parts.push(`<circle cx="${X(e[e.length - 1]).toFixed(1)}" cy="${Y(n[n.length - 1]).toFixed(1)}" r="4" fill="#333"><title>end</title></circle>`);
  parts.push('</svg>');
  return parts.join('');
}

// ------------------------------------------------------------------ HTML

const CSS = `
body{font:14px/1.45 system-ui,-apple-system,"Segoe UI",sans-serif;margin:0;color:#1d1d1f;background:#f6f7f9}
main{max-width:1000px;margin:0 auto;padding:16px 20px 60px}
h1{font-size:22px;margin:8px 0 4px}h2{font-size:18px;margin:0 0 6px}h3{font-size:15px;margin:18px 0 6px}
.muted{color:#666}.small{font-size:12px}
section.flight{background:#fff;border:1px solid #dde;border-radius:8px;padding:14px 18px;margin:18px 0}
.badge{white-space:nowrap;display:inline-block;padding:2px 10px;border-radius:12px;font-weight:600;font-size:13px;color:#fff}
.v-faults{background:#c62828}.v-clean{background:#2e7d32}.v-no-verdict{background:#757575}.v-unreadable{background:#6d4c41}
table{border-collapse:collapse;width:100%;font-size:13px;background:#fff}th,td{padding:3px 8px;border-bottom:1px solid #e4e6ea;text-align:left;vertical-align:top}
th{background:#f0f2f5}table.fleet td,table.fleet th{white-space:nowrap}table.fleet td:first-child{white-space:normal;word-break:break-all}td.num,th.num{text-align:right;font-variant-numeric:tabular-nums}
table.sortable th{cursor:pointer;user-select:none}table.sortable th:after{content:" \\2195";color:#aaa}
dl.sum{display:grid;grid-template-columns:max-content 1fr;gap:2px 14px;margin:8px 0}dl.sum dt{color:#555}dl.sum dd{margin:0}
svg.plot{display:block;margin:6px 0;background:#fff}svg.track{display:block;background:#fff}
svg .pt{font-size:12px;font-weight:600}svg .xt{font-size:10px;text-anchor:middle;fill:#444}svg .yt{font-size:10px;text-anchor:end;fill:#444}
svg .yl{font-size:11px;text-anchor:middle;fill:#444}svg .lg{font-size:11px}svg .mn{font-size:10px;fill:#37474f}svg .cl{font-size:10px;fill:#a00}
svg .grid{stroke:#eceef1}svg .axis{stroke:#999}svg .frame{fill:none;stroke:#bbb}svg .ln{fill:none;stroke-width:1.2}svg .ln.bad{stroke-width:2.4}
svg .mark{stroke:#7b1fa2;stroke-width:1;stroke-dasharray:2 2;opacity:.55}svg .mark.error{stroke:#c62828;opacity:.8}
.note{background:#fff8e1;border-left:4px solid #f9a825;padding:6px 10px;margin:8px 0}
.sev-high{color:#b71c1c;font-weight:600}.sev-medium{color:#e65100}.sev-low{color:#555}
details{margin:8px 0}summary{cursor:pointer;font-weight:600}
.legend{font-size:12px;color:#555}.sw{display:inline-block;width:12px;height:10px;margin:0 4px 0 10px;vertical-align:middle}
`;

const SORT_JS = `
for (const t of document.querySelectorAll('table.sortable')) {
  t.querySelectorAll('th').forEach((th, col) => th.addEventListener('click', () => {
    const dir = th.dataset.dir === 'asc' ? 'desc' : 'asc';
    t.querySelectorAll('th').forEach((h) => delete h.dataset.dir);
    th.dataset.dir = dir;
    const rows = [...t.tBodies[0].rows];
    const key = (r) => { const c = r.cells[col]; const v = c.dataset.sort ?? c.textContent; const n = Number(v); return v !== '' && Number.isFinite(n) ? n : v; };
    rows.sort((a, b) => { const x = key(a), y = key(b); const c = typeof x === 'number' && typeof y === 'number' ? x - y : String(x).localeCompare(String(y)); return dir === 'asc' ? c : -c; });
    for (const r of rows) t.tBodies[0].appendChild(r);
  }));
}`;

const MODE_FILLS = ['rgba(33,150,243,.07)', 'rgba(76,175,80,.08)', 'rgba(255,193,7,.10)', 'rgba(156,39,176,.07)', 'rgba(0,150,136,.08)', 'rgba(121,85,72,.08)'];

/** A fault interval's severity word, or '' when the report has none. */
function severity(f) {
  return typeof f.severity === 'string' ? f.severity : '';
}

function fmtNum(x, d = 2) {
  return Number.isFinite(x) ? x.toFixed(d) : '-';
}

function verdictBadge(v) {
  return `<span class="badge v-${v.replace(' ', '-')}" data-verdict="${v}">${v}</span>`;
}

/** Shaded bands and marks shared by a flight's time plots. */
function overlays(report, t0, tEnd) {
  const faults = faultList(report).map((f, i) => ({ start: f.start - t0, end: f.end - t0, fill: f.kind === 'residual' ? 'rgba(229,57,53,.28)' : 'rgba(255,152,0,.28)', title: `interval ${i + 1}: ${f.kind} ${fmtSince(f.start - t0)} - ${fmtSince(f.end - t0)}`, cls: 'fault' }));
  const modes = (report.modes || []).map((m, i, a) => ({ start: m.t - t0, end: (i + 1 < a.length ? a[i + 1].t : t0 + tEnd) - t0, fill: MODE_FILLS[i % MODE_FILLS.length], title: `mode ${m.mode} from ${fmtSince(m.t - t0)}`, cls: 'mode', name: m.mode }));
  const marks = (report.messages || []).filter((m) => m.level === 'error' || m.level === 'warning').map((m) => ({ t: m.t - t0, title: `${fmtSince(m.t - t0)} ${m.level}: ${m.text}`, cls: m.level }));
  return { shades: [...modes, ...faults], marks };
}

function summaryList(report, name) {
  const L = [];
  const row = (k, v) => L.push(`<dt>${esc(k)}</dt><dd>${v}</dd>`);
  row('log', esc(name));
  row('format', esc(report.format));
  row('start', fmtUtc(report.startUtc) ? esc(fmtUtc(report.startUtc)) : '<span class="muted">unknown (no GPS time in the log)</span>');
  row('duration', `${fmtSince(report.durationS)} (times below are seconds since the log's start)`);
  row('rows', Number(report.rows).toLocaleString('en-US'));
  row('GPS', report.gpsAvailable ? `${report.gpsEpochs} epochs at ${fmtNum(report.gpsRateHz, 1)} Hz, fix in ${fmtNum(100 * report.gpsFixFraction, 1)}% of reports` : 'no fix: no verdict');
  row('IMU', `${fmtNum(report.imuRateHz, 1)} Hz`);
  row('receiver quality', report.ephSource === 'hdop' ? 'HDOP (unitless; this log has no accuracy in metres)' : report.ephSource === 'eph' ? 'eph (m), the receiver\'s horizontal accuracy' : 'not in the log');
  row('flagged GPS epochs', report.gpsAvailable ? `${fmtNum(100 * report.flaggedGpsEpochFraction, 2)}%` : 'none to judge');
  if ((report.missing || []).length) row('missing inputs', esc(report.missing.join(', ')));
  const fw = (report.meta || []).find(([k]) => k === 'firmware' || k === 'ver_sw');
  if (fw) row('firmware', esc(fw[1]));
  return `<dl class="sum">${L.join('')}</dl>`;
}

function faultTable(report, t0) {
  const faults = faultList(report);
  if (!faults.length) return `<p class="muted">${report.gpsAvailable ? 'No fault interval.' : 'No interval: nothing to judge without GPS.'}</p>`;
  return intervalTable(faults, t0, 'interval', 'faults sortable');
}

/**
 * The whole-log reconciled intervals when they differ from the causal ones
 * (flicker joined; faults the detector did not flag throughout dated from
 * their onset, such as a drag-off it followed or a slow drift called late),
 * folded away under the causal table; '' when
 * they are the same. Their rows are `tr.reconciled-interval`.
 */
export function reconciledTable(report, t0) {
  const rec = reconciledIfDifferent(report);
  if (!rec) return '';
  return `<details class="reconciled"><summary>Reconciled over the whole log: ${rec.length} interval${rec.length === 1 ? '' : 's'}</summary><p class="note">The causal intervals above are what the detector said as the samples came. Here, intervals of one kind less than 2 s apart are joined, and a fault the detector did not flag throughout is dated from its onset: a drag-off it followed or a step held past its coast limit, once it ended; a slow drift or ramp called late, once its offset jumped back; a frozen or lost fix from the first fix owed, a stuck baro from its first repeat.</p>${intervalTable(rec, t0, 'reconciled-interval', 'reconciled sortable')}</details>`;
}

function intervalTable(faults, t0, rowClass, tableClass) {
  const hasSev = faults.some((f) => severity(f));
  const hasOff = faults.some((f) => Number.isFinite(f.peakOffset));
  const head = `<tr><th class="num">#</th><th class="num">start</th><th class="num">end</th><th class="num">duration s</th><th>kind</th>${hasSev ? '<th>severity</th>' : ''}${hasOff ? '<th class="num">peak offset</th>' : ''}<th class="num">peak F</th><th>driver</th><th>indicator</th></tr>`;
  const rows = faults.map((f, i) => {
    const dur = Number.isFinite(f.durationS) ? f.durationS : f.end - f.start;
    const sev = severity(f);
    return `<tr class="${rowClass}" data-start="${f.start - t0}" data-end="${f.end - t0}" data-kind="${esc(f.kind)}"><td class="num">${i + 1}</td><td class="num" data-sort="${f.start - t0}">${fmtSince(f.start - t0)}</td><td class="num" data-sort="${f.end - t0}">${fmtSince(f.end - t0)}</td><td class="num">${fmtNum(dur, 2)}</td><td>${esc(f.kind)}</td>${hasSev ? `<td class="sev-${esc(sev)}">${esc(sev || '-')}</td>` : ''}${hasOff ? `<td class="num">${Number.isFinite(f.peakOffset) ? `${fmtNum(f.peakOffset, 1)} ${esc(f.offsetUnit || '')}` : '-'}</td>` : ''}<td class="num">${fmtNum(f.peakF, 2)}</td><td>${esc(f.driver)}</td><td>${esc(f.indicator)}</td></tr>`;
  });
  return `<table class="${tableClass}"><thead>${head}</thead><tbody>${rows.join('')}</tbody></table>`;
}

function eventTables(report, t0) {
  const out = [];
  const modes = report.modes || [];
  if (modes.length) {
    out.push(`<details open class="modes"><summary>Flight modes (${modes.length})</summary><table><thead><tr><th class="num">from</th><th>mode</th></tr></thead><tbody>${modes.map((m) => `<tr><td class="num">${fmtSince(m.t - t0)}</td><td>${esc(m.mode)}</td></tr>`).join('')}</tbody></table></details>`);
  }
  const msgs = report.messages || [];
  if (msgs.length) {
    out.push(`<details class="messages"${msgs.length <= 30 ? ' open' : ''}><summary>Autopilot messages (${msgs.length}${msgs.length >= 256 ? ', first 256' : ''})</summary><table><thead><tr><th class="num">t</th><th>level</th><th>message</th></tr></thead><tbody>${msgs.map((m) => `<tr class="lvl-${esc(m.level)}"><td class="num">${fmtSince(m.t - t0)}</td><td>${esc(m.level)}</td><td>${esc(m.text)}</td></tr>`).join('')}</tbody></table></details>`);
  }
  if (!modes.length && !msgs.length) out.push('<p class="muted small">The log has no flight modes or autopilot messages.</p>');
  return out.join('');
}

function plots(i, report, s) {
  const t0 = s.t0;
  const tEnd = Math.max(report.durationS || 0, 1e-3);
  const x0 = 0, x1 = tEnd;
  const { shades, marks } = overlays(report, t0, tEnd);
  const out = [];
  out.push(`<p class="legend"><span class="sw" style="background:rgba(229,57,53,.5)"></span>fault interval<span class="sw" style="background:rgba(255,152,0,.5)"></span>GPS outage<span class="sw" style="background:rgba(33,150,243,.25)"></span>flight modes (alternating shades)<span class="sw" style="background:#7b1fa2;height:2px"></span>autopilot warning/error</p>`);
  out.push(svgPlot({ id: `f-${i}-F`, title: 'F indicator (fault when above the threshold)', ylabel: 'F', series: [{ label: 'F', ...s.f }], shades, marks, x0, x1, zero: true, names: true }));
  const res = [['rPn', 'north'], ['rPe', 'east'], ['rPd', 'down'], ['rBaro', 'baro']].filter(([k]) => s.resid[k] && s.resid[k].t.length).map(([k, label]) => ({ label, ...s.resid[k] }));
  if (res.length) out.push(svgPlot({ id: `f-${i}-res`, title: 'Position residuals (measurement minus prediction)', ylabel: 'm', series: res, shades, marks, x0, x1, zero: true }));
  const alt = [];
  if (s.alt.gps && s.alt.gps.t.length) alt.push({ label: 'GPS altitude', ...s.alt.gps });
  if (s.alt.baro && s.alt.baro.t.length) alt.push({ label: 'baro altitude', ...s.alt.baro });
  if (alt.length) out.push(svgPlot({ id: `f-${i}-alt`, title: 'Altitude change from the first value: GPS vs baro', ylabel: 'm', series: alt, shades, marks, x0, x1 }));
  const q = s.quality;
  const ql = qualityLabel(report);
  const qs = [];
  if (q.sats && q.sats.t.length) qs.push({ label: 'satellites', ...q.sats });
  if (q.eph && q.eph.t.length) qs.push({ label: ql, ...q.eph });
  if (q.fix && q.fix.t.length) qs.push({ label: 'fix type', ...q.fix });
  if (qs.length) out.push(svgPlot({ id: `f-${i}-gq`, title: `Receiver quality: satellites, ${ql}, fix type`, ylabel: '', series: qs, shades, marks, x0, x1, zero: true }));
  out.push('<div class="trackbox"><h3>Track</h3>');
  out.push(svgTrack({ id: `f-${i}-track`, track: s.track, faults: faultList(report), t0 }));
  if (s.track.anchor) out.push(`<p class="small muted">North/east metres from the first fix at ${s.track.anchor[0]}, ${s.track.anchor[1]}; flagged stretches in red.</p>`);
  out.push('</div>');
  return out.join('');
}

function flightSection(fl, i) {
  const { name, report, series, error } = fl;
  const v = error ? 'unreadable' : verdictOf(report);
  const L = [`<section class="flight" id="flight-${i}" data-verdict="${v}"><h2>${esc(name)} ${verdictBadge(v)}</h2>`];
  if (error) {
    L.push(`<p>Could not be read: ${esc(error)}</p></section>`);
    return L.join('');
  }
  const t0 = Number.isFinite(report.startT) ? report.startT : series ? series.t0 : 0;
  L.push(summaryList(report, name));
  if (!report.gpsAvailable) L.push(`<p class="note nogps">${esc(checkedWithoutGps(report))}</p>`);
  const rc = reconciledCount(report);
  const rec = reconciledTable(report, t0);
  L.push(`<h3>Fault intervals (${faultList(report).length}${rec ? `; ${rc} reconciled over the whole log, below` : ''})</h3>`);
  L.push(faultTable(report, t0));
  L.push(rec);
  if (series) L.push(plots(i, report, series));
  L.push(eventTables(report, t0));
  const warn = report.warnings || [];
  if (warn.length) L.push(`<details class="warnings"><summary>Reader and detector warnings (${warn.length})</summary><ul>${warn.map((w) => `<li>${esc(w)}</li>`).join('')}</ul></details>`);
  L.push('</section>');
  return L.join('');
}

function fleetTable(flights) {
  const rows = flights.map((fl, i) => {
    const r = fl.report;
    const v = fl.error ? 'unreadable' : verdictOf(r);
    const link = `<a href="#flight-${i}">${esc(fl.name)}</a>`;
    if (fl.error) return `<tr data-verdict="${v}"><td>${link}</td><td>-</td><td>-</td><td class="num" data-sort="-1">-</td><td class="num" data-sort="-1">-</td><td class="num" data-sort="-1">-</td><td class="num" data-sort="-1">-</td><td>${verdictBadge(v)}</td></tr>`;
    const faults = faultList(r);
    const flagged = r.gpsAvailable ? 100 * r.flaggedGpsEpochFraction : -1;
    return `<tr data-verdict="${v}"><td>${link}</td><td>${esc(r.format)}</td><td>${esc(fmtUtc(r.startUtc) || '-')}</td><td class="num" data-sort="${r.durationS}">${fmtSince(r.durationS)}</td><td class="num" data-sort="${r.gpsAvailable ? r.gpsRateHz : -1}">${r.gpsAvailable ? fmtNum(r.gpsRateHz, 1) : 'no GPS'}</td><td class="num" data-sort="${flagged}">${r.gpsAvailable ? fmtNum(flagged, 2) + '%' : '-'}</td><td class="num" data-sort="${faults.length}">${faults.length}</td><td data-sort="${v}">${verdictBadge(v)}</td></tr>`;
  });
  return `<table class="fleet sortable"><thead><tr><th>log</th><th>format</th><th>start (UTC)</th><th class="num">duration</th><th class="num">GPS Hz</th><th class="num">flagged</th><th class="num">intervals</th><th>verdict</th></tr></thead><tbody>${rows.join('')}</tbody></table>`;
}

/**
 * The whole report as one HTML string. `flights`: [{ name, report, series,
 * error }] (series from flightSeries, optional; error for an unreadable
 * log). With more than one flight, a sortable fleet table links to each.
 */
export function renderReport({ title = 'navguard flight report', version = '', generated = new Date().toISOString(), flights }) {
  const counts = {};
  for (const fl of flights) { const v = fl.error ? 'unreadable' : verdictOf(fl.report); counts[v] = (counts[v] || 0) + 1; }
  const tally = ['faults', 'clean', 'no verdict', 'unreadable'].filter((k) => counts[k]).map((k) => `${counts[k]} ${k}`).join(', ');
  return `<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<meta http-equiv="Content-Security-Policy" content="default-src 'none'; style-src 'unsafe-inline'; script-src 'unsafe-inline'; img-src data:">
<meta name="viewport" content="width=device-width, initial-scale=1">
<meta name="generator" content="navguard ${esc(version)}">
<title>${esc(title)}</title><style>${CSS}</style></head>
<body><main>
<h1>${esc(title)}</h1>
<p class="muted small">navguard ${esc(version)} · generated ${esc(generated)} · ${flights.length} log${flights.length === 1 ? '' : 's'}: ${esc(tally)}. A log with no GPS fix gets <b>no verdict</b>, never "clean".</p>
${flights.length > 1 ? fleetTable(flights) : ''}
${flights.map(flightSection).join('\n')}
</main><script>${SORT_JS}</script></body></html>
`;
}
