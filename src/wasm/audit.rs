//! Whole-log audits (`auditBytes`, `Auditor`, `StreamAuditor`) and
//! `metrics`. Audit module (feature `wasm-audit`): its own copy of the
//! detector and the readers, loaded on first use, so that the core module
//! (`new Detector()` plus `readLog`) does not carry the audit's code.

use js_sys::{Float64Array, Object, Uint8Array};
use wasm_bindgen::prelude::*;

use super::interop::{self as js_in, array_of, config_from, err, set, stats_object, string_pairs, strings, Obj, MAX_BYTES, MAX_VALUES};
use crate::logs::extras::EphSource;
use crate::audit;
use crate::logs;
use crate::metrics;

#[wasm_bindgen(typescript_custom_section)]
const TS_AUDIT: &'static str = r#"
export interface Metrics { tp: number; fp: number; tn: number; fn: number; accuracy: number; falseAlarmRate: number; misdetectionRate: number; precision: number; recall: number; f2: number; meanDetectionDelay: number; faultIntervals: number; detectedIntervals: number }
export interface FaultInterval {
  start: number; end: number; kind: "gps_outage" | "gps_stale" | "gps_degraded" | "residual"; peakF: number; driver: "gps_position" | "gps_velocity" | "baro" | "imu" | "none"; indicator: "R" | "C" | "none"; rows: number;
  /** Largest offset of the driving sensor from the filter's prediction, in `offsetUnit`; absent for an outage. */
  peakOffset?: number; offsetUnit: "m" | "m/s" | "";
  durationS: number; severity: "low" | "medium" | "high";
}
export interface AuditReport {
  format: "csv" | "ulog" | "dataflash"; rows: number; durationS: number; gpsEpochs: number; gpsRateHz: number; imuRateHz: number;
  gpsAvailable: boolean; gpsFixFraction: number; flaggedGpsEpochFraction: number;
  /** Causal intervals, as `push` gave them; `reconciled`: the same over the whole log, gaps under 2 s (or 3 GPS periods) of one kind joined, with the spans the detector dated once a fault ended (a drag-off from its onset, a step past its coast limit; `rows` 0 for those). */
  faults: FaultInterval[]; reconciled: FaultInterval[]; dataGaps: { start: number; end: number }[]; missing: string[]; warnings: string[];
  meta: [string, string][]; metrics?: Metrics; stats: DetectorStats;
  /** Boot-clock s of the first row; show times as t - startT. startUtc: ISO 8601 UTC of the first row when the log has GPS time. */
  startT: number; startUtc?: string;
  /** What the receiver-quality column `eph` holds: metres, HDOP (unitless) or nothing. */
  ephSource: "eph" | "hdop" | "none";
  modes: { t: number; mode: string }[]; messages: { t: number; level: "error" | "warning" | "info" | "event"; text: string }[];
}
/** Residual columns: GPS position N/E/D (m), velocity N/E/D (m/s), baro (m); NaN on rows without that measurement. */
export interface AuditResult { report: AuditReport; columns: { t: Float64Array; status: Uint8Array; f: Float64Array; r: Float64Array; c: Float64Array; kind: Uint8Array; rPn: Float64Array; rPe: Float64Array; rPd: Float64Array; rVn: Float64Array; rVe: Float64Array; rVd: Float64Array; rBaro: Float64Array } }
"#;

/// One fault interval as JS sees it (`peakOffset` absent for an outage).
fn interval_object(iv: &audit::FaultInterval) -> JsValue {
    let mut o = Obj::new()
        .n("start", iv.start)
        .n("end", iv.end)
        .s("kind", iv.kind)
        .n("peakF", iv.peak_f)
        .s("driver", iv.driver)
        .s("indicator", iv.indicator)
        .n("rows", iv.rows as f64);
    if let Some(x) = iv.peak_offset {
        o = o.n("peakOffset", x);
    }
    o.s("offsetUnit", iv.offset_unit).n("durationS", iv.duration_s).s("severity", iv.severity).done()
}

/// Metrics as JS sees them (camelCase).
fn metrics_object(m: &metrics::Metrics) -> JsValue {
    Obj::new()
        .n("tp", m.tp as f64)
        .n("fp", m.fp as f64)
        .n("tn", m.tn as f64)
        .n("fn", m.r#fn as f64)
        .n("accuracy", m.accuracy)
        .n("falseAlarmRate", m.false_alarm_rate)
        .n("misdetectionRate", m.misdetection_rate)
        .n("precision", m.precision)
        .n("recall", m.recall)
        .n("f2", m.f2)
        .n("meanDetectionDelay", m.mean_detection_delay)
        .n("faultIntervals", m.fault_intervals as f64)
        .n("detectedIntervals", m.detected_intervals as f64)
        .done()
}

/// The report as JS sees it (camelCase; `metrics` and `startUtc` absent
/// when the log has no labels or no GPS time).
fn report_object(r: &audit::Report) -> JsValue {
    let gaps = array_of(&r.data_gaps, |g| Obj::new().n("start", g.start).n("end", g.end).done());
    let mut o = Obj::new()
        .s("format", r.format)
        .n("rows", r.rows as f64)
        .n("durationS", r.duration_s)
        .n("gpsEpochs", r.gps_epochs as f64)
        .n("gpsRateHz", r.gps_rate_hz)
        .n("imuRateHz", r.imu_rate_hz)
        .b("gpsAvailable", r.gps_available)
        .n("gpsFixFraction", r.gps_fix_fraction)
        .n("flaggedGpsEpochFraction", r.flagged_gps_epoch_fraction)
        .v("faults", &array_of(&r.faults, interval_object))
        .v("reconciled", &array_of(&r.reconciled, interval_object))
        .v("dataGaps", &gaps)
        .v("missing", &strings(&r.missing))
        .v("warnings", &strings(&r.warnings))
        .v("meta", &string_pairs(&r.meta));
    if let Some(m) = &r.metrics {
        o = o.v("metrics", &metrics_object(m));
    }
    o = o.v("stats", &stats_object(&r.stats)).n("startT", r.start_t);
    if let Some(u) = &r.start_utc {
        o = o.s("startUtc", u);
    }
    let eph = match r.eph_source {
        EphSource::None => "none",
        EphSource::Eph => "eph",
        EphSource::Hdop => "hdop",
    };
    o.s("ephSource", eph)
        .v("modes", &array_of(&r.modes, |m| Obj::new().n("t", m.t).s("mode", &m.mode).done()))
        .v("messages", &array_of(&r.messages, |m| Obj::new().n("t", m.t).s("level", m.level).s("text", &m.text).done()))
        .done()
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
    set(&out, "report", &report_object(report));
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
    /// Read the whole log `bytes` (any supported format) and set up the
    /// detector with `config`; nothing is pushed until `step`.
    #[wasm_bindgen(constructor)]
    pub fn new(#[wasm_bindgen(unchecked_param_type = "Uint8Array")] bytes: &JsValue, #[wasm_bindgen(unchecked_param_type = "DetectorConfig | undefined")] config: JsValue) -> Result<Auditor, JsError> {
        let cfg = config_from(&config)?;
        let bytes = js_in::bytes(bytes, MAX_BYTES, "Auditor: bytes").map_err(err)?;
        let log = logs::read_any(&bytes)?;
        let rows = log.samples.len();
        let run = audit::AuditRun::new(log, &cfg).map_err(err)?;
        Ok(Auditor { run: Some(run), rows })
    }

    /// Rows in the log.
    pub fn rows(&self) -> f64 {
        self.rows as f64
    }

    /// Process up to `rows` more rows; returns the fraction done.
    pub fn step(&mut self, #[wasm_bindgen(unchecked_param_type = "number | undefined")] rows: &JsValue) -> Result<f64, JsError> {
        let rows = match js_in::given(rows) {
            None => 1.0,
            Some(rows) => js_in::num(rows, "Auditor.step: rows").map_err(err)?,
        };
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
    /// A streaming audit with `config`; `keepOutputs` keeps each chunk's
    /// per-row outputs for `outputs()`.
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
    Ok(metrics_object(&metrics::compute(t, label, status)))
}


/// Bytes of this module's wasm linear memory; the package's
/// `wasmMemoryBytes()` adds them to the core's once this module is loaded.
#[wasm_bindgen(js_name = __wasmMemoryBytes)]
pub fn wasm_memory_bytes() -> f64 {
    (core::arch::wasm32::memory_size(0) * 65536) as f64
}
