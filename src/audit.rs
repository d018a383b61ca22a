//! Whole-log audit: run the detector over a log and summarise (contract §3).

use core::borrow::Borrow;

use serde::Serialize;

use crate::config::Config;
use crate::detector::{kind, Detector, Output};
use crate::indicators::DRIVER_NAMES;
use crate::error::LogError;
use crate::logs::csv::CsvReader;
use crate::logs::dataflash::DataflashStream;
use crate::logs::ulog::UlogStream;
use crate::logs::extras::{iso_utc, EphSource, Extras, LogMessage, ModeChange};
use crate::logs::{sniff, Format, LogData, LogSummary, RowSink, FEED_CHUNK};
use crate::metrics::{self, Metrics};
use crate::sample::Sample;

/// One flagged interval.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct FaultInterval {
    /// Boot-clock seconds of the first and last flagged row.
    pub start: f64,
    /// Boot-clock seconds of the last flagged row.
    pub end: f64,
    /// "gps_outage" (no fix), "gps_stale" (the receiver repeated its last
    /// fix bit for bit: frozen output), "gps_degraded" (the receiver
    /// declared its fix degraded: 2D, ≤ 4 satellites, or an accuracy claim
    /// 3× its usual) or "residual".
    pub kind: &'static str,
    /// Largest F-indicator inside.
    pub peak_f: f64,
    /// Which residual group drove R at the peak, or "none" for an outage.
    pub driver: &'static str,
    /// Which indicator was further above its clean level at the peak: "R" or "C".
    pub indicator: &'static str,
    /// Rows inside the interval (all sensors). A span the detector dated
    /// once its fault ended (in `Report::reconciled`) adds none: its rows
    /// were judged before it was dated.
    pub rows: u64,
    /// Largest offset of the driving sensor from the filter's prediction
    /// inside the interval (the reference: the estimate coasting on the IMU
    /// and, for a position-only fault, the GPS velocity): position and baro
    /// in m, velocity in m/s (see `offset_unit`). None for an outage
    /// (absent in JSON and in JS alike).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub peak_offset: Option<f64>,
    /// "m", "m/s", or "" for an outage.
    pub offset_unit: &'static str,
    /// `end - start`, s.
    pub duration_s: f64,
    /// "low", "medium" or "high" (see [`severity`]).
    pub severity: &'static str,
}

impl FaultInterval {
    /// Close the interval: its duration and severity.
    fn closed(mut self) -> Self {
        self.duration_s = self.end - self.start;
        self.severity = severity(self.kind, self.offset_unit, self.peak_offset, self.duration_s);
        self
    }

    /// One interval spanning `self` and an `o` that starts later (of the
    /// same kind, or overlapping `self`: see [`reconcile`]).
    fn merged(mut self, o: &FaultInterval) -> Self {
        self.end = self.end.max(o.end);
        self.rows += o.rows;
        if o.peak_f > self.peak_f {
            self.peak_f = o.peak_f;
            self.driver = o.driver;
            self.indicator = o.indicator;
        }
        if o.offset_unit == self.offset_unit {
            self.peak_offset = max_opt(self.peak_offset, o.peak_offset);
        }
        self.closed()
    }
}

fn max_opt(a: Option<f64>, b: Option<f64>) -> Option<f64> {
    match (a, b) {
        (Some(x), Some(y)) => Some(x.max(y)),
        (x, None) => x,
        (None, y) => y,
    }
}

/// An interval's severity for an operator. `high`: the estimate would be
/// off by more than a multirotor's usual obstacle margin (10 m, 2 m/s of
/// velocity, 10 m of height by the baro), or the fault (or outage) lasted
/// 30 s or more, long enough for a position hold to drift away; `medium`:
/// more than 3 m (0.5 m/s), or 5 s or more; `low` otherwise (a short
/// departure a few metres wide, within a consumer receiver's own error
/// bound). Physical margins, not detector constants: they grade what an
/// interval means for the flight, not whether it is flagged.
pub fn severity(kind: &str, unit: &str, peak_offset: Option<f64>, duration_s: f64) -> &'static str {
    let (high, medium) = match unit {
        "m/s" => (2.0, 0.5),
        _ => (10.0, 3.0),
    };
    let off = if matches!(kind, "gps_outage" | "gps_stale") { None } else { peak_offset };
    if duration_s >= 30.0 || off.is_some_and(|x| x >= high) {
        "high"
    } else if duration_s >= 5.0 || off.is_some_and(|x| x >= medium) {
        "medium"
    } else {
        "low"
    }
}

/// The driving sensor's offset from the filter's prediction on this row
/// (`resid`: `Detector::residuals`), with its unit.
fn offset_of(driver: &str, resid: &[f64; 7]) -> (Option<f64>, &'static str) {
    let norm = |v: &[f64]| {
        let s: f64 = v.iter().map(|x| x * x).sum();
        s.is_finite().then(|| s.sqrt())
    };
    match driver {
        "gps_position" => (norm(&resid[0..3]), "m"),
        "gps_velocity" | "imu" => (norm(&resid[3..6]), "m/s"),
        "baro" => (resid[6].is_finite().then(|| resid[6].abs()), "m"),
        _ => (None, ""),
    }
}

/// The causal intervals reconciled over the whole log (issue 14 item 4).
/// `dated`: the spans the detector dated once their fault ended
/// ([`RetroSpans`], as intervals), which join the causal intervals they
/// overlap. Intervals of the same kind whose gap is shorter than
/// `RECONCILE_GAP_S` (or 3 GPS periods, `gps_period` s, if longer) are one
/// fault seen with gaps (a verdict flickering on an offset near its
/// threshold), so they become one interval from the first onset to the
/// last end. A stale fix and no fix count as one kind there: a frozen
/// receiver whose records also drop alternates between them at every
/// epoch (battery tune #572: a 9.7 s frozen fix listed as 161 intervals,
/// now one), and either way no fresh fix came. A dated silence before a
/// lost fix was called takes the rows it overlaps from an interval of
/// another kind (they carried the last fix's verdict).
pub fn reconcile(faults: &[FaultInterval], dated: &[FaultInterval], gps_period: f64) -> Vec<FaultInterval> {
    let max_gap = RECONCILE_GAP_S.max(3.0 * gps_period);
    let mut all: Vec<&FaultInterval> = faults.iter().chain(dated).collect();
    all.sort_by(|a, b| a.start.total_cmp(&b.start));
    let mut out: Vec<FaultInterval> = Vec::with_capacity(all.len());
    for iv in all {
        match out.last_mut() {
            // A dated silence before a lost fix was called takes its rows
            // from another kind's interval: those carried the last fix's
            // verdict while no fix came (real log 09-10 at 61.5 s).
            Some(last) if iv.rows == 0 && no_fresh_fix(iv.kind) && !same_kind(last.kind, iv.kind) && iv.start < last.end => {
                last.end = last.end.min(iv.start);
                *last = last.clone().closed();
                if last.end <= last.start {
                    *last = iv.clone();
                } else {
                    out.push(iv.clone());
                }
            }
            Some(last) if iv.start <= last.end || (same_kind(last.kind, iv.kind) && iv.start - last.end <= max_gap) => {
                *last = last.clone().merged(iv);
            }
            _ => out.push(iv.clone()),
        }
    }
    out
}

/// s: see [`reconcile`].
pub const RECONCILE_GAP_S: f64 = 2.0;

/// Kinds [`reconcile`] joins across a short gap: the same, or a stale fix
/// and no fix.
fn same_kind(a: &str, b: &str) -> bool {
    a == b || (no_fresh_fix(a) && no_fresh_fix(b))
}

/// A kind of no fresh fix: none, or a stale one.
fn no_fresh_fix(k: &str) -> bool {
    matches!(k, "gps_outage" | "gps_stale")
}

/// The spans a detector dated once their fault had ended or was called
/// (see [`Detector::retro_since`]): from the fault's onset to the row that
/// dated it, boot-clock s. A whole log's reconciled verdict is the causal
/// one or any of these; the streaming verdict never looks back.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RetroSpans {
    /// `(onset, end)` pairs, in the order they were dated.
    pub spans: Vec<(f64, f64)>,
}

impl RetroSpans {
    /// After `det` took the row at `t` (s): keep the span it dated there,
    /// if any (at most `MAX_LISTED`).
    pub fn note(&mut self, det: &Detector, t: f64) {
        if let Some(since) = det.retro_since() {
            if self.spans.len() < MAX_LISTED && since < t {
                self.spans.push((since, t));
            }
        }
    }

    /// Whether row time `t` (s) lies in a dated span (its end excluded: the
    /// row that ended the fault is the truth again).
    pub fn covers(&self, t: f64) -> bool {
        self.spans.iter().any(|&(a, b)| t >= a && t < b)
    }

    /// The span dated at the row `det` just took (see [`Detector::retro_since`])
    /// as a fault interval: a position fault whose peak offset is the GPS's
    /// jump back at its end; a slow fault (a baro drift, a position ramp)
    /// from its onset to its end, with the offset there; a stuck baro from
    /// its run's start; or the silence before an outage or a stale fix was
    /// called, of its kind. Its `rows` are 0: they were judged before the
    /// span was dated.
    fn interval(det: &Detector, o: &Output) -> Option<FaultInterval> {
        let since = det.retro_since().filter(|s| *s < o.t)?;
        let kind = kind_name(det.retro_kind());
        let no_fix = kind != "residual";
        let driver = if no_fix { "none" } else { DRIVER_NAMES[det.retro_group()] };
        let (peak_offset, offset_unit) = offset_of(driver, &det.residuals());
        let iv = FaultInterval {
            start: since,
            end: o.t,
            kind,
            peak_f: o.f,
            driver,
            indicator: if no_fix { "none" } else { "R" },
            rows: 0,
            peak_offset,
            offset_unit,
            duration_s: 0.0,
            severity: "",
        };
        Some(iv.closed())
    }
}

/// A pause in which every sensor stopped.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Gap {
    /// Boot-clock s of the last row before the pause.
    pub start: f64,
    /// Boot-clock s of the first row after it.
    pub end: f64,
}

/// The audit report (JSON via serde).
#[derive(Clone, Debug, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct Report {
    /// The log format: "csv", "ulog" or "dataflash" (`LogData::format`).
    pub format: &'static str,
    /// Rows audited.
    pub rows: usize,
    /// Time from the first row to the last, s.
    pub duration_s: f64,
    /// GPS epochs the detector judged.
    pub gps_epochs: u64,
    /// GPS epochs per second of log, Hz.
    pub gps_rate_hz: f64,
    /// IMU rows per second of log, Hz (0 without an IMU).
    pub imu_rate_hz: f64,
    /// Whether any GPS fix was seen; `false` means no residual verdicts were made.
    pub gps_available: bool,
    /// Fraction of GPS reports (rows with GPS columns) that carried a fix.
    pub gps_fix_fraction: f64,
    /// Share of GPS epochs flagged (residual faults).
    pub flagged_gps_epoch_fraction: f64,
    /// Flagged intervals as the streaming detector gave them (causal).
    pub faults: Vec<FaultInterval>,
    /// `faults` reconciled over the whole log ([`reconcile`]): what a
    /// person reading the log afterwards should count as fault intervals,
    /// with the spans the detector dated once a fault ended (a drag-off
    /// from its onset, a coasted-out step to its end, a slow drift or ramp
    /// from its onset once its offset jumped back) or was called (a frozen
    /// fix or a lost one from the first fix owed, a stuck baro from its
    /// first repeat; [`RetroSpans`]).
    /// `faults` stays the causal verdict, as the streaming `push` gave it.
    pub reconciled: Vec<FaultInterval>,
    /// Pauses in which every sensor stopped (logging gaps).
    pub data_gaps: Vec<Gap>,
    /// Detector inputs the log lacks: any of "gps", "imu", "attitude", "baro".
    pub missing: Vec<String>,
    /// What the reader and the detector coped with (skipped rows, truncation).
    pub warnings: Vec<String>,
    /// Vehicle and log metadata (key, value) from the reader.
    pub meta: Vec<(String, String)>,
    #[serde(skip_serializing_if = "Option::is_none")]
    /// Accuracy, false alarm and misdetection when the log has a `label` column.
    pub metrics: Option<Metrics>,
    /// The detector's counters at the end of the log.
    pub stats: crate::detector::Stats,
    /// Boot-clock s of the first row: a time minus this is the time since
    /// the log's start, as reports show it.
    pub start_t: f64,
    /// UTC of the first row, ISO 8601 ("2014-11-06T16:02:14.000Z"), when the
    /// log carries GPS time (DataFlash GWk/GMS, ULog time_utc_usec).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub start_utc: Option<String>,
    /// What the receiver-quality column `eph` holds: "eph" (m), "hdop"
    /// (unitless; DataFlash logs without GPA) or "none".
    pub eph_source: EphSource,
    /// Flight-mode changes (boot-clock s), at most 256.
    pub modes: Vec<ModeChange>,
    /// The autopilot's own messages (boot-clock s), at most 256.
    pub messages: Vec<LogMessage>,
}

impl Report {
    /// The log's extras (modes, messages, UTC, eph kind) into the report;
    /// they change no verdict.
    fn with_extras(mut self, x: &Extras) -> Report {
        self.start_utc = x.utc_at_boot.map(|u| iso_utc(u + self.start_t));
        self.eph_source = x.eph_source;
        self.modes = x.modes.clone();
        self.messages = x.messages.clone();
        if x.dropped > 0 {
            self.warnings.push(format!("{} flight modes and autopilot messages not listed (at most 256 of each are)", x.dropped));
        }
        self
    }
}

/// Per-row outputs in columns.
#[derive(Clone, Debug, Default)]
pub struct Columns {
    /// Row time, boot-clock s.
    pub t: Vec<f64>,
    /// Verdict per row: 0 normal, 1 fault.
    pub status: Vec<u8>,
    /// F-indicator (ANFIS output, or the method's statistic).
    pub f: Vec<f64>,
    /// R-indicator (residual level).
    pub r: Vec<f64>,
    /// C-indicator (residual change).
    pub c: Vec<f64>,
    /// Verdict kind per row (see [`crate::detector::kind`]).
    pub kind: Vec<u8>,
    /// Residuals per axis (see [`Detector::residuals`]), NaN where none.
    pub resid: [Vec<f64>; 7],
}

/// Names of the residual columns, in [`Columns::resid`] order.
pub const RESID_NAMES: [&str; 7] = ["rPn", "rPe", "rPd", "rVn", "rVe", "rVd", "rBaro"];

const MAX_LISTED: usize = 1000;

/// The per-row bookkeeping of an audit, whatever the rows come from: the
/// detector, fault intervals, gaps, counters and metrics. Bounded: lists are
/// capped at `MAX_LISTED`, everything else is a counter.
struct Tally {
    cfg: Config,
    det: Detector,
    metrics: metrics::Accumulator,
    warnings: Vec<String>,
    bad_rows: u64,
    faults: Vec<FaultInterval>,
    open: Option<FaultInterval>,
    gaps: Vec<Gap>,
    first_t: Option<f64>,
    last_t: Option<f64>,
    rows: usize,
    gps_reports: u64,
    gps_fixes: u64,
    flagged_epochs: u64,
    /// Inputs seen at least once: GPS, IMU, attitude, baro.
    seen: [bool; 4],
    /// Spans the detector called the vehicle upset (`kind::UPSET`), s, and
    /// whether the last row was one.
    upsets: Vec<Gap>,
    in_upset: bool,
    /// Spans the detector dated once their fault ended (`RetroSpans`).
    dated: Vec<FaultInterval>,
}

impl Tally {
    fn new(cfg: &Config, warnings: Vec<String>) -> Result<Self, String> {
        Ok(Tally {
            cfg: cfg.clone(),
            det: Detector::new(cfg.clone())?,
            metrics: metrics::Accumulator::default(),
            warnings,
            bad_rows: 0,
            faults: vec![],
            open: None,
            gaps: vec![],
            first_t: None,
            last_t: None,
            rows: 0,
            gps_reports: 0,
            gps_fixes: 0,
            flagged_epochs: 0,
            seen: [false; 4],
            upsets: vec![],
            in_upset: false,
            dated: vec![],
        })
    }

    /// One row (index `i` for messages). A row that fails validation is
    /// skipped with a warning (`None`): a log is audited, not rejected, for a
    /// few bad rows.
    fn push(&mut self, s: &Sample, i: u64) -> Option<Output> {
        if let Err(e) = self.det.validate(s, i) {
            self.bad_rows += 1;
            if self.bad_rows <= 5 {
                self.warnings.push(format!("skipped bad row: {e}"));
            }
            return None;
        }
        if let Some(lt) = self.last_t {
            if s.t - lt > self.cfg.data_gap && self.gaps.len() < MAX_LISTED {
                self.gaps.push(Gap { start: lt, end: s.t });
            }
        }
        self.last_t = Some(s.t);
        self.first_t.get_or_insert(s.t);
        self.rows += 1;
        if s.has_position() || !s.fix.is_nan() {
            self.gps_reports += 1;
            self.gps_fixes += s.has_fix() as u64;
        }
        let seen = [s.has_position() || s.reports_no_fix(), s.has_accel(), s.has_attitude(), s.has_baro()];
        for (a, b) in self.seen.iter_mut().zip(seen) {
            *a |= b;
        }
        let o = self.det.push_valid(s);
        if o.gps_epoch && o.status == 1 {
            self.flagged_epochs += 1;
        }
        track(&mut self.open, &mut self.faults, &o, &self.det);
        if let Some(iv) = RetroSpans::interval(&self.det, &o).filter(|_| self.dated.len() < MAX_LISTED) {
            self.dated.push(iv);
        }
        let upset = o.kind == kind::UPSET;
        if upset && self.in_upset {
            if let Some(u) = self.upsets.last_mut() {
                u.end = o.t;
            }
        } else if upset && self.upsets.len() < MAX_LISTED {
            self.upsets.push(Gap { start: o.t, end: o.t });
        }
        self.in_upset = upset;
        self.metrics.push(o.t, s.label, o.status);
        Some(o)
    }

    /// Inputs never seen, by the names `LogData::missing` uses.
    fn missing(&self) -> Vec<String> {
        ["gps", "imu", "attitude", "baro"].iter().zip(self.seen).filter(|(_, s)| !s).map(|(n, _)| n.to_string()).collect()
    }

    fn report(self, format: &'static str, missing: Vec<String>, meta: Vec<(String, String)>) -> Report {
        let Tally { det, metrics, mut warnings, bad_rows, mut faults, mut open, gaps, first_t, last_t, rows, gps_reports, gps_fixes, flagged_epochs, upsets, .. } = self;
        if let Some(iv) = open.take() {
            faults.push(iv.closed());
        }
        if bad_rows > 5 {
            warnings.push(format!("{bad_rows} bad rows skipped in all"));
        }
        let st = det.stats();
        // Every such warning starts so (the readers' and ours); `contains`
        // would bring in str slicing's panic path and, through it, std's
        // Unicode tables (see `navguard_logs::text`).
        if st.gps_epochs == 0 && !warnings.iter().any(|w| w.starts_with("GPS unavailable")) {
            warnings.push(if missing.iter().any(|m| m == "gps") {
                "GPS unavailable: the log has no GPS data; no residual-based verdicts were made".into()
            } else {
                "GPS unavailable: no valid fix in the whole log; no residual-based verdicts were made".into()
            });
        }
        for g in &gaps {
            warnings.push(format!("data gap: no rows from {:.2} s to {:.2} s (logging pause, not a navigation fault)", g.start, g.end));
        }
        for u in &upsets {
            warnings.push(format!(
                "vehicle upset: tilted past 90 deg from {:.2} s to {:.2} s (a crash or a flip, not a sensor fault); the sensors were not judged there",
                u.start, u.end
            ));
        }
        let duration = match (first_t, last_t) {
            (Some(a), Some(b)) => b - a,
            _ => 0.0,
        };
        let active = (duration - gaps.iter().map(|g| g.end - g.start).sum::<f64>()).max(1e-9);
        faults.truncate(MAX_LISTED);
        let gps_period = if st.gps_epochs > 0 { active / st.gps_epochs as f64 } else { 1.0 };
        let reconciled = reconcile(&faults, &self.dated, gps_period);
        Report {
            format,
            rows,
            duration_s: duration,
            gps_epochs: st.gps_epochs,
            gps_rate_hz: st.gps_epochs as f64 / active,
            imu_rate_hz: st.imu_rows as f64 / active,
            gps_available: st.gps_epochs > 0,
            gps_fix_fraction: if gps_reports > 0 { gps_fixes as f64 / gps_reports as f64 } else { 0.0 },
            flagged_gps_epoch_fraction: if st.gps_epochs > 0 { flagged_epochs as f64 / st.gps_epochs as f64 } else { 0.0 },
            faults,
            reconciled,
            data_gaps: gaps,
            missing,
            warnings,
            meta,
            metrics: metrics.any_label.then(|| metrics.metrics()),
            stats: st,
            start_t: first_t.unwrap_or(0.0),
            start_utc: None,
            eph_source: EphSource::None,
            modes: vec![],
            messages: vec![],
        }
    }
}

impl Columns {
    fn with_capacity(n: usize) -> Self {
        Columns {
            t: Vec::with_capacity(n),
            status: Vec::with_capacity(n),
            f: Vec::with_capacity(n),
            r: Vec::with_capacity(n),
            c: Vec::with_capacity(n),
            kind: Vec::with_capacity(n),
            resid: core::array::from_fn(|_| Vec::with_capacity(n)),
        }
    }

    fn push(&mut self, o: &Output, resid: &[f64; 7]) {
        self.t.push(o.t);
        self.status.push(o.status);
        self.f.push(o.f);
        self.r.push(o.r);
        self.c.push(o.c);
        self.kind.push(o.kind);
        for (k, v) in resid.iter().enumerate() {
            self.resid[k].push(*v);
        }
    }

    /// Append another set of outputs.
    pub fn append(&mut self, o: &Columns) {
        self.t.extend_from_slice(&o.t);
        self.status.extend_from_slice(&o.status);
        self.f.extend_from_slice(&o.f);
        self.r.extend_from_slice(&o.r);
        self.c.extend_from_slice(&o.c);
        self.kind.extend_from_slice(&o.kind);
        for (a, b) in self.resid.iter_mut().zip(&o.resid) {
            a.extend_from_slice(b);
        }
    }

    /// Rows held.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// No rows held.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }

    /// Empty, keeping the capacity.
    pub fn clear(&mut self) {
        self.t.clear();
        self.status.clear();
        self.f.clear();
        self.r.clear();
        self.c.clear();
        self.kind.clear();
        for v in &mut self.resid {
            v.clear();
        }
    }
}

/// An audit in progress: feed it rows a slice at a time ([`AuditRun::step`])
/// so a front end can report progress, then [`AuditRun::finish`].
pub struct AuditRun<L: Borrow<LogData>> {
    log: L,
    next: usize,
    cols: Columns,
    tally: Tally,
}

impl<L: Borrow<LogData>> AuditRun<L> {
    /// Start an audit of `log` (owned or borrowed).
    pub fn new(log: L, cfg: &Config) -> Result<Self, String> {
        let n = log.borrow().samples.len();
        let tally = Tally::new(cfg, log.borrow().warnings.clone())?;
        Ok(AuditRun { log, next: 0, cols: Columns::with_capacity(n), tally })
    }

    /// Fraction of rows processed, in [0, 1].
    pub fn progress(&self) -> f64 {
        let n = self.log.borrow().samples.len();
        if n == 0 {
            1.0
        } else {
            self.next as f64 / n as f64
        }
    }

    /// Every row of the log has been processed.
    pub fn done(&self) -> bool {
        self.next >= self.log.borrow().samples.len()
    }

    /// Process up to `max_rows` more rows (bad rows are skipped with a warning).
    pub fn step(&mut self, max_rows: usize) {
        let log = self.log.borrow();
        let end = self.next.saturating_add(max_rows).min(log.samples.len());
        for (i, s) in log.samples.iter().enumerate().take(end).skip(self.next) {
            if let Some(o) = self.tally.push(s, i as u64) {
                self.cols.push(&o, &self.tally.det.residuals());
            }
        }
        self.next = end;
    }

    /// Run what is left and build the report.
    pub fn finish(mut self) -> (Report, Columns) {
        self.step(usize::MAX);
        let log = self.log.borrow();
        // A CSV's inputs are those of the rows the audit accepted, as the
        // streaming audit counts them: a column whose every row was
        // rejected is missing (found by the fuzz target that compares the
        // two paths).
        let missing = if log.format == "csv" { self.tally.missing() } else { log.missing.clone() };
        let report = self.tally.report(log.format, missing, log.meta.clone()).with_extras(&log.extras);
        (report, self.cols)
    }
}

/// Run the detector over a whole log.
pub fn audit(log: &LogData, cfg: &Config) -> Result<(Report, Columns), String> {
    Ok(AuditRun::new(log, cfg)?.finish())
}

/// Most CSV bytes parsed at once: bounds the rows held between the reader
/// and the detector (a 4 MiB chunk of 4-byte rows would be 1 M rows, 208 MB).
const CSV_SLICE: usize = 64 << 10;

/// The reader a [`StreamAudit`] feeds, chosen from the first bytes.
enum Source {
    /// Not enough bytes yet to tell the format (fewer than 7).
    Sniff(Vec<u8>),
    Csv(CsvReader),
    Ulog(Box<UlogStream>),
    Dataflash(Box<DataflashStream>),
}

/// The detector end of a streaming reader: every row is audited as it comes.
struct Feed<'a> {
    tally: &'a mut Tally,
    out: &'a mut Columns,
    keep_outputs: bool,
}

impl RowSink for Feed<'_> {
    fn row(&mut self, s: &Sample) {
        let i = self.tally.rows as u64 + self.tally.bad_rows;
        if let Some(o) = self.tally.push(s, i) {
            if self.keep_outputs {
                self.out.push(&o, &self.tally.det.residuals());
            }
        }
    }
}

/// A log audited as it streams in, chunk by chunk, in bounded memory (a
/// 1 GB file never sits in memory whole): navlog CSV, ULog or DataFlash,
/// recognised by content. The readers are incremental, and per-row outputs
/// are kept only for the latest chunk ([`StreamAudit::outputs`], e.g. for a
/// per-sample file written alongside). The report equals [`audit`]'s on the
/// same bytes.
///
/// A ULog file is read twice (its first pass finds which topics have data):
/// after the last chunk, call [`StreamAudit::end_pass`]; when it returns
/// true, feed the same bytes again from the start, then call it again.
pub struct StreamAudit {
    src: Source,
    tally: Tally,
    /// Rows parsed from the current CSV slice (reused).
    rows: Vec<Sample>,
    out: Columns,
    keep_outputs: bool,
    bytes: u64,
}

impl StreamAudit {
    /// `keep_outputs`: collect each chunk's per-row outputs.
    pub fn new(cfg: &Config, keep_outputs: bool) -> Result<Self, String> {
        Ok(StreamAudit { src: Source::Sniff(Vec::new()), tally: Tally::new(cfg, vec![])?, rows: Vec::new(), out: Columns::default(), keep_outputs, bytes: 0 })
    }

    /// Feed the next chunk of the file (any size, any split). Returns the
    /// rows completed by it. A malformed CSV line is an error naming it, as
    /// in [`crate::logs::csv::read_csv`].
    pub fn feed(&mut self, chunk: &[u8]) -> Result<usize, String> {
        self.bytes += chunk.len() as u64;
        self.out.clear();
        let before = self.tally.rows as u64 + self.tally.bad_rows;
        self.feed_inner(chunk, false)?;
        Ok((self.tally.rows as u64 + self.tally.bad_rows - before) as usize)
    }

    fn feed_inner(&mut self, chunk: &[u8], at_end: bool) -> Result<(), String> {
        if let Source::Sniff(head) = &mut self.src {
            head.extend_from_slice(chunk);
            let Some(format) = sniff(head, at_end) else {
                return Ok(());
            };
            let head = core::mem::take(head);
            self.src = match format {
                Format::Csv => Source::Csv(CsvReader::new()),
                Format::Ulog => Source::Ulog(Box::new(UlogStream::plan())),
                Format::Dataflash => Source::Dataflash(Box::default()),
            };
            return self.feed_inner(&head, at_end);
        }
        let mut feed = Feed { tally: &mut self.tally, out: &mut self.out, keep_outputs: self.keep_outputs };
        match &mut self.src {
            Source::Sniff(_) => {}
            Source::Ulog(r) => r.feed(chunk, &mut feed),
            Source::Dataflash(r) => r.feed(chunk, &mut feed),
            Source::Csv(r) => {
                for slice in chunk.chunks(CSV_SLICE) {
                    self.rows.clear();
                    let res = r.read_chunk(slice, &mut self.rows);
                    res.map_err(|e| not_csv(r, e))?;
                    for s in &self.rows {
                        feed.row(s);
                    }
                }
            }
        }
        Ok(())
    }

    /// The format, once the first bytes are in.
    pub fn format(&self) -> Option<&'static str> {
        match self.src {
            Source::Sniff(_) => None,
            Source::Csv(_) => Some("csv"),
            Source::Ulog(_) => Some("ulog"),
            Source::Dataflash(_) => Some("dataflash"),
        }
    }

    /// End of one pass over the file. `Ok(true)`: feed the same bytes again
    /// from the start (the second pass over a ULog file); `Ok(false)`: call
    /// [`StreamAudit::finish`]. Err when the file cannot be read.
    pub fn end_pass(&mut self) -> Result<bool, String> {
        self.out.clear();
        self.feed_inner(&[], true)?;
        let Source::Ulog(r) = &mut self.src else {
            return Ok(false);
        };
        if !r.is_planning() {
            return Ok(false);
        }
        let first = core::mem::replace(r.as_mut(), UlogStream::plan());
        **r = first.second_pass()?;
        Ok(true)
    }

    fn drain(&mut self) {
        let mut feed = Feed { tally: &mut self.tally, out: &mut self.out, keep_outputs: self.keep_outputs };
        for s in &self.rows {
            feed.row(s);
        }
    }

    /// Per-row outputs of the latest chunk (empty unless `keep_outputs`).
    pub fn outputs(&self) -> &Columns {
        &self.out
    }

    /// Bytes fed so far (over all passes).
    pub fn bytes(&self) -> u64 {
        self.bytes
    }

    /// Rows audited so far (bad rows excluded).
    pub fn rows(&self) -> usize {
        self.tally.rows
    }

    /// End of input: the report, and the outputs of the rows completed by
    /// the end (a last CSV line without a newline, the rows a binary reader
    /// still held) when `keep_outputs`.
    pub fn finish(mut self) -> Result<(Report, Columns), String> {
        self.out.clear();
        self.feed_inner(&[], true)?;
        let summary = match core::mem::replace(&mut self.src, Source::Sniff(Vec::new())) {
            Source::Sniff(_) => return Err("not a ULog or DataFlash log, and not a navlog CSV: no header row found (empty file or only comments)".into()),
            Source::Csv(mut r) => {
                self.rows.clear();
                let res = r.read_end(&mut self.rows);
                res.map_err(|e| not_csv(&r, e))?;
                self.drain();
                let meta = r.comments.iter().take(8).enumerate().map(|(i, c)| (format!("comment{i}"), c.clone())).collect();
                LogSummary { format: "csv", meta, warnings: core::mem::take(&mut r.warnings), missing: self.tally.missing(), topic_counts: vec![], extras: r.extras() }
            }
            Source::Ulog(r) => {
                if r.is_planning() {
                    return Err("ULog input is read in two passes: call end_pass() after the first and feed the file again".into());
                }
                let mut feed = Feed { tally: &mut self.tally, out: &mut self.out, keep_outputs: self.keep_outputs };
                r.finish(&mut feed)?
            }
            Source::Dataflash(r) => {
                let mut feed = Feed { tally: &mut self.tally, out: &mut self.out, keep_outputs: self.keep_outputs };
                r.finish(&mut feed)?
            }
        };
        let LogSummary { format, meta, mut warnings, missing, extras, .. } = summary;
        warnings.append(&mut self.tally.warnings);
        self.tally.warnings = warnings;
        Ok((self.tally.report(format, missing, meta).with_extras(&extras), self.out))
    }
}

/// An error before the header says what the file is not, as [`read_any`](crate::logs::read_any) does.
fn not_csv(r: &CsvReader, e: LogError) -> String {
    let e = e.to_string();
    if r.has_header() {
        e
    } else {
        format!("not a ULog or DataFlash log, and not a navlog CSV: {e}")
    }
}

/// Audit a whole file held in memory through the streaming path (both
/// passes for ULog): the same report as [`audit`] of [`read_any`](crate::logs::read_any),
/// without holding the parsed rows. With `keep_outputs`, every row's outputs.
pub fn audit_bytes(bytes: &[u8], cfg: &Config, keep_outputs: bool) -> Result<(Report, Columns), String> {
    audit_chunks(bytes, cfg, keep_outputs, FEED_CHUNK)
}

/// [`audit_bytes`] fed `chunk` bytes at a time (any size gives the same result).
pub fn audit_chunks(bytes: &[u8], cfg: &Config, keep_outputs: bool, chunk: usize) -> Result<(Report, Columns), String> {
    let mut run = StreamAudit::new(cfg, keep_outputs)?;
    let mut all = Columns::default();
    loop {
        for c in bytes.chunks(chunk.max(1)) {
            run.feed(c)?;
            all.append(run.outputs());
        }
        if !run.end_pass()? {
            break;
        }
    }
    let (report, last) = run.finish()?;
    all.append(&last);
    Ok((report, all))
}

/// A fault interval's `kind` for a detector's `kind` code.
fn kind_name(k: u8) -> &'static str {
    match k {
        kind::OUTAGE => "gps_outage",
        kind::STALE => "gps_stale",
        kind::DEGRADED => "gps_degraded",
        _ => "residual",
    }
}

fn track(open: &mut Option<FaultInterval>, done: &mut Vec<FaultInterval>, o: &Output, det: &Detector) {
    if o.status == 0 {
        if let Some(iv) = open.take() {
            if done.len() < MAX_LISTED {
                done.push(iv.closed());
            }
        }
        return;
    }
    let no_fix = matches!(o.kind, kind::OUTAGE | kind::STALE);
    let kind_name = kind_name(o.kind);
    let ind = det.indicators();
    let driver = if no_fix { "none" } else { ind.r_driver().and_then(|g| DRIVER_NAMES.get(g).copied()).unwrap_or("none") };
    // R is ≈1 when clean and C ≈ 0.2: compare relative excess.
    let indicator = if no_fix { "none" } else if (o.c - 0.2) / 0.8 > (o.r - 1.0) / 4.0 { "C" } else { "R" };
    let (offset, unit) = offset_of(driver, &det.residuals());
    match open {
        Some(iv) if iv.kind == kind_name => {
            iv.end = o.t;
            iv.rows += 1;
            if o.f > iv.peak_f {
                iv.peak_f = o.f;
                iv.driver = driver;
                iv.indicator = indicator;
            }
            // The offset of the interval's driver (the first row's unit).
            if unit == iv.offset_unit {
                iv.peak_offset = max_opt(iv.peak_offset, offset);
            }
        }
        _ => {
            if let Some(iv) = open.take() {
                if done.len() < MAX_LISTED {
                    done.push(iv.closed());
                }
            }
            *open = Some(FaultInterval {
                start: o.t,
                end: o.t,
                kind: kind_name,
                peak_f: o.f,
                driver,
                indicator,
                rows: 1,
                peak_offset: offset,
                offset_unit: unit,
                duration_s: 0.0,
                severity: "low",
            });
        }
    }
}
