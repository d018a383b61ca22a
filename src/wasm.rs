//! The wasm-bindgen facade: the contract's streaming API (§2) plus the audit,
//! simulator and trainer entry points the CLI and the page use. Everything
//! `#[wasm_bindgen]` lives here; the core never sees a JS type.
//!
//! Results are plain JS objects and typed arrays (no class handles to free
//! in loops). Errors are JS `Error`s naming the row and field; the detector
//! is untouched by a rejected row or batch.

use js_sys::{Array, Float64Array, Object, Reflect, Uint8Array};
use wasm_bindgen::prelude::*;

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

fn config_from(v: &JsValue) -> Result<Config, JsError> {
    if v.is_undefined() || v.is_null() {
        return Ok(Config::default());
    }
    if !v.is_object() {
        return Err(err("config: must be a plain object"));
    }
    for k in Object::keys(v.unchecked_ref::<Object>()).iter() {
        let name = k.as_string().unwrap_or_default();
        ConfigInput::check_field_name(&name).map_err(err)?;
        // Field by field, so a type error names its field.
        let one = Object::new();
        set(&one, &name, &Reflect::get(v, &k).unwrap_or(JsValue::UNDEFINED));
        serde_wasm_bindgen::from_value::<ConfigInput>(one.into()).map_err(|e| err(format!("config.{name}: {e}")))?;
    }
    let input: ConfigInput = serde_wasm_bindgen::from_value(v.clone()).map_err(|e| err(format!("config: {e}")))?;
    input.check().map_err(err)
}

fn set(o: &Object, k: &str, v: &JsValue) {
    // Setting a property on a fresh plain object cannot fail.
    let _ = Reflect::set(o, &JsValue::from_str(k), v);
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
#[wasm_bindgen]
pub struct Detector {
    inner: CoreDetector,
    /// Reused column buffers for `pushColumns` (grown, never shrunk).
    cols: Vec<Vec<f64>>,
    /// Reused row buffer for `pushColumns`.
    rows: Vec<Sample>,
}

#[wasm_bindgen]
impl Detector {
    /// `new Detector(config)`: every field optional; unknown fields throw.
    #[wasm_bindgen(constructor)]
    pub fn new(#[wasm_bindgen(unchecked_param_type = "DetectorConfig | undefined")] config: JsValue) -> Result<Detector, JsError> {
        let cfg = config_from(&config)?;
        let inner = CoreDetector::new(cfg).map_err(err)?;
        Ok(Detector { inner, cols: vec![Vec::new(); COLUMNS.len()], rows: Vec::new() })
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
        let mut bad: Option<&'static str> = None;
        KEYS.with(|keys| {
            for (i, k) in keys.iter().enumerate() {
                let v = Reflect::get(sample, k).unwrap_or(JsValue::UNDEFINED);
                if v.is_undefined() || v.is_null() {
                    continue;
                }
                match v.as_f64() {
                    Some(x) => s.set(i, x),
                    None => {
                        bad = Some(COLUMNS[i]);
                        break;
                    }
                }
            }
        });
        if let Some(field) = bad {
            return Err(err(format!("row {row}: field '{field}': must be a number")));
        }
        let out = self.inner.push(&s).map_err(err)?;
        Ok(output_object(&out))
    }

    /// Push one row given as the contract's 26 columns in `COLUMNS` order
    /// (NaN = absent). The package's JS `push` packs objects into a reused
    /// Float64Array and calls this: JS property reads are far cheaper than
    /// 26 `Reflect.get` calls from wasm.
    #[wasm_bindgen(js_name = pushRow, unchecked_return_type = "PushResult")]
    pub fn push_row(&mut self, row: &[f64]) -> Result<JsValue, JsError> {
        if row.len() != COLUMNS.len() {
            return Err(err(format!("pushRow: expected {} values, got {}", COLUMNS.len(), row.len())));
        }
        let mut s = Sample::default();
        for (i, v) in row.iter().enumerate() {
            s.set(i, *v);
        }
        let out = self.inner.push(&s).map_err(err)?;
        Ok(output_object(&out))
    }

    /// Like `pushRow`, but writes `[t, status, f, r, c, kind, gpsEpoch]` into
    /// `out` (length ≥ 7) instead of returning an object, so the JS wrapper
    /// builds the result object itself: one boundary crossing per row.
    #[wasm_bindgen(js_name = pushRowInto)]
    pub fn push_row_into(&mut self, row: &[f64], out: &mut [f64]) -> Result<(), JsError> {
        if row.len() != COLUMNS.len() || out.len() < 7 {
            return Err(err(format!("pushRowInto: expected {} values and an output of 7, got {} and {}", COLUMNS.len(), row.len(), out.len())));
        }
        let mut s = Sample::default();
        for (i, v) in row.iter().enumerate() {
            s.set(i, *v);
        }
        let o = self.inner.push(&s).map_err(err)?;
        out[..7].copy_from_slice(&[o.t, o.status as f64, o.f, o.r, o.c, o.kind as f64, if o.gps_epoch { 1.0 } else { 0.0 }]);
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
    /// kind: Uint8Array }`, one entry per row.
    #[wasm_bindgen(js_name = pushColumns, unchecked_return_type = "ColumnsResult")]
    pub fn push_columns(&mut self, #[wasm_bindgen(unchecked_param_type = "NavColumns")] columns: &JsValue) -> Result<JsValue, JsError> {
        if !columns.is_object() {
            return Err(err("pushColumns: argument must be an object of Float64Arrays"));
        }
        let mut present = [false; COLUMNS.len()];
        let mut n: Option<usize> = None;
        let res: Result<(), JsError> = KEYS.with(|keys| {
            for (i, k) in keys.iter().enumerate() {
                let v = Reflect::get(columns, k).unwrap_or(JsValue::UNDEFINED);
                if v.is_undefined() || v.is_null() {
                    continue;
                }
                let arr: Float64Array = match v.dyn_into::<Float64Array>() {
                    Ok(a) => a,
                    Err(_) => return Err(err(format!("pushColumns: column '{}' must be a Float64Array", COLUMNS[i]))),
                };
                let len = arr.length() as usize;
                match n {
                    None => n = Some(len),
                    Some(m) if m != len => {
                        return Err(err(format!("pushColumns: column '{}' has length {len}, expected {m} (all columns must have the same length)", COLUMNS[i])))
                    }
                    _ => {}
                }
                let buf = &mut self.cols[i];
                buf.resize(len, 0.0);
                arr.copy_to(buf);
                present[i] = true;
            }
            Ok(())
        });
        res?;
        if !present[0] {
            return Err(err("pushColumns: column 't' is required"));
        }
        let n = n.unwrap_or(0);
        let base = self.inner.stats().rows;
        // Assemble and validate every row (time order included) before
        // touching state, so a rejected batch changes nothing.
        // Absent columns read as NaN; then one pass builds each row from
        // the 26 columns (no per-value dispatch on the column index).
        for (i, p) in present.iter().enumerate() {
            if !*p {
                self.cols[i].clear();
                self.cols[i].resize(n, f64::NAN);
            }
        }
        let c: [&[f64]; COLUMNS.len()] = core::array::from_fn(|i| &self.cols[i][..n]);
        self.rows.clear();
        self.rows.extend((0..n).map(|j| Sample::from_columns(&c, j)));
        let mut last_t = f64::NEG_INFINITY;
        for (j, s) in self.rows.iter().enumerate() {
            self.inner.validate(s, base + j as u64).map_err(|e| err(format!("{e} (batch index {j})")))?;
            if s.t < last_t {
                return Err(err(format!("row {}: field 't': time goes backwards: {} after {} (batch index {j})", base + j as u64, s.t, last_t)));
            }
            last_t = s.t;
        }
        let mut status = vec![0u8; n];
        let mut kind = vec![0u8; n];
        let mut f = vec![0.0; n];
        let mut r = vec![0.0; n];
        let mut c = vec![0.0; n];
        for (j, s) in self.rows.iter().enumerate() {
            let o = self.inner.push_valid(s);
            status[j] = o.status;
            kind[j] = o.kind;
            f[j] = o.f;
            r[j] = o.r;
            c[j] = o.c;
        }
        let obj = Object::new();
        set(&obj, "status", &Uint8Array::from(&status[..]).into());
        set(&obj, "f", &Float64Array::from(&f[..]).into());
        set(&obj, "r", &Float64Array::from(&r[..]).into());
        set(&obj, "c", &Float64Array::from(&c[..]).into());
        set(&obj, "kind", &Uint8Array::from(&kind[..]).into());
        Ok(obj.into())
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
    pub fn restore(snapshot: &[u8]) -> Result<Detector, JsError> {
        let inner = CoreDetector::restore(snapshot).map_err(err)?;
        Ok(Detector { inner, cols: vec![Vec::new(); COLUMNS.len()], rows: Vec::new() })
    }
}

/// A snapshot's header: `{ version, crateVersion, bytes }` (checksum verified).
#[wasm_bindgen(js_name = snapshotInfo, unchecked_return_type = "SnapshotInfo")]
pub fn snapshot_info(snapshot: &[u8]) -> Result<JsValue, JsError> {
    serde_wasm_bindgen::to_value(&crate::snapshot::info(snapshot).map_err(err)?).map_err(err)
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
pub fn audit_bytes(bytes: &[u8], #[wasm_bindgen(unchecked_param_type = "DetectorConfig | undefined")] config: JsValue) -> Result<JsValue, JsError> {
    let cfg = config_from(&config)?;
    let (report, cols) = audit::audit_bytes(bytes, &cfg, true).map_err(err)?;
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
    pub fn new(bytes: &[u8], #[wasm_bindgen(unchecked_param_type = "DetectorConfig | undefined")] config: JsValue) -> Result<Auditor, JsError> {
        let cfg = config_from(&config)?;
        let log = logs::read_any(bytes).map_err(err)?;
        let rows = log.samples.len();
        let run = audit::AuditRun::new(log, &cfg).map_err(err)?;
        Ok(Auditor { run: Some(run), rows })
    }

    /// Rows in the log.
    pub fn rows(&self) -> f64 {
        self.rows as f64
    }

    /// Process up to `rows` more rows; returns the fraction done.
    pub fn step(&mut self, rows: f64) -> f64 {
        match self.run.as_mut() {
            Some(r) => {
                r.step(if rows.is_finite() && rows > 0.0 { rows as usize } else { 1 });
                r.progress()
            }
            None => 1.0,
        }
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
        #[wasm_bindgen(js_name = keepOutputs)] keep_outputs: Option<bool>,
    ) -> Result<StreamAuditor, JsError> {
        let cfg = config_from(&config)?;
        Ok(StreamAuditor { run: Some(audit::StreamAudit::new(&cfg, keep_outputs.unwrap_or(false)).map_err(err)?) })
    }

    /// Feed the next chunk (any split); returns the rows it completed.
    pub fn feed(&mut self, chunk: &[u8]) -> Result<f64, JsError> {
        let run = self.run.as_mut().ok_or_else(|| err("StreamAuditor.feed: already finished"))?;
        Ok(run.feed(chunk).map_err(err)? as f64)
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
            serde_wasm_bindgen::from_value(options).map_err(|e| err(format!("compare options: {e}")))?
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
            .map(|m| crate::methods::Method::parse(m).map_err(|e| e.replace("config.method", "compare options.methods")))
            .collect::<Result<Vec<_>, _>>()
            .map_err(err)?;
        Ok(CompareRun { run: Some(crate::compare::CompareRun::new(&seeds, &methods, Some(js_clock)).map_err(err)?) })
    }

    /// Add a real log (any supported format) under `name`.
    #[wasm_bindgen(js_name = addLog)]
    pub fn add_log(&mut self, name: &str, bytes: &[u8]) -> Result<(), JsError> {
        let log = logs::read_any(bytes).map_err(|e| err(format!("{name}: {e}")))?;
        self.run.as_mut().ok_or_else(|| err("CompareRun: already finished"))?.add_log(name, log);
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
            serde_wasm_bindgen::from_value(config).map_err(|e| err(format!("tight config: {e}")))?
        };
        Ok(TightDetectorJs { inner: crate::tight::stream::TightDetector::new(cfg).map_err(err)? })
    }

    /// One epoch row; returns `{ t, status, faulty_prn, statistic, lambda_max, rdpop, action, n_sats, position_ned, ... }`.
    #[wasm_bindgen(unchecked_return_type = "TightOutput")]
    pub fn push(&mut self, #[wasm_bindgen(unchecked_param_type = "TightRow")] row: JsValue) -> Result<JsValue, JsError> {
        let row: crate::tight::stream::EpochRow = serde_wasm_bindgen::from_value(row).map_err(|e| err(format!("tight row: {e}")))?;
        let out = self.inner.push(&row).map_err(err)?;
        serde_wasm_bindgen::to_value(&out).map_err(err)
    }

    /// GAN-FDSR with a model from `tightGanTrain` (its `model` bytes) instead
    /// of the embedded one; `config` as for the constructor.
    #[wasm_bindgen(js_name = withGanModel)]
    pub fn with_gan_model(#[wasm_bindgen(unchecked_param_type = "object | undefined")] config: JsValue, model: &[u8]) -> Result<TightDetectorJs, JsError> {
        let cfg: crate::tight::stream::TightConfig = if config.is_undefined() || config.is_null() {
            Default::default()
        } else {
            serde_wasm_bindgen::from_value(config).map_err(|e| err(format!("tight config: {e}")))?
        };
        let model = crate::tight::gan_fdsr::GanDetectorModel::from_bytes(model).map_err(err)?;
        Ok(TightDetectorJs { inner: crate::tight::stream::TightDetector::with_gan(cfg, model).map_err(err)? })
    }

    /// Every row of a pseudo-range CSV (`pr_<prn>` or `sat_id` layout); an array of outputs.
    #[wasm_bindgen(js_name = pushCsv, unchecked_return_type = "TightOutput[]")]
    pub fn push_csv(&mut self, text: &str) -> Result<JsValue, JsError> {
        let rows = crate::tight::stream::parse_csv(text).map_err(err)?;
        let out = self.inner.run(&rows).map_err(err)?;
        serde_wasm_bindgen::to_value(&out).map_err(err)
    }
}

/// A simulated tightly coupled flight: environment `env` (1–5, the paper's
/// Table 3 plus Env 5), fault type 1–5 (Table 4; 0 = none), seed. Returns
/// `{ csv, config, faultyPrn, faultStart, faultEnd }`: feed `csv` to a
/// `new TightDetector(config)`.
#[wasm_bindgen(js_name = tightSimulate, unchecked_return_type = "{ csv: string; config: object; faultyPrn: number; faultStart: number; faultEnd: number }")]
pub fn tight_simulate(env: u32, fault_type: u32, seed: f64) -> Result<JsValue, JsError> {
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
    use crate::tight::gan_fdsr::{train_detector, GanTrainOptions};
    use crate::tight::scenario::{environments, SimConfig, World};
    let mut opts = GanTrainOptions::default();
    // Small by default: the page trains in seconds, not minutes.
    opts.train_seeds = vec![101, 102];
    opts.calib_seeds = vec![201, 202];
    opts.gan.epochs = 5;
    if !(options.is_undefined() || options.is_null()) {
        let get = |k: &str| js_sys::Reflect::get(&options, &JsValue::from_str(k)).unwrap_or(JsValue::UNDEFINED);
        let seeds = |k: &str| -> Result<Option<Vec<u64>>, JsError> {
            let v = get(k);
            if v.is_undefined() {
                return Ok(None);
            }
            let arr: Vec<f64> = serde_wasm_bindgen::from_value(v).map_err(|e| err(format!("tightGanTrain: {k}: {e}")))?;
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
            let v = get(k);
            if v.is_undefined() {
                continue;
            }
            match v.as_f64() {
                Some(x) if x.fract() == 0.0 && x >= lo as f64 && x <= hi as f64 => *slot = x as usize,
                _ => return Err(err(format!("tightGanTrain: {k} must be an integer in {lo}..={hi}, got {v:?}"))),
            }
        }
        let a = get("alpha");
        if !a.is_undefined() {
            opts.alpha = a.as_f64().filter(|x| *x > 0.0 && *x < 1.0).ok_or_else(|| err(format!("tightGanTrain: alpha must be in (0, 1), got {a:?}")))?;
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
pub fn read_log(bytes: &[u8]) -> Result<JsValue, JsError> {
    let log = logs::read_any(bytes).map_err(err)?;
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
pub fn simulate(name: &str, seed: f64) -> Result<String, JsError> {
    if !(seed.is_finite() && seed >= 0.0 && seed.fract() == 0.0 && seed < 9.0e15) {
        return Err(err(format!("seed: must be a non-negative integer, got {seed}")));
    }
    let sc = sim::Scenario::preset(name, seed as u64).map_err(err)?;
    let rows = sim::simulate(&sc).map_err(err)?;
    Ok(sim::to_csv(&sc, &rows))
}

/// Simulate a scenario given as an object (same fields as the `# scenario:` CSV comment).
#[wasm_bindgen(js_name = simulateScenario)]
pub fn simulate_scenario(#[wasm_bindgen(unchecked_param_type = "object")] scenario: JsValue) -> Result<String, JsError> {
    let sc: sim::Scenario = serde_wasm_bindgen::from_value(scenario).map_err(|e| err(format!("scenario: {e}")))?;
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
pub fn metrics(t: &[f64], label: &[f64], status: &[u8]) -> Result<JsValue, JsError> {
    if t.len() != label.len() || t.len() != status.len() {
        return Err(err(format!("metrics: lengths differ: t {}, label {}, status {}", t.len(), label.len(), status.len())));
    }
    serde_wasm_bindgen::to_value(&metrics::compute(t, label, status)).map_err(err)
}

/// Train a model from labelled navlog CSV files (an array of `Uint8Array`).
/// Pass the result as `config.model`.
#[wasm_bindgen(js_name = trainFromCsv, unchecked_return_type = "NavguardModel")]
pub fn train_from_csv(#[wasm_bindgen(unchecked_param_type = "Uint8Array[]")] files: Array, #[wasm_bindgen(unchecked_param_type = "DetectorConfig | undefined")] config: JsValue) -> Result<JsValue, JsError> {
    let cfg = config_from(&config)?;
    let mut streams = vec![];
    for (i, f) in files.iter().enumerate() {
        let bytes = f.dyn_into::<Uint8Array>().map_err(|_| err(format!("trainFromCsv: file {i} must be a Uint8Array")))?;
        let log = logs::csv::read_csv(&bytes.to_vec()).map_err(|e| err(format!("trainFromCsv: file {i}: {e}")))?;
        streams.push(log.samples);
    }
    let refs: Vec<&[Sample]> = streams.iter().map(|s| s.as_slice()).collect();
    let model = Model::train(&refs, &cfg, 42).map_err(err)?;
    serde_wasm_bindgen::to_value(&model).map_err(err)
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
