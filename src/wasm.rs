//! The wasm-bindgen facade: the contract's streaming API (§2) plus the audit,
//! simulator and trainer entry points the CLI and the page use. Everything
//! `#[wasm_bindgen]` lives here; the core never sees a JS type.
//!
//! Results are plain JS objects and typed arrays (no class handles to free
//! in loops). Errors are JS `Error`s naming the row and field; the detector
//! is untouched by a rejected row or batch.

use js_sys::{Array, Float64Array, Object, Reflect, Uint8Array};
use serde::de::DeserializeOwned;
use wasm_bindgen::prelude::*;

mod js_in;

use crate::audit;
use crate::config::{Config, ConfigInput};
use crate::detector::{Detector as CoreDetector, Model, Output};
use crate::logs;
use crate::metrics;
use crate::sample::{Sample, COLUMNS};
use crate::sim;

thread_local! {
    /// Column names as JS strings, made once: property lookups then cost no
    /// string conversion per sample.
    static KEYS: Vec<JsValue> = COLUMNS.iter().map(|c| JsValue::from_str(c)).collect();
}

fn err(msg: impl core::fmt::Display) -> JsError {
    JsError::new(&msg.to_string())
}

/// Largest `pushColumns` batch (rows per call). The batch is processed in
/// chunks of [`CHUNK_ROWS`], so wasm memory does not grow with it; the limit
/// bounds the result arrays (26 bytes a row, allocated in JS).
pub const MAX_BATCH_ROWS: usize = 1 << 24;
/// Rows per chunk of a `pushColumns` batch: 26 columns × 8 B × 4096 = 852 KB
/// of scratch, reused.
const CHUNK_ROWS: usize = 4096;
/// Largest byte input (a log, a snapshot, a CSV chunk) per call.
const MAX_BYTES: usize = 1 << 31;
/// Largest numeric array per call (`metrics`).
const MAX_VALUES: usize = 1 << 27;
/// Largest text argument (`TightDetector.pushCsv`), UTF-16 units.
const MAX_TEXT: usize = 1 << 26;
/// Largest name argument (scenario, log name).
const MAX_NAME: usize = 4096;

/// The checked config. Fields are read once each, by name, through
/// catching calls (see `js_in`): a throwing getter or Proxy trap is a
/// config error naming the field, and nothing is left half-done.
fn config_from(v: &JsValue) -> Result<Config, JsError> {
    if v.is_undefined() || v.is_null() {
        return Ok(Config::default());
    }
    if !v.is_object() || v.is_function() {
        return Err(err("config: must be a plain object"));
    }
    for name in js_in::own_keys(v, "config").map_err(err)? {
        ConfigInput::check_field_name(&name).map_err(err)?;
    }
    let mut map = serde_json::Map::new();
    for name in ConfigInput::FIELDS {
        let what = format!("config.{name}");
        let x = js_in::get(v, &JsValue::from_str(name), &what).map_err(err)?;
        if let Some(x) = js_in::plain(&x, &what).map_err(err)? {
            map.insert(name.to_string(), x);
        }
    }
    ConfigInput::from_value(serde_json::Value::Object(map)).map_err(err)
}

/// A user object as `T`, copied to plain data first (see `js_in::plain`).
fn plain_of<T: DeserializeOwned>(v: &JsValue, what: &str) -> Result<T, JsError> {
    let x = js_in::plain(v, what).map_err(err)?.unwrap_or(serde_json::Value::Null);
    serde_json::from_value(x).map_err(|e| err(format!("{what}: {e}")))
}

fn set(o: &Object, k: &str, v: &JsValue) {
    // Setting a property on a fresh plain object cannot fail.
    let _ = Reflect::set(o, &JsValue::from_str(k), v);
}

/// `[t, status, f, r, c, kind, gpsEpoch]` (what `pushRowInto` writes).
fn output_row(o: &Output) -> [f64; 7] {
    [o.t, o.status as f64, o.f, o.r, o.c, o.kind as f64, if o.gps_epoch { 1.0 } else { 0.0 }]
}

fn output_object(o: &Output) -> JsValue {
    let obj = Object::new();
    set(&obj, "t", &o.t.into());
    set(&obj, "status", &o.status.into());
    set(&obj, "f", &o.f.into());
    set(&obj, "r", &o.r.into());
    set(&obj, "c", &o.c.into());
    set(&obj, "kind", &o.kind.into());
    set(&obj, "gpsEpoch", &o.gps_epoch.into());
    obj.into()
}


#[wasm_bindgen(typescript_custom_section)]
const TS_TYPES: &'static str = r#"
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
/** kind: 0 normal, 1 residual fault, 2 GPS outage, 3 no GPS yet. */
export interface PushResult { t: number; status: 0 | 1; f: number; r: number; c: number; kind: 0 | 1 | 2 | 3; gpsEpoch: boolean }
export interface ColumnsResult { status: Uint8Array; f: Float64Array; r: Float64Array; c: Float64Array; kind: Uint8Array }
export interface DetectorStats { rows: number; gps_epochs: number; imu_rows: number; baro_rows: number; retrains: number; filter_resets: number; data_gaps: number; filter_errors: number }
export interface Metrics { tp: number; fp: number; tn: number; fn: number; accuracy: number; falseAlarmRate: number; misdetectionRate: number; precision: number; recall: number; f2: number; meanDetectionDelay: number; faultIntervals: number; detectedIntervals: number }
export interface FaultInterval { start: number; end: number; kind: "gps_outage" | "residual"; peakF: number; driver: "gps_position" | "gps_velocity" | "baro" | "imu" | "none"; indicator: "R" | "C" | "none"; rows: number }
export interface AuditReport {
  format: "csv" | "ulog" | "dataflash"; rows: number; durationS: number; gpsEpochs: number; gpsRateHz: number; imuRateHz: number;
  gpsAvailable: boolean; gpsFixFraction: number; flaggedGpsEpochFraction: number;
  faults: FaultInterval[]; dataGaps: { start: number; end: number }[]; missing: string[]; warnings: string[];
  meta: [string, string][]; metrics?: Metrics; stats: DetectorStats;
  /** Boot-clock s of the first row; show times as t - startT. startUtc: ISO 8601 UTC of the first row when the log has GPS time. */
  startT: number; startUtc?: string;
  /** What the receiver-quality column `eph` holds: metres, HDOP (unitless) or nothing. */
  ephSource: "eph" | "hdop" | "none";
  modes: { t: number; mode: string }[]; messages: { t: number; level: "error" | "warning" | "info" | "event"; text: string }[];
}
/** Residual columns: GPS position N/E/D (m), velocity N/E/D (m/s), baro (m); NaN on rows without that measurement. */
export interface AuditResult { report: AuditReport; columns: { t: Float64Array; status: Uint8Array; f: Float64Array; r: Float64Array; c: Float64Array; kind: Uint8Array; rPn: Float64Array; rPe: Float64Array; rPd: Float64Array; rVn: Float64Array; rVe: Float64Array; rVd: Float64Array; rBaro: Float64Array } }
/** One epoch for the tightly coupled detector: IMU (rad/s, m/s^2) and pseudo-ranges (m); `pr: []` on IMU-only rows. */
export interface TightRow { t: number; gyro: [number, number, number]; accel: [number, number, number]; pr: { prn: number; pr: number }[] }
/** Fields that do not apply to a row are absent (undefined), e.g. `faulty_prn` on a fault-free epoch or `gan_score_max` for strategies other than `gan`. */
export interface TightOutput {
  t: number; status: "initializing" | "no-gnss" | "ok" | "fault"; faulty_prn?: number; statistic?: number;
  lambda_max: number; rdpop?: number; action?: string; gan_score_max?: number; n_sats: number;
  position_ned: [number, number, number]; velocity_ned: [number, number, number]; clock_bias_m: number;
}
/** Options of `tightGanTrain` (all optional): fault-free training and calibration flights, GAN size. */
export interface GanTrainOptions { trainSeeds?: number[]; calibSeeds?: number[]; epochs?: number; hidden?: number; window?: number; alpha?: number }
export interface GanTrainProgress { epoch: number; epochs: number; dLoss: number; gLoss: number; dReal: number; dFake: number }
export interface GanTrainResult { model: Uint8Array; tau: number; m: number; lambda: number; t2: number; falseAlarm: number; trainWindows: number; calibWindows: number; parameters: number; table1: string }
export interface SnapshotInfo { version: number; crateVersion: string; bytes: number }
export interface LogColumns { format: string; rows: number; columns: Partial<Record<keyof NavSample, Float64Array>>; warnings: string[]; missing: string[]; meta: [string, string][]; topicCounts: [string, number][] }
"#;

/// The streaming detector (contract §2).
///
/// Every method reads and checks all its JS arguments first, through
/// catching calls only (`js_in`), and touches the detector's state only once
/// they are all good; no JS exception can unwind through it, so the borrow
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
    /// The package's `push` fast path: 26 inputs then 7 outputs, written and
    /// read by JS through a view on wasm memory (boxed: its address is fixed
    /// for the detector's life), so a row costs one call with no arguments.
    io: Box<[f64; IO_LEN]>,
}

/// `Detector::io`: the row's 26 columns, then `[t, status, f, r, c, kind, gpsEpoch]`.
const IO_LEN: usize = COLUMNS.len() + 7;

/// One chunk of `pushColumns` results, then copied into the JS arrays.
#[derive(Default)]
struct ChunkOut {
    status: Vec<u8>,
    kind: Vec<u8>,
    f: Vec<f64>,
    r: Vec<f64>,
    c: Vec<f64>,
}

#[wasm_bindgen]
impl Detector {
    fn wrap(inner: CoreDetector) -> Detector {
        Detector { inner, cols: vec![Vec::new(); COLUMNS.len()], rows: Vec::new(), row: Vec::new(), io: Box::new([f64::NAN; IO_LEN]) }
    }

    /// `new Detector(config)`: every field optional; unknown fields throw.
    #[wasm_bindgen(constructor)]
    pub fn new(#[wasm_bindgen(unchecked_param_type = "DetectorConfig | undefined")] config: JsValue) -> Result<Detector, JsError> {
        let cfg = config_from(&config)?;
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
        Ok(output_object(&out))
    }

    /// The 26 contract columns of one row from `row` (Float64Array or array).
    fn read_row(&mut self, row: &JsValue, what: &str) -> Result<Sample, JsError> {
        js_in::f64s(row, COLUMNS.len(), what, &mut self.row).map_err(err)?;
        if self.row.len() != COLUMNS.len() {
            return Err(err(format!("{what}: expected {} values, got {}", COLUMNS.len(), self.row.len())));
        }
        let mut s = Sample::default();
        for (i, v) in self.row.iter().enumerate() {
            s.set(i, *v);
        }
        Ok(s)
    }

    /// Push one row given as the contract's 26 columns in `COLUMNS` order
    /// (NaN = absent), a Float64Array or an array of numbers.
    #[wasm_bindgen(js_name = pushRow, unchecked_return_type = "PushResult")]
    pub fn push_row(&mut self, #[wasm_bindgen(unchecked_param_type = "Float64Array | number[]")] row: &JsValue) -> Result<JsValue, JsError> {
        let s = self.read_row(row, "pushRow: row")?;
        let out = self.inner.push(&s).map_err(err)?;
        Ok(output_object(&out))
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
        let mut s = Sample::default();
        for (i, v) in self.io.iter().take(COLUMNS.len()).enumerate() {
            s.set(i, *v);
        }
        let o = self.inner.push(&s).map_err(err)?;
        let vals = output_row(&o);
        for (d, v) in self.io.iter_mut().skip(COLUMNS.len()).zip(vals) {
            *d = v;
        }
        Ok(())
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
            for (k, s) in self.rows.iter().enumerate() {
                let j = a + k;
                self.inner.validate(s, base + j as u64).map_err(|e| err(format!("{e} (batch index {j})")))?;
                if s.t < last_t {
                    return Err(err(format!("row {}: field 't': time goes backwards: {} after {} (batch index {j})", base + j as u64, s.t, last_t)));
                }
                last_t = s.t;
            }
        }
        let (u8c, f64c) = (js_in::u8_ctor(), js_in::f64_ctor());
        let new = |c: &JsValue| js_in::new_typed(c, n, "pushColumns: result").map_err(err);
        let (status, f, r, c, kind) = (new(&u8c)?, new(&f64c)?, new(&f64c)?, new(&f64c)?, new(&u8c)?);
        // Pass 2: push. A single chunk is still loaded from pass 1.
        let mut o = ChunkOut::default();
        for &(a, b) in &chunks {
            if chunks.len() > 1 {
                self.load_chunk(&src, a, b)?;
            }
            o.status.clear();
            o.kind.clear();
            o.f.clear();
            o.r.clear();
            o.c.clear();
            for s in &self.rows {
                let out = self.inner.push_valid(s);
                o.status.push(out.status);
                o.kind.push(out.kind);
                o.f.push(out.f);
                o.r.push(out.r);
                o.c.push(out.c);
            }
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
                None => {
                    buf.clear();
                    buf.resize(b - a, f64::NAN);
                }
            }
        }
        let c: [&[f64]; COLUMNS.len()] = core::array::from_fn(|i| self.cols.get(i).map_or(&[][..], |v| &v[..]));
        self.rows.clear();
        self.rows.extend((0..b - a).map(|j| Sample::from_columns(&c, j)));
        Ok(())
    }

    /// Counters: rows, GPS epochs, retrains, resets, data gaps.
    #[wasm_bindgen(unchecked_return_type = "DetectorStats")]
    pub fn stats(&self) -> Result<JsValue, JsError> {
        serde_wasm_bindgen::to_value(&self.inner.stats()).map_err(err)
    }

    /// The checked configuration in use.
    #[wasm_bindgen(unchecked_return_type = "object")]
    pub fn config(&self) -> Result<JsValue, JsError> {
        serde_wasm_bindgen::to_value(self.inner.config()).map_err(err)
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
    serde_wasm_bindgen::to_value(&crate::snapshot::info(&bytes).map_err(err)?).map_err(err)
}

fn report_object(report: &audit::Report) -> Result<JsValue, JsError> {
    let ser = serde_wasm_bindgen::Serializer::new().serialize_maps_as_objects(true);
    serde::Serialize::serialize(report, &ser).map_err(err)
}

fn columns_object(cols: &audit::Columns) -> JsValue {
    let c = Object::new();
    set(&c, "t", &Float64Array::from(&cols.t[..]).into());
    set(&c, "status", &Uint8Array::from(&cols.status[..]).into());
    set(&c, "f", &Float64Array::from(&cols.f[..]).into());
    set(&c, "r", &Float64Array::from(&cols.r[..]).into());
    set(&c, "c", &Float64Array::from(&cols.c[..]).into());
    set(&c, "kind", &Uint8Array::from(&cols.kind[..]).into());
    for (name, v) in audit::RESID_NAMES.iter().zip(cols.resid.iter()) {
        set(&c, name, &Float64Array::from(&v[..]).into());
    }
    c.into()
}

fn audit_result(report: &audit::Report, cols: &audit::Columns) -> Result<JsValue, JsError> {
    let out = Object::new();
    set(&out, "report", &report_object(report)?);
    set(&out, "columns", &columns_object(cols));
    Ok(out.into())
}

/// Audit a whole log (navlog CSV, PX4 ULog or ArduPilot DataFlash, recognised
/// by content). Returns `{ report, columns: { t, status, f, r, c, kind, rPn..rBaro } }`.
/// Runs the streaming readers over the bytes: the parsed rows are never held,
/// only the per-row outputs returned.
#[wasm_bindgen(js_name = auditBytes, unchecked_return_type = "AuditResult")]
pub fn audit_bytes(#[wasm_bindgen(unchecked_param_type = "Uint8Array")] bytes: &JsValue, #[wasm_bindgen(unchecked_param_type = "DetectorConfig | undefined")] config: JsValue) -> Result<JsValue, JsError> {
    let cfg = config_from(&config)?;
    let bytes = js_in::bytes(bytes, MAX_BYTES, "auditBytes: bytes").map_err(err)?;
    let (report, cols) = audit::audit_bytes(&bytes, &cfg, true).map_err(err)?;
    audit_result(&report, &cols)
}

/// An audit run in slices, for progress bars: `new Auditor(bytes, config)`
/// parses the log; call `step(rows)` until it returns 1 (the fraction done),
/// then `finish()` for the same result as `auditBytes`.
#[wasm_bindgen]
pub struct Auditor {
    run: Option<audit::AuditRun<logs::LogData>>,
    rows: usize,
}

#[wasm_bindgen]
impl Auditor {
    #[wasm_bindgen(constructor)]
    pub fn new(#[wasm_bindgen(unchecked_param_type = "Uint8Array")] bytes: &JsValue, #[wasm_bindgen(unchecked_param_type = "DetectorConfig | undefined")] config: JsValue) -> Result<Auditor, JsError> {
        let cfg = config_from(&config)?;
        let bytes = js_in::bytes(bytes, MAX_BYTES, "Auditor: bytes").map_err(err)?;
        let log = logs::read_any(&bytes).map_err(err)?;
        let rows = log.samples.len();
        let run = audit::AuditRun::new(log, &cfg).map_err(err)?;
        Ok(Auditor { run: Some(run), rows })
    }

    /// Rows in the log.
    pub fn rows(&self) -> f64 {
        self.rows as f64
    }

    /// Process up to `rows` more rows; returns the fraction done.
    pub fn step(&mut self, #[wasm_bindgen(unchecked_param_type = "number")] rows: &JsValue) -> Result<f64, JsError> {
        let rows = if rows.is_undefined() { 1.0 } else { js_in::num(rows, "Auditor.step: rows").map_err(err)? };
        Ok(match self.run.as_mut() {
            Some(r) => {
                r.step(if rows.is_finite() && rows > 0.0 { rows as usize } else { 1 });
                r.progress()
            }
            None => 1.0,
        })
    }

    /// Finish (processing what is left) and return `{ report, columns }`.
    #[wasm_bindgen(unchecked_return_type = "AuditResult")]
    pub fn finish(&mut self) -> Result<JsValue, JsError> {
        let run = self.run.take().ok_or_else(|| err("Auditor.finish: already finished"))?;
        let (report, cols) = run.finish();
        audit_result(&report, &cols)
    }
}

/// A log (navlog CSV, ULog or DataFlash, recognised by content) audited as it
/// streams in, in bounded memory (for files too large to hold whole):
/// `feed(chunk)` the whole file, then `endPass()`; while it returns true (a
/// ULog file is read twice), feed the same bytes again from the start and
/// call it again; then `finish()` for the report (the same as `auditBytes`
/// gives on the whole file). With `keepOutputs`, `outputs()` holds the
/// per-row outputs of the latest chunk.
#[wasm_bindgen]
pub struct StreamAuditor {
    run: Option<audit::StreamAudit>,
}

#[wasm_bindgen]
impl StreamAuditor {
    #[wasm_bindgen(constructor)]
    pub fn new(
        #[wasm_bindgen(unchecked_param_type = "DetectorConfig | undefined")] config: JsValue,
        #[wasm_bindgen(js_name = keepOutputs, unchecked_param_type = "boolean | undefined")] keep_outputs: JsValue,
    ) -> Result<StreamAuditor, JsError> {
        let cfg = config_from(&config)?;
        Ok(StreamAuditor { run: Some(audit::StreamAudit::new(&cfg, js_in::flag(&keep_outputs, "StreamAuditor: keepOutputs").map_err(err)?).map_err(err)?) })
    }

    /// Feed the next chunk (any split); returns the rows it completed.
    pub fn feed(&mut self, #[wasm_bindgen(unchecked_param_type = "Uint8Array")] chunk: &JsValue) -> Result<f64, JsError> {
        let chunk = js_in::bytes(chunk, MAX_BYTES, "StreamAuditor.feed: chunk").map_err(err)?;
        let run = self.run.as_mut().ok_or_else(|| err("StreamAuditor.feed: already finished"))?;
        Ok(run.feed(&chunk).map_err(err)? as f64)
    }

    /// End of one pass over the file: true when the same bytes must be fed
    /// again from the start (the second pass over a ULog file).
    #[wasm_bindgen(js_name = endPass)]
    pub fn end_pass(&mut self) -> Result<bool, JsError> {
        let run = self.run.as_mut().ok_or_else(|| err("StreamAuditor.endPass: already finished"))?;
        run.end_pass().map_err(err)
    }

    /// "csv", "ulog" or "dataflash" once the first bytes are in, else undefined.
    pub fn format(&self) -> Option<String> {
        self.run.as_ref().and_then(|r| r.format()).map(str::to_string)
    }

    /// Per-row outputs `{ t, status, f, r, c, kind, rPn..rBaro }` of the latest chunk.
    #[wasm_bindgen(unchecked_return_type = "AuditResult['columns']")]
    pub fn outputs(&self) -> JsValue {
        self.run.as_ref().map_or(JsValue::UNDEFINED, |r| columns_object(r.outputs()))
    }

    /// Rows audited so far.
    pub fn rows(&self) -> f64 {
        self.run.as_ref().map_or(0.0, |r| r.rows() as f64)
    }

    /// Bytes fed so far.
    pub fn bytes(&self) -> f64 {
        self.run.as_ref().map_or(0.0, |r| r.bytes() as f64)
    }

    /// End of input: `{ report, columns }`, the columns holding the outputs
    /// of the rows completed at the end (a last unterminated CSV line, the
    /// rows a binary reader still held in its reorder buffer).
    #[wasm_bindgen(unchecked_return_type = "AuditResult")]
    pub fn finish(&mut self) -> Result<JsValue, JsError> {
        let run = self.run.take().ok_or_else(|| err("StreamAuditor.finish: already finished"))?;
        let (report, cols) = run.finish().map_err(err)?;
        audit_result(&report, &cols)
    }
}

fn js_clock() -> f64 {
    js_sys::Date::now() / 1000.0
}

/// Every `config.method` over a seeded battery of simulated flights (and any
/// real logs added), in steps for a progress bar: `new CompareRun({ seeds,
/// methods })`, `addLog(name, bytes)`, `step()` until it returns 1, then
/// `finish()` → `{ comparison, markdown }`.
#[wasm_bindgen]
pub struct CompareRun {
    run: Option<crate::compare::CompareRun>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct CompareOptions {
    /// Number of seeds (1..=n), default 5.
    seeds: Option<f64>,
    methods: Option<Vec<String>>,
}

#[wasm_bindgen]
impl CompareRun {
    #[wasm_bindgen(constructor)]
    pub fn new(#[wasm_bindgen(unchecked_param_type = "{ seeds?: number; methods?: string[] } | undefined")] options: JsValue) -> Result<CompareRun, JsError> {
        let o: CompareOptions = if options.is_undefined() || options.is_null() {
            CompareOptions { seeds: None, methods: None }
        } else {
            plain_of(&options, "compare options")?
        };
        let n = o.seeds.unwrap_or(5.0);
        if !(n.is_finite() && n.fract() == 0.0 && (1.0..=100.0).contains(&n)) {
            return Err(err(format!("compare options.seeds: must be an integer in 1..=100, got {n}")));
        }
        let seeds: Vec<u64> = (1..=n as u64).collect();
        let methods = o
            .methods
            .unwrap_or_default()
            .iter()
            .map(|m| crate::methods::Method::parse(m).map_err(|e| e.to_string().replace("config.method", "compare options.methods")))
            .collect::<Result<Vec<_>, _>>()
            .map_err(err)?;
        Ok(CompareRun { run: Some(crate::compare::CompareRun::new(&seeds, &methods, Some(js_clock)).map_err(err)?) })
    }

    /// Add a real log (any supported format) under `name`.
    #[wasm_bindgen(js_name = addLog)]
    pub fn add_log(&mut self, #[wasm_bindgen(unchecked_param_type = "string")] name: &JsValue, #[wasm_bindgen(unchecked_param_type = "Uint8Array")] bytes: &JsValue) -> Result<(), JsError> {
        let name = js_in::string(name, MAX_NAME, "CompareRun.addLog: name").map_err(err)?;
        let bytes = js_in::bytes(bytes, MAX_BYTES, "CompareRun.addLog: bytes").map_err(err)?;
        let log = logs::read_any(&bytes).map_err(|e| err(format!("{name}: {e}")))?;
        self.run.as_mut().ok_or_else(|| err("CompareRun: already finished"))?.add_log(&name, log);
        Ok(())
    }

    /// Run one (flight, method) pair; returns the fraction done.
    pub fn step(&mut self) -> Result<f64, JsError> {
        self.run.as_mut().ok_or_else(|| err("CompareRun: already finished"))?.step().map_err(err)
    }

    /// `{ comparison, markdown }` (runs what is left first).
    #[wasm_bindgen(unchecked_return_type = "{ comparison: object; markdown: string }")]
    pub fn finish(&mut self) -> Result<JsValue, JsError> {
        let run = self.run.take().ok_or_else(|| err("CompareRun: already finished"))?;
        let c = run.finish().map_err(err)?;
        let out = Object::new();
        let ser = serde_wasm_bindgen::Serializer::new().serialize_maps_as_objects(true);
        set(&out, "comparison", &serde::Serialize::serialize(&c, &ser).map_err(err)?);
        set(&out, "markdown", &crate::compare::markdown(&c).into());
        Ok(out.into())
    }
}

/// The tightly coupled GNSS/INS detector of Shen et al. 2022 (see
/// `docs/tight.md`): one row per epoch `{ t, gyro: [x,y,z], accel: [x,y,z],
/// pr: [{ prn, pr }] }` (IMU-only rows have `pr: []`); each output names the
/// faulty satellite, if any.
#[wasm_bindgen(js_name = TightDetector)]
pub struct TightDetectorJs {
    inner: crate::tight::stream::TightDetector,
}

#[wasm_bindgen(js_class = TightDetector)]
impl TightDetectorJs {
    /// `new TightDetector(config)`: every field optional (see `docs/tight.md`).
    #[wasm_bindgen(constructor)]
    pub fn new(#[wasm_bindgen(unchecked_param_type = "object | undefined")] config: JsValue) -> Result<TightDetectorJs, JsError> {
        let cfg: crate::tight::stream::TightConfig = if config.is_undefined() || config.is_null() {
            Default::default()
        } else {
            plain_of(&config, "tight config")?
        };
        Ok(TightDetectorJs { inner: crate::tight::stream::TightDetector::new(cfg).map_err(err)? })
    }

    /// One epoch row; returns `{ t, status, faulty_prn, statistic, lambda_max, rdpop, action, n_sats, position_ned, ... }`.
    #[wasm_bindgen(unchecked_return_type = "TightOutput")]
    pub fn push(&mut self, #[wasm_bindgen(unchecked_param_type = "TightRow")] row: JsValue) -> Result<JsValue, JsError> {
        let row: crate::tight::stream::EpochRow = plain_of(&row, "tight row")?;
        let out = self.inner.push(&row).map_err(err)?;
        serde_wasm_bindgen::to_value(&out).map_err(err)
    }

    /// GAN-FDSR with a model from `tightGanTrain` (its `model` bytes) instead
    /// of the embedded one; `config` as for the constructor.
    #[wasm_bindgen(js_name = withGanModel)]
    pub fn with_gan_model(#[wasm_bindgen(unchecked_param_type = "object | undefined")] config: JsValue, #[wasm_bindgen(unchecked_param_type = "Uint8Array")] model: &JsValue) -> Result<TightDetectorJs, JsError> {
        let model = js_in::bytes(model, MAX_BYTES, "withGanModel: model").map_err(err)?;
        let cfg: crate::tight::stream::TightConfig = if config.is_undefined() || config.is_null() {
            Default::default()
        } else {
            plain_of(&config, "tight config")?
        };
        let model = crate::tight::gan_fdsr::GanDetectorModel::from_bytes(&model).map_err(err)?;
        Ok(TightDetectorJs { inner: crate::tight::stream::TightDetector::with_gan(cfg, model).map_err(err)? })
    }

    /// Every row of a pseudo-range CSV (`pr_<prn>` or `sat_id` layout); an array of outputs.
    #[wasm_bindgen(js_name = pushCsv, unchecked_return_type = "TightOutput[]")]
    pub fn push_csv(&mut self, #[wasm_bindgen(unchecked_param_type = "string")] text: &JsValue) -> Result<JsValue, JsError> {
        let text = js_in::string(text, MAX_TEXT, "pushCsv: text").map_err(err)?;
        let rows = crate::tight::stream::parse_csv(&text).map_err(err)?;
        let out = self.inner.run(&rows).map_err(err)?;
        serde_wasm_bindgen::to_value(&out).map_err(err)
    }
}

/// A simulated tightly coupled flight: environment `env` (1–5, the paper's
/// Table 3 plus Env 5), fault type 1–5 (Table 4; 0 = none), seed. Returns
/// `{ csv, config, faultyPrn, faultStart, faultEnd }`: feed `csv` to a
/// `new TightDetector(config)`.
#[wasm_bindgen(js_name = tightSimulate, unchecked_return_type = "{ csv: string; config: object; faultyPrn: number; faultStart: number; faultEnd: number }")]
pub fn tight_simulate(
    #[wasm_bindgen(unchecked_param_type = "number")] env: &JsValue,
    #[wasm_bindgen(unchecked_param_type = "number", js_name = faultType)] fault_type: &JsValue,
    #[wasm_bindgen(unchecked_param_type = "number")] seed: &JsValue,
) -> Result<JsValue, JsError> {
    let small = |v: &JsValue, what: &str| -> Result<u32, JsError> {
        let x = js_in::num(v, what).map_err(err)?;
        Ok(if x.fract() == 0.0 && (0.0..=1e6).contains(&x) { x as u32 } else { u32::MAX })
    };
    let (env, fault_type) = (small(env, "tightSimulate: env")?, small(fault_type, "tightSimulate: faultType")?);
    let seed = js_in::num(seed, "tightSimulate: seed").map_err(err)?;
    use crate::tight::fdi::{FdsrConfig, Strategy};
    use crate::tight::scenario::{environments, run_with_rows, FaultSpec, FaultType, RunSpec, SimConfig, World};
    let cfg = SimConfig::default();
    let world = World::new(&cfg).map_err(err)?;
    let envs = environments(&world, &cfg).map_err(err)?;
    let e = envs.get((env as usize).wrapping_sub(1)).ok_or_else(|| err(format!("tightSimulate: env must be 1..={}, got {env}", envs.len())))?;
    let kind = match fault_type {
        0 => None,
        1 => Some(FaultType::Step20),
        2 => Some(FaultType::Step10),
        3 => Some(FaultType::Ramp1),
        4 => Some(FaultType::Ramp05),
        5 => Some(FaultType::Ramp03),
        k => return Err(err(format!("tightSimulate: fault type must be 0..=5, got {k}"))),
    };
    if !(seed.is_finite() && seed >= 0.0) {
        return Err(err(format!("tightSimulate: seed must be a non-negative number, got {seed}")));
    }
    let fault = kind.map(|kind| FaultSpec { prn: e.faulty_prn, kind, start: e.fault_start, end: e.fault_end });
    let spec = RunSpec {
        world: &world,
        cfg: &cfg,
        prns: &e.prns,
        watch_prn: e.faulty_prn,
        fault,
        fdsr: FdsrConfig { strategy: Strategy::Fdi, alpha: 0.001, eta: 0.035 },
        seed: seed as u64,
        gan: None,
    };
    let (_, rows, init) = run_with_rows(&spec).map_err(err)?;
    let tc = crate::tight::stream::TightConfig { t0: world.t0, strategy: Strategy::Fdi, initial: Some(init), ..Default::default() };
    let out = Object::new();
    set(&out, "csv", &crate::tight::stream::to_csv(&rows).into());
    set(&out, "config", &serde_wasm_bindgen::to_value(&tc).map_err(err)?);
    set(&out, "faultyPrn", &JsValue::from(e.faulty_prn));
    set(&out, "faultStart", &JsValue::from(e.fault_start));
    set(&out, "faultEnd", &JsValue::from(e.fault_end));
    Ok(out.into())
}

/// Train a GAN-FDSR model in the page (small models: a few flights and
/// epochs), as `navguard-gan train` does natively. `onProgress` is called
/// after every epoch with `{ epoch, epochs, dLoss, gLoss, dReal, dFake }`;
/// returning `false` cancels. The `model` bytes go to
/// `TightDetector.withGanModel`.
#[wasm_bindgen(js_name = tightGanTrain, unchecked_return_type = "GanTrainResult")]
pub fn tight_gan_train(
    #[wasm_bindgen(unchecked_param_type = "GanTrainOptions | undefined")] options: JsValue,
    #[wasm_bindgen(unchecked_param_type = "((p: GanTrainProgress) => boolean | void) | undefined")] on_progress: JsValue,
) -> Result<JsValue, JsError> {
    use crate::tight::gan_fdsr_train::{train_detector, GanTrainOptions};
    use crate::tight::scenario::{environments, SimConfig, World};
    let mut opts = GanTrainOptions::default();
    // Small by default: the page trains in seconds, not minutes.
    opts.train_seeds = vec![101, 102];
    opts.calib_seeds = vec![201, 202];
    opts.gan.epochs = 5;
    if !(options.is_undefined() || options.is_null()) {
        let o: serde_json::Map<String, serde_json::Value> = plain_of(&options, "tightGanTrain options")?;
        const KNOWN: [&str; 6] = ["trainSeeds", "calibSeeds", "epochs", "hidden", "window", "alpha"];
        if let Some(k) = o.keys().find(|k| !KNOWN.contains(&k.as_str())) {
            return Err(err(format!("tightGanTrain options.{k}: unknown field (known: {})", KNOWN.join(", "))));
        }
        let seeds = |k: &str| -> Result<Option<Vec<u64>>, JsError> {
            let Some(v) = o.get(k) else { return Ok(None) };
            let arr: Vec<f64> = serde_json::from_value(v.clone()).map_err(|e| err(format!("tightGanTrain: {k}: {e}")))?;
            if arr.is_empty() || arr.iter().any(|x| !(x.is_finite() && *x >= 0.0 && x.fract() == 0.0)) {
                return Err(err(format!("tightGanTrain: {k} must be a non-empty array of non-negative integers, got {arr:?}")));
            }
            Ok(Some(arr.into_iter().map(|x| x as u64).collect()))
        };
        if let Some(s) = seeds("trainSeeds")? {
            opts.train_seeds = s;
        }
        if let Some(s) = seeds("calibSeeds")? {
            opts.calib_seeds = s;
        }
        for (k, slot, lo, hi) in [("epochs", &mut opts.gan.epochs, 1usize, 1000usize), ("hidden", &mut opts.gan.hidden, 1, 128), ("window", &mut opts.gan.window, 2, 200)] {
            let Some(v) = o.get(k) else { continue };
            match v.as_f64() {
                Some(x) if x.fract() == 0.0 && x >= lo as f64 && x <= hi as f64 => *slot = x as usize,
                _ => return Err(err(format!("tightGanTrain: {k} must be an integer in {lo}..={hi}, got {v}"))),
            }
        }
        if let Some(a) = o.get("alpha") {
            opts.alpha = a.as_f64().filter(|x| *x > 0.0 && *x < 1.0).ok_or_else(|| err(format!("tightGanTrain: alpha must be in (0, 1), got {a}")))?;
        }
    }
    let cb = on_progress.dyn_ref::<js_sys::Function>().cloned();
    let sim = SimConfig::default();
    let world = World::new(&sim).map_err(err)?;
    let envs = environments(&world, &sim).map_err(err)?;
    let prns = envs.first().ok_or_else(|| err("tightGanTrain: no environment"))?.prns.clone();
    let (model, report) = train_detector(&world, &sim, &prns, &opts, &mut |p| {
        let Some(f) = cb.as_ref() else { return true };
        let o = Object::new();
        set(&o, "epoch", &JsValue::from(p.epoch as f64));
        set(&o, "epochs", &JsValue::from(p.epochs as f64));
        set(&o, "dLoss", &JsValue::from(p.d_loss));
        set(&o, "gLoss", &JsValue::from(p.g_loss));
        set(&o, "dReal", &JsValue::from(p.d_real));
        set(&o, "dFake", &JsValue::from(p.d_fake));
        // A throwing or `false`-returning callback cancels training.
        match f.call1(&JsValue::NULL, &o) {
            Ok(v) => v.as_bool() != Some(false),
            Err(_) => false,
        }
    })
    .map_err(err)?;
    let bytes = model.to_bytes().map_err(err)?;
    let out = Object::new();
    set(&out, "model", &js_sys::Uint8Array::from(bytes.as_slice()).into());
    set(&out, "tau", &JsValue::from(report.tau as f64));
    set(&out, "m", &JsValue::from(report.m as f64));
    set(&out, "lambda", &JsValue::from(model.gan.lambda()));
    set(&out, "t2", &JsValue::from(model.gan.t2()));
    set(&out, "falseAlarm", &JsValue::from(report.threshold.false_alarm));
    set(&out, "trainWindows", &JsValue::from(report.train_windows as f64));
    set(&out, "calibWindows", &JsValue::from(report.calib_windows as f64));
    set(&out, "parameters", &JsValue::from(model.gan.param_count() as f64));
    set(&out, "table1", &crate::tight::chaos::table1_markdown(&report.chaos).into());
    Ok(out.into())
}

/// Parse a log into columns (for plotting): `{ format, columns: {name: Float64Array}, warnings, missing, meta }`.
#[wasm_bindgen(js_name = readLog, unchecked_return_type = "LogColumns")]
pub fn read_log(#[wasm_bindgen(unchecked_param_type = "Uint8Array")] bytes: &JsValue) -> Result<JsValue, JsError> {
    let bytes = js_in::bytes(bytes, MAX_BYTES, "readLog: bytes").map_err(err)?;
    let log = logs::read_any(&bytes).map_err(err)?;
    let cols = Object::new();
    let mut buf = vec![0.0; log.samples.len()];
    for (i, name) in COLUMNS.iter().enumerate() {
        if !log.samples.iter().any(|s| !s.get(i).is_nan()) {
            continue;
        }
        for (j, s) in log.samples.iter().enumerate() {
            buf[j] = s.get(i);
        }
        set(&cols, name, &Float64Array::from(&buf[..]).into());
    }
    let out = Object::new();
    set(&out, "format", &JsValue::from_str(log.format));
    set(&out, "rows", &(log.samples.len() as f64).into());
    set(&out, "columns", &cols.into());
    let ser = serde_wasm_bindgen::Serializer::new().serialize_maps_as_objects(true);
    set(&out, "warnings", &serde::Serialize::serialize(&log.warnings, &ser).map_err(err)?);
    set(&out, "missing", &serde::Serialize::serialize(&log.missing, &ser).map_err(err)?);
    set(&out, "meta", &serde::Serialize::serialize(&log.meta, &ser).map_err(err)?);
    set(&out, "topicCounts", &serde::Serialize::serialize(&log.topic_counts, &ser).map_err(err)?);
    Ok(out.into())
}

/// Simulate a built-in scenario by name (see `scenarioNames()`) into navlog CSV text.
#[wasm_bindgen]
pub fn simulate(#[wasm_bindgen(unchecked_param_type = "string")] name: &JsValue, #[wasm_bindgen(unchecked_param_type = "number")] seed: &JsValue) -> Result<String, JsError> {
    let seed = js_in::num(seed, "simulate: seed").map_err(err)?;
    let name = js_in::string(name, MAX_NAME, "simulate: name").map_err(err)?;
    if !(seed.is_finite() && seed >= 0.0 && seed.fract() == 0.0 && seed < 9.0e15) {
        return Err(err(format!("seed: must be a non-negative integer, got {seed}")));
    }
    let sc = sim::Scenario::preset(&name, seed as u64).map_err(err)?;
    let rows = sim::simulate(&sc).map_err(err)?;
    Ok(sim::to_csv(&sc, &rows))
}

/// Simulate a scenario given as an object (same fields as the `# scenario:` CSV comment).
#[wasm_bindgen(js_name = simulateScenario)]
pub fn simulate_scenario(#[wasm_bindgen(unchecked_param_type = "object")] scenario: JsValue) -> Result<String, JsError> {
    let sc: sim::Scenario = plain_of(&scenario, "scenario")?;
    let rows = sim::simulate(&sc).map_err(err)?;
    Ok(sim::to_csv(&sc, &rows))
}

/// Names of the built-in scenarios.
#[wasm_bindgen(js_name = scenarioNames, unchecked_return_type = "string[]")]
pub fn scenario_names() -> Array {
    sim::preset_names().into_iter().map(JsValue::from_str).collect()
}

/// Metrics over labelled rows (contract definitions).
#[wasm_bindgen(unchecked_return_type = "Metrics")]
pub fn metrics(
    #[wasm_bindgen(unchecked_param_type = "Float64Array | number[]")] t: &JsValue,
    #[wasm_bindgen(unchecked_param_type = "Float64Array | number[]")] label: &JsValue,
    #[wasm_bindgen(unchecked_param_type = "Uint8Array | number[]")] status: &JsValue,
) -> Result<JsValue, JsError> {
    let (mut tv, mut lv) = (Vec::new(), Vec::new());
    js_in::f64s(t, MAX_VALUES, "metrics: t", &mut tv).map_err(err)?;
    js_in::f64s(label, MAX_VALUES, "metrics: label", &mut lv).map_err(err)?;
    let sv = js_in::bytes(status, MAX_VALUES, "metrics: status").map_err(err)?;
    let (t, label, status) = (&tv[..], &lv[..], &sv[..]);
    if t.len() != label.len() || t.len() != status.len() {
        return Err(err(format!("metrics: lengths differ: t {}, label {}, status {}", t.len(), label.len(), status.len())));
    }
    serde_wasm_bindgen::to_value(&metrics::compute(t, label, status)).map_err(err)
}

/// Train a model from labelled navlog CSV files (an array of `Uint8Array`).
/// Pass the result as `config.model`.
#[wasm_bindgen(js_name = trainFromCsv, unchecked_return_type = "NavguardModel")]
pub fn train_from_csv(#[wasm_bindgen(unchecked_param_type = "Uint8Array[]")] files: JsValue, #[wasm_bindgen(unchecked_param_type = "DetectorConfig | undefined")] config: JsValue) -> Result<JsValue, JsError> {
    let cfg = config_from(&config)?;
    let mut streams = vec![];
    for (i, f) in js_in::items(&files, 10_000, "trainFromCsv: files").map_err(err)?.iter().enumerate() {
        let bytes = js_in::bytes(f, MAX_BYTES, &format!("trainFromCsv: file {i}")).map_err(err)?;
        let log = logs::csv::read_csv(&bytes).map_err(|e| err(format!("trainFromCsv: file {i}: {e}")))?;
        streams.push(log.samples);
    }
    let refs: Vec<&[Sample]> = streams.iter().map(|s| s.as_slice()).collect();
    let model = crate::calibrate::train_model(&refs, &cfg, 42).map_err(err)?;
    serde_wasm_bindgen::to_value(&model).map_err(err)
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

/// Crate version.
#[wasm_bindgen]
pub fn version() -> String {
    env!("CARGO_PKG_VERSION").to_string()
}
