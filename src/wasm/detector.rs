//! The streaming detector (contract §2): `Detector`, its snapshot helpers
//! and the contract's column names. Core module.

use js_sys::{Array, Object, Uint8Array};
use wasm_bindgen::prelude::*;

use super::interop::{self as js_in, err, set, stats_object, Obj, MAX_BYTES};
use crate::config::Config;
use crate::detector::{row_from_values, rows_from_columns, Detector as CoreDetector, Output, OutputColumns};
use crate::logs::decimal::Shortest;
use crate::sample::{Sample, COLUMNS};

thread_local! {
    /// Column names as JS strings, made once: property lookups then cost no
    /// string conversion per sample.
    static KEYS: Vec<JsValue> = COLUMNS.iter().map(|c| JsValue::from_str(c)).collect();
}

/// Largest `pushColumns` batch (rows per call). The batch is processed in
/// chunks of [`CHUNK_ROWS`], so wasm memory does not grow with it; the limit
/// bounds the result arrays (26 bytes a row, allocated in JS).
pub const MAX_BATCH_ROWS: usize = 1 << 24;
/// Rows per chunk of a `pushColumns` batch: 28 columns × 8 B × 4096 = 918 KB
/// of scratch, reused.
const CHUNK_ROWS: usize = 4096;

/// `[t, status, f, r, c, kind, gpsEpoch]` (what `pushRowInto` writes).
fn output_row(o: &Output) -> [f64; 7] {
    [o.t, o.status as f64, o.f, o.r, o.c, o.kind as f64, if o.gps_epoch { 1.0 } else { 0.0 }]
}

/// One push result as JS sees it: `{ t, status, f, r, c, kind, gpsEpoch }`.
fn output_object(o: &Output) -> Result<JsValue, JsError> {
    Ok(Obj::new().n("t", o.t).n("status", o.status as f64).n("f", o.f).n("r", o.r).n("c", o.c).n("kind", o.kind as f64).b("gpsEpoch", o.gps_epoch).done())
}

/// The checked config as JS sees it: the fields of `Config` as they are
/// named in Rust (snake_case, as the API has always returned them), the
/// model left out.
fn config_object(c: &Config) -> JsValue {
    let n = &c.noise;
    let noise = Obj::new()
        .n("gps_pos_sigma", n.gps_pos_sigma)
        .n("gps_alt_sigma", n.gps_alt_sigma)
        .n("gps_vel_sigma", n.gps_vel_sigma)
        .n("baro_sigma", n.baro_sigma)
        .n("accel_noise", n.accel_noise)
        .n("cv_accel_noise", n.cv_accel_noise)
        .done();
    Obj::new()
        .s("method", c.method.name())
        .n("tc", c.tc as f64)
        .n("q", c.q as f64)
        .n("window", c.window as f64)
        .n("threshold", c.threshold)
        .b("retrain", c.retrain)
        .v("noise", &noise)
        .opt("outage_timeout", c.outage_timeout)
        .n("max_coast", c.max_coast)
        .n("data_gap", c.data_gap)
        .done()
}

#[wasm_bindgen(typescript_custom_section)]
const TS_DETECTOR: &'static str = r#"
/** One navlog row (contract §1). Every field but `t` is optional; units: s, deg, m, m/s, m/s^2, rad/s. */
export interface NavSample {
  t: number;
  lat?: number; lon?: number; alt?: number;
  pn?: number; pe?: number; pd?: number;
  vn?: number; ve?: number; vd?: number;
  fix?: number; sats?: number; eph?: number; epv?: number;
  ax?: number; ay?: number; az?: number;
  gx?: number; gy?: number; gz?: number;
  qw?: number; qx?: number; qy?: number; qz?: number;
  baro?: number;
  label?: number;
  /** The receiver's own time of the fix, s, on any epoch (GPS seconds, UTC seconds): the boot clock's rate is measured against it. */
  gps_time?: number;
  /** The receiver's speed accuracy claim, m/s (u-blox sAcc): the velocity test is scaled by its ratio to the receiver's usual claim. */
  sacc?: number;
}
/** Columnar batch: every array the same length, NaN = absent. */
export type NavColumns = { t: Float64Array } & Partial<Record<Exclude<keyof NavSample, "t">, Float64Array>>;
/** Detector configuration; every field optional, unknown fields throw. */
export interface DetectorConfig {
  method?: "anfis" | "chi2" | "nis" | "gate" | "mahalanobis" | "rms" | "knee" | "adaptive";
  /** Training condition: retrain after this many new fault epochs (default 100). */
  tc?: number;
  /** Database length q (default 500). */
  q?: number;
  /** Indicator window in GPS epochs (default 10). */
  window?: number;
  /** F-indicator threshold (default 0.5). */
  threshold?: number;
  retrain?: boolean;
  /** m */ gpsPosSigma?: number;
  /** m */ gpsAltSigma?: number;
  /** m/s */ gpsVelSigma?: number;
  /** m */ baroSigma?: number;
  /** m/s^2 */ accelNoise?: number;
  /** m/s^2 */ cvAccelNoise?: number;
  /** s; default 1.5 GPS periods */ outageTimeout?: number;
  /** s */ maxCoast?: number;
  /** s */ dataGap?: number;
  model?: NavguardModel;
}
export interface NavguardModel {
  anfis: { centre: number[][]; sigma: number[][]; conseq: number[][] };
  d1: [number, number][];
  d2: [number, number][];
  provenance?: string;
}
/** kind: 0 normal, 1 residual fault, 2 GPS outage, 3 no GPS yet, 4 GPS output frozen (the receiver repeats its last fix), 5 GPS degraded by the receiver's own word (2D fix, four satellites or fewer, or an accuracy claim 3x its usual), 6 vehicle upset (tilted past 90 deg, a crash or a flip: nothing judged until 5 s after it; status 0). */
export interface PushResult { t: number; status: 0 | 1; f: number; r: number; c: number; kind: 0 | 1 | 2 | 3 | 4 | 5 | 6; gpsEpoch: boolean }
export interface ColumnsResult { status: Uint8Array; f: Float64Array; r: Float64Array; c: Float64Array; kind: Uint8Array }
export interface DetectorStats { rows: number; gpsEpochs: number; imuRows: number; baroRows: number; retrains: number; filterResets: number; dataGaps: number; filterErrors: number }
export interface SnapshotInfo { version: number; crateVersion: string; bytes: number }
"#;

/// wasm-bindgen holds on `self` is always released and a rejected call
/// changes nothing.
#[wasm_bindgen]
pub struct Detector {
    inner: CoreDetector,
    /// Reused column buffers for `pushColumns` (one chunk, grown, never shrunk).
    cols: Vec<Vec<f64>>,
    /// Reused row buffer for `pushColumns` (one chunk).
    rows: Vec<Sample>,
    /// Reused input buffer for `pushRow` / `pushRowInto`.
    row: Vec<f64>,
    /// The package's `push` fast path: 28 inputs then 7 outputs, written and
    /// read by JS through a view on wasm memory (boxed: its address is fixed
    /// for the detector's life), so a row costs one call with no arguments.
    io: Box<[f64; IO_LEN]>,
}

/// `Detector::io`: the row's 28 columns, then `[t, status, f, r, c, kind, gpsEpoch]`.
const IO_LEN: usize = COLUMNS.len() + 7;

#[wasm_bindgen]
impl Detector {
    fn wrap(inner: CoreDetector) -> Detector {
        Detector { inner, cols: vec![Vec::new(); COLUMNS.len()], rows: Vec::new(), row: Vec::new(), io: Box::new([f64::NAN; IO_LEN]) }
    }

    /// `new Detector(config)`: every field optional; unknown fields throw.
    #[wasm_bindgen(constructor)]
    pub fn new(#[wasm_bindgen(unchecked_param_type = "DetectorConfig | undefined")] config: JsValue) -> Result<Detector, JsError> {
        let cfg = js_in::config_from(&config)?;
        Ok(Self::wrap(CoreDetector::new(cfg).map_err(err)?))
    }

    /// Push one sample (plain object keyed by CSV column names).
    /// Returns `{ t, status, f, r, c, kind, gpsEpoch }`.
    #[wasm_bindgen(unchecked_return_type = "PushResult")]
    pub fn push(&mut self, #[wasm_bindgen(unchecked_param_type = "NavSample")] sample: &JsValue) -> Result<JsValue, JsError> {
        let row = self.inner.stats().rows;
        if !sample.is_object() {
            return Err(err(format!("row {row}: sample must be a plain object")));
        }
        let mut s = Sample::default();
        KEYS.with(|keys| -> Result<(), JsError> {
            for (i, k) in keys.iter().enumerate() {
                let field = COLUMNS.get(i).copied().unwrap_or("?");
                // A getter that re-enters this detector finds it borrowed and
                // throws; that throw, like any other, is caught here.
                let v = js_in::get(sample, k, &format!("row {row}: field '{field}'")).map_err(err)?;
                if v.is_undefined() || v.is_null() {
                    continue;
                }
                let x = v.as_f64().ok_or_else(|| err(format!("row {row}: field '{field}': must be a number")))?;
                s.set(i, x);
            }
            Ok(())
        })?;
        let out = self.inner.push(&s).map_err(err)?;
        output_object(&out)
    }

    /// The 28 columns (contract §1, `gps_time` and `sacc`) of one row from `row` (Float64Array or array).
    fn read_row(&mut self, row: &JsValue, what: &str) -> Result<Sample, JsError> {
        js_in::f64s(row, COLUMNS.len(), what, &mut self.row).map_err(err)?;
        if self.row.len() != COLUMNS.len() {
            return Err(err(format!("{what}: expected {} values, got {}", COLUMNS.len(), self.row.len())));
        }
        Ok(row_from_values(&self.row))
    }

    /// Push one row given as the 28 columns in `COLUMNS` order
    /// (NaN = absent), a Float64Array or an array of numbers.
    #[wasm_bindgen(js_name = pushRow, unchecked_return_type = "PushResult")]
    pub fn push_row(&mut self, #[wasm_bindgen(unchecked_param_type = "Float64Array | number[]")] row: &JsValue) -> Result<JsValue, JsError> {
        let s = self.read_row(row, "pushRow: row")?;
        let out = self.inner.push(&s).map_err(err)?;
        output_object(&out)
    }

    /// Like `pushRow`, but writes `[t, status, f, r, c, kind, gpsEpoch]` into
    /// the Float64Array `out` (length ≥ 7) instead of returning an object, so
    /// the JS wrapper builds the result object itself: one boundary crossing
    /// per row. `out` is checked before the row is pushed, so a bad `out`
    /// consumes nothing.
    #[wasm_bindgen(js_name = pushRowInto)]
    pub fn push_row_into(
        &mut self,
        #[wasm_bindgen(unchecked_param_type = "Float64Array | number[]")] row: &JsValue,
        #[wasm_bindgen(unchecked_param_type = "Float64Array")] out: &JsValue,
    ) -> Result<(), JsError> {
        let n = js_in::f64_out_len(out, "pushRowInto: out").map_err(err)?;
        if n < 7 {
            return Err(err(format!("pushRowInto: out must have at least 7 elements, got {n} (a detached buffer has 0)")));
        }
        let s = self.read_row(row, "pushRowInto: row")?;
        let o = self.inner.push(&s).map_err(err)?;
        let vals = output_row(&o);
        // Cannot fail: `out` was checked above and no JS ran since.
        js_in::write_f64(out, 0, &vals, "pushRowInto: out").map_err(err)
    }

    /// Byte offset in wasm memory of this detector's row buffer (33 f64s),
    /// for the package's own `push` (see `pkg/index.js`); not an API.
    #[wasm_bindgen(js_name = __ioOffset)]
    pub fn io_offset(&self) -> f64 {
        self.io.as_ptr() as usize as f64
    }

    /// Push the row in the row buffer and write its outputs after it; not
    /// an API (the package's `push` is). Touches no JS value.
    #[wasm_bindgen(js_name = __pushIo)]
    pub fn push_io(&mut self) -> Result<(), JsError> {
        self.inner.push_values(&mut self.io[..]).map_err(err)
    }

    /// Rows accepted so far (the next row's index in error messages).
    #[wasm_bindgen(js_name = rowCount)]
    pub fn row_count(&self) -> f64 {
        self.inner.stats().rows as f64
    }

    /// Push a columnar batch: `{ t: Float64Array, lat: Float64Array, ... }`,
    /// NaN = absent. Validates the whole batch first, so a rejected batch
    /// changes nothing. Returns `{ status: Uint8Array, f, r, c: Float64Array,
    /// kind: Uint8Array }`, one entry per row. Processed in chunks of 4096
    /// rows, so wasm memory does not grow with the batch; at most
    /// 16 777 216 rows per call.
    #[wasm_bindgen(js_name = pushColumns, unchecked_return_type = "ColumnsResult")]
    pub fn push_columns(&mut self, #[wasm_bindgen(unchecked_param_type = "NavColumns")] columns: &JsValue) -> Result<JsValue, JsError> {
        let (src, n) = column_sources(columns)?;
        let base = self.inner.stats().rows;
        // Pass 1: assemble and validate every row (time order included)
        // before touching state, so a rejected batch changes nothing.
        let mut last_t = f64::NEG_INFINITY;
        let chunks: Vec<(usize, usize)> = (0..n).step_by(CHUNK_ROWS).map(|a| (a, (a + CHUNK_ROWS).min(n))).collect();
        for &(a, b) in &chunks {
            self.load_chunk(&src, a, b)?;
            if let Err((k, e)) = self.inner.validate_batch(&self.rows, base + a as u64, &mut last_t) {
                let j = a + k;
                return Err(match e {
                    Some(e) => err(format!("{e} (batch index {j})")),
                    None => {
                        let t = self.rows.get(k).map_or(f64::NAN, |s| s.t);
                        err(format!("row {}: field 't': time goes backwards: {} after {} (batch index {j})", base + j as u64, Shortest(t), Shortest(last_t)))
                    }
                });
            }
        }
        let (u8c, f64c) = (js_in::u8_ctor(), js_in::f64_ctor());
        let new = |c: &JsValue| js_in::new_typed(c, n, "pushColumns: result").map_err(err);
        let (status, f, r, c, kind) = (new(&u8c)?, new(&f64c)?, new(&f64c)?, new(&f64c)?, new(&u8c)?);
        // Pass 2: push. A single chunk is still loaded from pass 1.
        let mut o = OutputColumns::default();
        for &(a, b) in &chunks {
            if chunks.len() > 1 {
                self.load_chunk(&src, a, b)?;
            }
            o.clear();
            self.inner.push_valid_batch(&self.rows, &mut o);
            // Our own fresh arrays, sized n: these writes cannot fail.
            let w = "pushColumns: result";
            js_in::write_u8(&status, a, &o.status, w).map_err(err)?;
            js_in::write_u8(&kind, a, &o.kind, w).map_err(err)?;
            js_in::write_f64(&f, a, &o.f, w).map_err(err)?;
            js_in::write_f64(&r, a, &o.r, w).map_err(err)?;
            js_in::write_f64(&c, a, &o.c, w).map_err(err)?;
        }
        let obj = Object::new();
        set(&obj, "status", &status);
        set(&obj, "f", &f);
        set(&obj, "r", &r);
        set(&obj, "c", &c);
        set(&obj, "kind", &kind);
        Ok(obj.into())
    }

    /// Rows `a..b` of the batch into `self.rows` (absent columns read NaN).
    fn load_chunk(&mut self, src: &[Option<js_in::F64Source>], a: usize, b: usize) -> Result<(), JsError> {
        for (i, (s, buf)) in src.iter().zip(self.cols.iter_mut()).enumerate() {
            match s {
                Some(s) => s.read(a, b, buf, &format!("pushColumns: column '{}'", COLUMNS.get(i).copied().unwrap_or("?"))).map_err(err)?,
                // An empty column reads as NaN (absent) in `rows_from_columns`.
                None => buf.clear(),
            }
        }
        let c: [&[f64]; COLUMNS.len()] = core::array::from_fn(|i| self.cols.get(i).map_or(&[][..], |v| &v[..]));
        rows_from_columns(&c, b - a, &mut self.rows);
        Ok(())
    }

    /// Counters: rows, GPS epochs, retrains, resets, data gaps.
    #[wasm_bindgen(unchecked_return_type = "DetectorStats")]
    pub fn stats(&self) -> Result<JsValue, JsError> {
        Ok(stats_object(&self.inner.stats()))
    }

    /// The checked configuration in use.
    #[wasm_bindgen(unchecked_return_type = "object")]
    pub fn config(&self) -> Result<JsValue, JsError> {
        Ok(config_object(self.inner.config()))
    }

    /// The whole detector state (filter, windows, D1/D2, ANFIS, counters,
    /// config) as versioned bytes: store it (IndexedDB, a file) and resume
    /// with `Detector.restore`.
    pub fn snapshot(&self) -> Result<Uint8Array, JsError> {
        let bytes = self.inner.snapshot().map_err(err)?;
        Ok(Uint8Array::from(&bytes[..]))
    }

    /// A detector resumed from `snapshot()` bytes; its outputs continue
    /// bit-identical to the snapshotted one's. Throws on a damaged snapshot
    /// or one of another format version.
    pub fn restore(#[wasm_bindgen(unchecked_param_type = "Uint8Array")] snapshot: &JsValue) -> Result<Detector, JsError> {
        let bytes = js_in::bytes(snapshot, MAX_BYTES, "restore: snapshot").map_err(err)?;
        Ok(Self::wrap(CoreDetector::restore(&bytes).map_err(err)?))
    }
}

/// The batch's columns, checked before anything is read: each present one
/// a real, attached Float64Array, all of one length n ≤ `MAX_BATCH_ROWS`,
/// `t` present. Each column's getter runs once.
fn column_sources(columns: &JsValue) -> Result<(Vec<Option<js_in::F64Source>>, usize), JsError> {
    if !columns.is_object() {
        return Err(err("pushColumns: argument must be an object of Float64Arrays"));
    }
    let mut src = Vec::with_capacity(COLUMNS.len());
    let mut n: Option<usize> = None;
    KEYS.with(|keys| -> Result<(), JsError> {
        for (k, name) in keys.iter().zip(COLUMNS) {
            let what = format!("pushColumns: column '{name}'");
            let v = js_in::get(columns, k, &what).map_err(err)?;
            if v.is_undefined() || v.is_null() {
                src.push(None);
                continue;
            }
            let s = js_in::F64Source::new(&v, MAX_BATCH_ROWS, &what).map_err(err)?;
            let len = s.len();
            match n {
                None => n = Some(len),
                Some(m) if m != len => {
                    return Err(err(format!("pushColumns: column '{name}' has length {len}, expected {m} (all columns must have the same length)")))
                }
                _ => {}
            }
            src.push(Some(s));
        }
        Ok(())
    })?;
    if !matches!(src.first(), Some(Some(_))) {
        return Err(err("pushColumns: column 't' is required"));
    }
    Ok((src, n.unwrap_or(0)))
}

/// A snapshot's header: `{ version, crateVersion, bytes }` (checksum verified).
#[wasm_bindgen(js_name = snapshotInfo, unchecked_return_type = "SnapshotInfo")]
pub fn snapshot_info(#[wasm_bindgen(unchecked_param_type = "Uint8Array")] snapshot: &JsValue) -> Result<JsValue, JsError> {
    let bytes = js_in::bytes(snapshot, MAX_BYTES, "snapshotInfo: snapshot").map_err(err)?;
    let i = crate::snapshot::info(&bytes).map_err(err)?;
    Ok(Obj::new().n("version", i.version as f64).s("crateVersion", &i.crate_version).n("bytes", i.bytes as f64).done())
}

/// The wasm memory, for the package's `push` fast path; not an API.
#[wasm_bindgen(js_name = __memory, unchecked_return_type = "WebAssembly.Memory")]
pub fn memory() -> JsValue {
    wasm_bindgen::memory()
}

/// Bytes of wasm linear memory (for memory-flatness checks).
#[wasm_bindgen(js_name = wasmMemoryBytes)]
pub fn wasm_memory_bytes() -> f64 {
    (core::arch::wasm32::memory_size(0) * 65536) as f64
}

/// The contract's column names, in the order `pushRow` takes them.
#[wasm_bindgen(js_name = columnNames, unchecked_return_type = "string[]")]
pub fn column_names() -> Array {
    COLUMNS.iter().map(|c| JsValue::from_str(c)).collect()
}

/// Names of the built-in scenarios (in the core module: a page lists them
/// before it needs the lab module that simulates them).
#[wasm_bindgen(js_name = scenarioNames, unchecked_return_type = "string[]")]
pub fn scenario_names() -> Array {
    crate::sim::preset_names().into_iter().map(JsValue::from_str).collect()
}

/// Crate version.
#[wasm_bindgen]
pub fn version() -> String {
    env!("CARGO_PKG_VERSION").to_string()
}
