//! The online KF–ANFIS detector of Sun et al. 2017 §2.4.
//!
//! Per row: validate, predict the filter to the row's time, feed IMU and
//! baro, and at each GPS fix compute residuals, the R/C indicators and the
//! ANFIS F-indicator; `F ≥ threshold` is a fault. A fault epoch's residual
//! groups that departed are not fed to the filter (it coasts on the IMU), so a
//! fault cannot drag the estimate it is judged against. A group that departed
//! stays withheld for the rest of the fault episode (fault memory); GPS
//! velocity is withheld with a departed position when the receiver is
//! incoherent (its position and velocity disagree at every recent epoch),
//! and GPS position with a departed velocity when its residual is off its
//! clean level. A group that never departed (velocity during a position
//! step or ramp) keeps aiding the filter, so the coast drift, and with it the
//! departure's normalisation, stays small. A fault episode ends early
//! (re-anchoring the filter on GPS) once the GPS increments agree with the
//! filter's for 5 epochs and the baro is clean, and either the episode
//! withheld the whole receiver (outage, degraded fix: the offset is the
//! IMU coast's own drift, whatever its size) and the velocity no longer
//! departs, or only the position was withheld and its departure is below 4
//! (a larger offset with clean velocity aiding is a persisting step).
//! A receiver that reports losing its fix is an outage on the ground too.
//! A withheld barometer comes back once its vertical consistency (see
//! `indicators`) stays below 1.5 for 5 baro samples; its offset state is then
//! re-anchored (`Kf::reset_baro`), since it absorbed part of the fault
//! before detection and would otherwise raise false alarms after it.
//!
//! Online cycle (eqs. 15–20): each epoch's own verdict files its (R, C) into
//! database D1 (normal) or D2 (fault), ring buffers of length q, but only a
//! confident verdict: `F ≤ 0.2` into D1, `F ≥ 0.8` with a fault signature
//! (`R ≥ 3` or `C ≥ 0.7`, the same rule that cleans the training set) into
//! D2. After TC new D2 entries the ANFIS is retrained on D1 ∪ D2 by hybrid
//! learning, and the candidate replaces the current ANFIS only if it
//! misclassifies no more of D0 (the shipped model's databases) than the
//! current one. Without these guards retraining fed on its own borderline
//! false alarms and widened the fault region with each cycle. No fix while flying, after a fix
//! has been seen, is a GPS outage (a fault); rows between fixes carry the last
//! epoch's verdict. Every allocation happens in `new`.

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::anfis::{inputs, Anfis};
use crate::config::Config;
use crate::filter::{quat_from_wxyz, FilterError, ImuInput, Kf};
use crate::frames::Anchor;
use crate::indicators::{IndicatorEngine, Indicators, GROUPS};
use crate::methods::{self, Decision, EpochInnovations, MahaWindow, Method, PoolState};
use crate::sample::Sample;

/// A trained model: ANFIS parameters plus the initial databases D1₀, D2₀.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Model {
    pub anfis: Anfis,
    /// Normal samples, ANFIS input space `[ln(1+R), C]`.
    pub d1: Vec<[f64; 2]>,
    /// Fault samples.
    pub d2: Vec<[f64; 2]>,
    /// How it was made (free text).
    #[serde(default)]
    pub provenance: String,
}

impl Model {
    /// The model shipped in the crate, made by `cargo run --release --bin navguard-train`.
    /// Parsed once per process (a few hundred µs), then cloned.
    pub fn embedded() -> Result<Model, String> {
        static EMBEDDED: std::sync::OnceLock<Result<Model, String>> = std::sync::OnceLock::new();
        EMBEDDED
            .get_or_init(|| {
                serde_json::from_str(include_str!("default_model.json")).map_err(|e| format!("embedded model: {e}"))
            })
            .clone()
    }

    /// Train a model from labelled streams: run the detector with decisions
    /// forced to the labels (so the filter gates as it would on a correct
    /// verdict), collect `(R, C)` at labelled GPS epochs, clean, subsample
    /// `q` per class with a seeded RNG, and fit the ANFIS by hybrid learning.
    ///
    /// Cleaning: fault epochs whose indicators never left the clean region
    /// (`R < 3` and `C < 0.7`, e.g. the first seconds of a slow ramp) are
    /// dropped from D2: they carry no fault signature and would only teach the
    /// model to alarm on clean data.
    pub fn train(streams: &[&[Sample]], cfg: &Config, seed: u64) -> Result<Model, String> {
        let mut normal = vec![];
        let mut fault = vec![];
        let base = Model::untrained();
        for rows in streams {
            let mut det = Detector::with_model(cfg.clone(), &base);
            det.set_oracle(true);
            for (i, s) in rows.iter().enumerate() {
                let o = det.push(s).map_err(|e| format!("training stream, {e} (index {i})"))?;
                if !o.gps_epoch || s.label.is_nan() || o.kind == kind::NO_GPS {
                    continue;
                }
                let x = inputs(o.r, o.c);
                if s.label >= 0.5 {
                    if has_signature(o.r, o.c) {
                        fault.push(x);
                    }
                } else {
                    normal.push(x);
                }
            }
        }
        if normal.len() < 10 || fault.len() < 10 {
            return Err(format!(
                "training needs at least 10 labelled normal and 10 fault GPS epochs with a fault signature; got {} and {}",
                normal.len(),
                fault.len()
            ));
        }
        let mut rng = crate::sim::Rng::new(seed);
        let pick = |v: &mut Vec<[f64; 2]>, n: usize, rng: &mut crate::sim::Rng| -> Vec<[f64; 2]> {
            // Partial Fisher–Yates: a seeded uniform subsample.
            let n = n.min(v.len());
            for i in 0..n {
                let j = i + (rng.next_u64() % (v.len() - i) as u64) as usize;
                v.swap(i, j);
            }
            v[..n].to_vec()
        };
        let d1 = pick(&mut normal, cfg.q, &mut rng);
        let d2 = pick(&mut fault, cfg.q, &mut rng);
        let mut xs = d1.clone();
        xs.extend_from_slice(&d2);
        let ys: Vec<f64> = d1.iter().map(|_| 0.0).chain(d2.iter().map(|_| 1.0)).collect();
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for x in &xs {
            for k in 0..2 {
                lo[k] = lo[k].min(x[k]);
                hi[k] = hi[k].max(x[k]);
            }
        }
        let mut anfis = Anfis::init_grid(lo, hi);
        let mse = anfis.train_hybrid(&xs, &ys, 200, 0.05);
        Ok(Model {
            anfis,
            d1,
            d2,
            provenance: format!(
                "navguard-train: {} streams, {} normal / {} fault epochs before subsampling, q={}, window={}, seed={}, training MSE {:.4}",
                streams.len(),
                normal.len(),
                fault.len(),
                cfg.q,
                cfg.window,
                seed,
                mse
            ),
        })
    }

    /// Grid-initialised ANFIS with a plain R ramp, used only to drive the
    /// trainer's oracle runs (their decisions come from the labels).
    pub fn untrained() -> Model {
        Model {
            anfis: Anfis::init_grid([0.0, 0.0], [3.0, 1.0]),
            d1: vec![],
            d2: vec![],
            provenance: "untrained".into(),
        }
    }

    pub fn check(&self) -> Result<(), String> {
        crate::config::check_anfis(&self.anfis)?;
        if !self.d1.iter().chain(self.d2.iter()).flatten().all(|v| v.is_finite()) {
            return Err("database entries must be finite".into());
        }
        Ok(())
    }
}

/// A fault epoch carries a fault signature: its indicators left the region
/// clean data occupies (`R ≥ 3` or `C ≥ 0.7`). Used to clean the training
/// set and to admit online verdicts into D2.
pub fn has_signature(r: f64, c: f64) -> bool {
    r >= SIG_R || c >= SIG_C
}
const SIG_R: f64 = 3.0;
const SIG_C: f64 = 0.7;

/// What kind of verdict a row carries.
pub mod kind {
    pub const NORMAL: u8 = 0;
    /// Residual-based fault (ANFIS).
    pub const RESIDUAL: u8 = 1;
    /// GPS outage: no fix while flying.
    pub const OUTAGE: u8 = 2;
    /// No verdict possible: no GPS fix seen yet (or since a data gap).
    pub const NO_GPS: u8 = 3;
}

/// Per-row output.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Output {
    pub t: f64,
    /// 0 normal, 1 fault.
    pub status: u8,
    /// F-indicator.
    pub f: f64,
    pub r: f64,
    pub c: f64,
    /// See [`kind`].
    pub kind: u8,
    /// Whether this row was a GPS epoch (a fix was evaluated).
    pub gps_epoch: bool,
    /// What drove R (0 GPS position, 1 GPS velocity, 2 baro, 3 the IMU
    /// through the IMU–GPS velocity consistency, 255 none).
    pub driver: u8,
}

/// Bad input: names the row and the field.
#[derive(Clone, Debug, PartialEq)]
pub struct InputError {
    pub row: u64,
    pub field: &'static str,
    pub reason: String,
}

impl core::fmt::Display for InputError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "row {}: field '{}': {}", self.row, self.field, self.reason)
    }
}

/// Counters of things worth reporting (no unbounded storage).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Stats {
    pub rows: u64,
    pub gps_epochs: u64,
    pub imu_rows: u64,
    pub baro_rows: u64,
    pub retrains: u64,
    pub filter_resets: u64,
    pub data_gaps: u64,
    pub filter_errors: u64,
}

/// Fixed-capacity ring buffer (database D1 or D2).
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Ring {
    buf: Vec<[f64; 2]>,
    head: usize,
    len: usize,
}

impl Ring {
    fn new(cap: usize, init: &[[f64; 2]]) -> Self {
        let mut r = Ring { buf: vec![[0.0; 2]; cap.max(1)], head: 0, len: 0 };
        let skip = init.len().saturating_sub(cap);
        for x in init.iter().skip(skip) {
            r.push(*x);
        }
        r
    }
    fn push(&mut self, x: [f64; 2]) {
        let cap = self.buf.len();
        self.buf[self.head] = x;
        self.head = (self.head + 1) % cap;
        self.len = (self.len + 1).min(cap);
    }
    fn items(&self) -> &[[f64; 2]] {
        &self.buf[..self.len]
    }
    /// Indices in range and capacity `q` (a restored snapshot may be forged).
    fn check_shape(&self, q: usize, name: &str) -> Result<(), String> {
        let cap = self.buf.len();
        if cap != q.max(1) || self.head >= cap || self.len > cap {
            return Err(format!(
                "database {name}: capacity {cap} / head {} / len {} inconsistent with q = {q}",
                self.head, self.len
            ));
        }
        Ok(())
    }
}

const IMU_TIMEOUT: f64 = 0.25; // s: older IMU is not used for prediction
/// The IMU consistency joins the decision after this much flight (s) and
/// this many in-flight windows learnt: its σ must be the flight's, not the
/// ground's (on the real Loiter log, take-off alone reaches 3–6).
const IMU_ARM_S: f64 = 20.0;
const IMU_ARM_WINDOWS: u32 = 50;
/// An IMU episode ends when z's change over the last `IMU_RECENT_S` s stays
/// below `IMU_CALM` σ for `RECOVER_EPOCHS` epochs. A 0.3 m/s² bias moves z by
/// about 3σ in that second.
const IMU_RECENT_S: f64 = 1.0;
const IMU_CALM: f64 = 1.0;
const GATE: f64 = 2.5; // per-group R above which a sensor is withheld during a fault
/// Recovery after a coast: GPS increments agree with the filter's (RMS of
/// normalised consecutive Δr below this) while the offset is modest...
const RECOVER_INC: f64 = 2.0;
/// ...meaning the position departure R is below this: the offset is the
/// filter's own coast drift, so re-anchor on GPS. A larger static offset is
/// kept as a fault (a persisting step), until `maxCoast`.
const RECOVER_R: f64 = 4.0;
/// ...and the position–velocity statistic below this.
const RECOVER_PV: f64 = 2.0;
/// Baro consistency below which a withheld baro counts as following the
/// filter again (see `baro_row`).
const BARO_RECOVER: f64 = 1.5;
/// Epochs of agreement needed before recovering.
const RECOVER_EPOCHS: u32 = 5;
/// Receiver incoherence (RMS of u/σ_u, see `IndicatorEngine::incoherence`)
/// above which a receiver with a departed position loses its velocity too.
const INCOHERENT: f64 = 4.0;
const TRAIN_EPOCHS: usize = 5;
/// F above which a fault verdict (below which a normal one) enters D2 (D1).
const CONFIDENT_FAULT: f64 = 0.8;
const CONFIDENT_NORMAL: f64 = 0.2;
const TRAIN_LR: f64 = 0.05;
/// A retrain touches every sample of D1 ∪ D2 (to train) and of D0 (to
/// validate): W ≤ 2q + |D0| samples. It waits for at least W / this many new
/// D2 samples (and for TC), so the work per new sample is bounded whatever
/// q and TC are: with TC = 1 and q = 100 000 a retrain at every fault epoch
/// made an audit quadratic in the log's length. The default (TC 100, q 500,
/// |D0| 1000: W ≤ 2000) always meets it, so its verdicts do not change.
pub const RETRAIN_SAMPLES_PER_NEW: usize = 20;

/// What retraining has cost so far (not in snapshots): for the linear-cost
/// regression test and the bench.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RetrainCost {
    /// Retrains run (accepted or not).
    pub runs: u64,
    /// New D2 samples those retrains waited for.
    pub new_samples: u64,
    /// Samples they touched: |D1| + |D2| + |D0| each.
    pub samples: u64,
    /// Sample-operations: `TRAIN_EPOCHS` passes over D1 ∪ D2, two over D0.
    pub sample_ops: u64,
}

/// The streaming detector.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Detector {
    cfg: Config,
    anfis: Anfis,
    d1: Ring,
    d2: Ring,
    new_faults: usize,
    kf: Option<Kf>,
    anchor: Option<Anchor>,
    ind: IndicatorEngine,
    imu: Option<(f64, ImuInput)>,
    last_t: Option<f64>,
    last_fix_t: Option<f64>,
    fix_seen: bool,
    gps_dt: f64,
    /// Mean absolute deviation of the GPS interval, s (receiver jitter).
    gps_jitter: f64,
    /// This row's residuals (pos N/E/D m, vel N/E/D m/s, baro m); NaN where
    /// not computed on this row.
    resid: [f64; 7],
    prev_pos: Vector3<f64>,
    prev_vel: Vector3<f64>,
    prev_baro_h: Option<f64>,
    /// Previous GPS fix (t, position NED, velocity) for the consistency test.
    last_gps: Option<(f64, Vector3<f64>, Vector3<f64>)>,
    coast_start: Option<f64>,
    calm_epochs: u32,
    /// The current fault episode withheld the GPS velocity or was an
    /// outage: the filter has coasted on the IMU alone.
    receiver_lost: bool,
    /// Consecutive normal GPS verdicts.
    normal_run: u32,
    group_bad: [bool; GROUPS],
    /// The filter's vertical velocity integrated (altitude up, m), for the
    /// baro consistency test.
    alt_int: f64,
    /// The filter's IMU-predicted velocity changes summed (m/s), for the IMU
    /// consistency test; `imu_gap`: a prediction since the last GPS epoch ran
    /// without IMU.
    dv_imu: Vector3<f64>,
    imu_gap: bool,
    /// Time flown with the filter running, s: the IMU consistency test joins
    /// the decision once its σ has been learnt in flight.
    flight_time: f64,
    /// Inside a fault episode; `imu_episode`: the IMU consistency drove its
    /// first verdict. Any other episode restarts the IMU window at every
    /// epoch, so the GPS velocities of an outage or a GPS fault never sit in
    /// the window that judges the clean epochs after it.
    in_episode: bool,
    imu_episode: bool,
    /// Consecutive IMU-episode epochs whose last second was calm.
    imu_calm: u32,
    /// Consecutive baro samples consistent with the filter while withheld.
    baro_calm: u32,
    last: Output,
    last_ind: Indicators,
    stats: Stats,
    oracle: bool,
    /// Retraining scratch (contents do not outlive `retrain`).
    #[serde(skip)]
    train_x: Vec<[f64; 2]>,
    #[serde(skip)]
    train_y: Vec<f64>,
    /// The shipped model's databases D1₀ ∪ D2₀ (labels 0/1): the validation
    /// set a retrained ANFIS must not do worse on.
    d0_x: Vec<[f64; 2]>,
    d0_y: Vec<f64>,
    #[serde(skip)]
    retrain_cost: RetrainCost,
    /// Previous GPS epoch's innovations (pos, vel) for Δr; None after a
    /// (re)initialisation.
    prev_nu: Option<[f64; 6]>,
    /// Reference windows of the `mahalanobis` method (position, velocity).
    maha: [MahaWindow; 2],
    /// Largest-γ baro innovation (ν, S) since the last GPS epoch.
    baro_inn: Option<(f64, f64)>,
    /// Threshold pool of the `rms`, `knee` and `adaptive` methods.
    pool: Option<PoolState>,
}

impl Detector {
    /// Detector with the config's model, or the embedded default.
    pub fn new(cfg: Config) -> Result<Self, String> {
        let model = match &cfg.model {
            Some(m) => m.clone(),
            None => Model::embedded()?,
        };
        let pool = match cfg.method {
            Method::Rms | Method::Knee | Method::Adaptive => Some(methods::default_pool(cfg.method)?),
            _ => None,
        };
        let mut det = Self::with_model(cfg, &model);
        det.pool = pool;
        Ok(det)
    }

    pub fn with_model(cfg: Config, model: &Model) -> Self {
        let q = cfg.q;
        Detector {
            anfis: model.anfis.clone(),
            d1: Ring::new(q, &model.d1),
            d2: Ring::new(q, &model.d2),
            new_faults: 0,
            kf: None,
            anchor: None,
            ind: IndicatorEngine::new(cfg.indicator_settings()),
            imu: None,
            last_t: None,
            last_fix_t: None,
            fix_seen: false,
            gps_dt: 0.2,
            gps_jitter: 0.0,
            resid: [f64::NAN; 7],
            prev_pos: Vector3::zeros(),
            prev_vel: Vector3::zeros(),
            prev_baro_h: None,
            last_gps: None,
            coast_start: None,
            calm_epochs: 0,
            receiver_lost: false,
            normal_run: 0,
            group_bad: [false; GROUPS],
            alt_int: 0.0,
            dv_imu: Vector3::zeros(),
            imu_gap: true,
            flight_time: 0.0,
            in_episode: false,
            imu_episode: false,
            imu_calm: 0,
            baro_calm: 0,
            last: Output { kind: kind::NO_GPS, driver: 255, ..Output::default() },
            last_ind: Indicators::default(),
            stats: Stats::default(),
            oracle: false,
            train_x: Vec::with_capacity(2 * q),
            train_y: Vec::with_capacity(2 * q),
            d0_x: model.d1.iter().chain(model.d2.iter()).copied().collect(),
            d0_y: model.d1.iter().map(|_| 0.0).chain(model.d2.iter().map(|_| 1.0)).collect(),
            retrain_cost: RetrainCost::default(),
            prev_nu: None,
            maha: Default::default(),
            baro_inn: None,
            pool: None,
            cfg,
        }
    }

    /// After deserializing a snapshot: check the config and every buffer's
    /// shape against a fresh detector of that config (so a corrupt or forged
    /// snapshot is an error, not an index panic later), and restore the
    /// scratch buffers that snapshots do not carry.
    pub(crate) fn check_restored(&mut self) -> Result<(), String> {
        let checked = self.cfg.to_input().check()?;
        if checked != self.cfg {
            return Err("config does not validate to itself".into());
        }
        let q = self.cfg.q;
        self.d1.check_shape(q, "D1")?;
        self.d2.check_shape(q, "D2")?;
        self.ind.check_shape(&self.cfg.indicator_settings())?;
        if self.d0_x.len() != self.d0_y.len() {
            return Err(format!("D0: {} samples but {} labels", self.d0_x.len(), self.d0_y.len()));
        }
        crate::config::check_anfis(&self.anfis).map_err(|e| format!("anfis: {e}"))?;
        for w in &self.maha {
            w.check_shape()?;
        }
        let pooled = matches!(self.cfg.method, Method::Rms | Method::Knee | Method::Adaptive);
        match &self.pool {
            Some(p) if pooled => p.eval.check_shape()?,
            None if !pooled => {}
            _ => {
                return Err(format!(
                    "threshold pool present/absent does not match method \"{}\"",
                    self.cfg.method.name()
                ))
            }
        }
        self.train_x = Vec::with_capacity(2 * q);
        self.train_y = Vec::with_capacity(2 * q);
        Ok(())
    }

    #[cfg(all(test, not(target_arch = "wasm32")))]
    pub(crate) fn forge_ring_head_for_test(&mut self, head: usize) {
        self.d1.head = head;
    }

    /// Teacher forcing for building training data: decisions follow the
    /// row's `label` instead of the ANFIS (used by the model trainer only).
    pub fn set_oracle(&mut self, on: bool) {
        self.oracle = on;
    }

    pub fn config(&self) -> &Config {
        &self.cfg
    }

    pub fn stats(&self) -> Stats {
        self.stats
    }

    pub fn anfis(&self) -> &Anfis {
        &self.anfis
    }

    /// The local NED anchor (first valid fix), once known.
    pub fn anchor(&self) -> Option<Anchor> {
        self.anchor
    }

    /// Filter velocity estimate NED (m/s), once initialised.
    pub fn velocity(&self) -> Option<Vector3<f64>> {
        self.kf.as_ref().map(|k| k.velocity())
    }

    /// Filter accelerometer-bias estimate, body frame (m/s²), once initialised.
    pub fn accel_bias(&self) -> Option<Vector3<f64>> {
        self.kf.as_ref().map(|k| k.accel_bias())
    }

    /// Filter position estimate NED (m), once initialised.
    pub fn position(&self) -> Option<Vector3<f64>> {
        self.kf.as_ref().map(|k| k.position())
    }

    /// Residuals computed on the last pushed row: GPS position N/E/D (m),
    /// GPS velocity N/E/D (m/s), baro (m); NaN where that row had none.
    pub fn residuals(&self) -> [f64; 7] {
        self.resid
    }

    /// Latest indicators (per-group detail included).
    pub fn indicators(&self) -> Indicators {
        self.last_ind
    }

    /// Check a row without touching state. `row` is used for the message.
    pub fn validate(&self, s: &Sample, row: u64) -> Result<(), InputError> {
        validate_sample(s, row)?;
        if let Some(lt) = self.last_t {
            if s.t < lt {
                return Err(InputError {
                    row,
                    field: "t",
                    reason: format!("time goes backwards: {} after {}", s.t, lt),
                });
            }
        }
        Ok(())
    }

    /// Process one row. On `Err` nothing changed.
    pub fn push(&mut self, s: &Sample) -> Result<Output, InputError> {
        self.validate(s, self.stats.rows)?;
        Ok(self.push_valid(s))
    }

    /// Process a row already validated (see [`Detector::validate`]).
    pub fn push_valid(&mut self, s: &Sample) -> Output {
        self.stats.rows += 1;
        self.resid = [f64::NAN; 7];
        let t = s.t;
        let dt = self.last_t.map_or(0.0, |lt| t - lt);
        if self.last_t.is_some() && dt > self.cfg.data_gap {
            // Every sensor stopped: a logging gap, not a navigation fault.
            self.stats.data_gaps += 1;
            // No verdict carries across a gap: it starts from "no GPS yet".
            self.last = Output { kind: kind::NO_GPS, driver: 255, ..Output::default() };
            self.kf = None;
            self.imu = None;
            self.ind.reset_references();
            self.prev_baro_h = None;
            self.coast_start = None;
            self.group_bad = [false; GROUPS];
            if self.last_fix_t.is_some() {
                self.last_fix_t = Some(t);
            }
        }
        self.last_t = Some(t);

        // Predict to this row's time with the IMU held from the previous row.
        if dt > 0.0 {
            let imu = self.imu.filter(|(ti, _)| t - ti <= IMU_TIMEOUT).map(|(_, u)| u);
            if let Some(kf) = self.kf.as_mut() {
                let v0 = kf.velocity();
                match kf.predict(dt, imu.as_ref()) {
                    Ok(()) => {
                        let v1 = kf.velocity();
                        if kf_flying(kf) {
                            self.flight_time += dt;
                        }
                        self.alt_int -= 0.5 * (v0[2] + v1[2]) * dt;
                        if imu.is_some() {
                            self.dv_imu += v1 - v0;
                        } else {
                            self.imu_gap = true;
                        }
                    }
                    Err(e) => self.filter_failed(e),
                }
            }
        }
        if s.has_accel() && s.has_attitude() {
            if let Some(q) = quat_from_wxyz(s.qw, s.qx, s.qy, s.qz) {
                self.imu = Some((t, ImuInput { f_body: Vector3::new(s.ax, s.ay, s.az), q }));
                self.stats.imu_rows += 1;
            }
        }
        if s.has_baro() {
            self.stats.baro_rows += 1;
            self.baro_row(t, s.baro);
        }

        let mut out = if s.has_fix() {
            self.gps_epoch(s)
        } else {
            let mut o = self.last;
            o.gps_epoch = false;
            if self.is_outage(t, s) {
                o.status = 1;
                o.kind = kind::OUTAGE;
                o.f = 1.0;
                self.ind.clear_imu();
                self.in_episode = true;
                self.imu_episode = false;
                // The filter coasts; the first fix back is judged against it.
                self.receiver_lost = true;
                if self.coast_start.is_none() {
                    self.coast_start = self.last_fix_t;
                }
            } else if o.kind == kind::OUTAGE {
                o.status = 0;
                o.kind = kind::NORMAL;
            }
            o
        };
        out.t = t;
        self.last = out;
        out
    }

    /// Outage: after a fix has been seen, the receiver says it has none, or
    /// (flying) no fix arrived within the timeout; it lasts until the next
    /// fix. A receiver that reports losing its fix is an outage on the
    /// ground too; mere silence counts only in flight (logs often stop
    /// sending GPS after landing).
    fn is_outage(&self, t: f64, s: &Sample) -> bool {
        let Some(lf) = self.last_fix_t else {
            return false;
        };
        if !self.fix_seen {
            return false;
        }
        if self.last.kind == kind::OUTAGE {
            return true;
        }
        if s.reports_no_fix() && t - lf > 0.5 * self.gps_dt {
            return true;
        }
        // 1.5 periods, or more for a jittery receiver: a late fix is not an outage.
        let auto = (1.5 * self.gps_dt).max(self.gps_dt + 4.0 * self.gps_jitter) + 0.02;
        let timeout = self.cfg.outage_timeout.unwrap_or(auto);
        self.flying() && t - lf > timeout
    }

    /// Flying: moving faster than 1 m/s or more than 2 m above the anchor.
    fn flying(&self) -> bool {
        self.kf.as_ref().is_some_and(kf_flying)
    }

    fn filter_failed(&mut self, _e: FilterError) {
        // Re-initialise at the next fix; keep the verdict history.
        self.stats.filter_errors += 1;
        self.kf = None;
        self.ind.reset_references();
        self.prev_baro_h = None;
        self.imu_gap = true;
    }

    fn baro_row(&mut self, t: f64, baro: f64) {
        let Some(kf) = self.kf.as_mut() else { return };
        if !kf.baro_initialised() {
            if kf.update_baro(baro).is_ok() {
                self.prev_baro_h = Some(-kf.position()[2] + kf.x[9]);
            }
            return;
        }
        let inn = kf.baro_innovation(baro);
        self.resid[6] = inn.nu[0];
        let g = |(nu, s): (f64, f64)| nu.abs() / s.max(1e-12).sqrt();
        if self.baro_inn.is_none_or(|b| g((inn.nu[0], inn.s[0])) > g(b)) {
            self.baro_inn = Some((inn.nu[0], inn.s[0]));
        }
        let h_prior = -kf.x[2] + kf.x[9];
        let m = self.prev_baro_h.map_or(0.0, |p| h_prior - p);
        let prev = self.ind.previous(6);
        self.ind.observe(6, inn.nu[0], m, inn.s[0]);
        let cons = self.ind.observe_baro(t, baro - self.alt_int, self.group_bad[2]);
        if self.group_bad[2] {
            // Withheld baro that follows the filter's climb again (its change
            // since before the fault is consistent): the fault is over, but
            // the offset state absorbed part of it before detection, so
            // re-anchor the offset instead of judging the baro against it.
            self.baro_calm = if cons < BARO_RECOVER { self.baro_calm + 1 } else { 0 };
            if self.baro_calm >= RECOVER_EPOCHS {
                self.baro_calm = 0;
                self.group_bad[2] = false;
                kf.reset_baro();
                self.ind.reset_axis(6);
                self.ind.clear_baro();
                if kf.update_baro(baro).is_ok() {
                    self.prev_baro_h = Some(-kf.x[2] + kf.x[9]);
                }
                return;
            }
        } else {
            self.baro_calm = 0;
        }
        if !self.group_bad[2] {
            match kf.update_baro(baro) {
                Ok(()) => {
                    let p_post = kf.P[(2, 2)] + kf.P[(9, 9)] - 2.0 * kf.P[(2, 9)];
                    let post = kf.baro_innovation(baro).nu[0];
                    self.ind.accept(6, prev, p_post, post);
                    if self.last.status == 0 {
                        self.ind.accept_baro();
                    }
                }
                Err(e) => {
                    self.filter_failed(e);
                    return;
                }
            }
        }
        if let Some(kf) = self.kf.as_ref() {
            self.prev_baro_h = Some(-kf.x[2] + kf.x[9]);
        }
    }

    fn gps_epoch(&mut self, s: &Sample) -> Output {
        self.stats.gps_epochs += 1;
        let t = s.t;
        if let Some(lf) = self.last_fix_t {
            let d = t - lf;
            if d > 0.0 && d < 5.0 {
                // Learn the GPS period for the outage timeout.
                self.gps_jitter += 0.05 * ((d - self.gps_dt).abs() - self.gps_jitter);
                self.gps_dt += 0.05 * (d - self.gps_dt);
            }
        }
        let anchor = *self.anchor.get_or_insert_with(|| Anchor::from_sample(s));
        let y = anchor.to_ned(s);
        let vel = s.has_velocity().then(|| Vector3::new(s.vn, s.ve, s.vd));
        self.last_fix_t = Some(t);
        self.fix_seen = true;

        let Some(kf) = self.kf.as_mut() else {
            let noise = self.cfg.filter_noise();
            let v0 = vel.unwrap_or_else(Vector3::zeros);
            let vs = if vel.is_some() { noise.gps_vel } else { 3.0 };
            self.kf = Some(Kf::new(noise, y, v0, noise.gps_pos_h, vs));
            self.prev_pos = y;
            self.prev_vel = v0;
            self.ind.reset_references();
            self.imu_gap = true;
            self.coast_start = None;
            self.prev_nu = None;
            return Output { t, status: 0, f: 0.0, r: 0.0, c: 0.0, kind: kind::NORMAL, gps_epoch: true, driver: 255 };
        };

        // Residuals and predicted changes since the last epoch.
        let pin = kf.position_innovation(&y);
        self.resid[..3].copy_from_slice(&pin.nu);
        let pos_prior = kf.position();
        let mut prev_r = [0.0; 6];
        for a in 0..3 {
            prev_r[a] = self.ind.previous(a);
            self.ind.observe(a, pin.nu[a], pos_prior[a] - self.prev_pos[a], kf.P[(a, a)]);
        }
        let vel_prior = kf.velocity();
        let mut vin_opt = None;
        if let Some(v) = &vel {
            let vin = kf.velocity_innovation(v);
            vin_opt = Some(vin);
            self.resid[3..6].copy_from_slice(&vin.nu);
            for a in 0..3 {
                prev_r[3 + a] = self.ind.previous(3 + a);
                self.ind.observe(3 + a, vin.nu[a], vel_prior[a] - self.prev_vel[a], kf.P[(3 + a, 3 + a)]);
            }
        }
        // Position–velocity consistency: the GPS's own position change
        // against the trapezoid of its velocities (filter-independent).
        // Not while the velocity is withheld: a biased velocity (degraded
        // fix, frozen or zeroed output) would fill the window with its own
        // bias and hold the test up after it clears.
        match (&vel, self.last_gps) {
            (Some(v), Some((pt, pp, pv))) if t - pt > 0.0 && t - pt < 1.0 => {
                let dtg = t - pt;
                let u = core::array::from_fn(|a| (y[a] - pp[a]) - 0.5 * (v[a] + pv[a]) * dtg);
                self.ind.observe_pv(u, !self.group_bad[1]);
            }
            _ => self.ind.clear_pv(),
        }
        self.last_gps = vel.map(|v| (t, y, v));
        // IMU consistency: GPS horizontal velocity against the filter's
        // IMU-predicted velocity changes, only while every prediction since
        // the last epoch ran on the IMU.
        if self.imu_gap {
            self.ind.clear_imu();
            self.imu_gap = false;
        }
        match &vel {
            Some(v) => self.ind.observe_imu(t, [v[0] - self.dv_imu[0], v[1] - self.dv_imu[1]]),
            None => self.ind.clear_imu(),
        }
        self.ind.set_imu_fold(self.flight_time >= IMU_ARM_S && self.ind.imu_learnt() >= IMU_ARM_WINDOWS);
        let ind = self.ind.close_epoch();
        self.last_ind = ind;
        let x = inputs(ind.r, ind.c);
        let f_anfis = self.anfis.eval(&x);
        // Another method's decision on the same innovations (see `methods`);
        // nothing to build for the default ANFIS.
        let baro_inn = self.baro_inn.take();
        let mut dr = [[f64::NAN; 3]; 2];
        let dec: Option<Decision> = if self.cfg.method == Method::Anfis {
            None
        } else {
            let mut nu = [f64::NAN; 6];
            nu[..3].copy_from_slice(&pin.nu);
            let mut inn = EpochInnovations { nu, s: kf.P.fixed_view::<6, 6>(0, 0).into_owned(), m: 3, baro: baro_inn };
            for a in 0..3 {
                inn.s[(a, a)] = pin.s[a];
            }
            if let Some(vin) = &vin_opt {
                inn.m = 6;
                for a in 0..3 {
                    inn.nu[3 + a] = vin.nu[a];
                    inn.s[(3 + a, 3 + a)] = vin.s[a];
                }
            }
            dr = core::array::from_fn(|g| {
                core::array::from_fn(|a| self.prev_nu.map_or(f64::NAN, |p| inn.nu[3 * g + a] - p[3 * g + a]))
            });
            self.prev_nu = Some(inn.nu);
            match self.cfg.method {
                Method::Anfis => None,
                Method::Chi2 => Some(methods::chi2(&inn)),
                Method::Nis => Some(methods::nis(&inn)),
                Method::Gate => Some(methods::gate(&inn)),
                Method::Mahalanobis => Some(methods::mahalanobis(&self.maha, dr, inn.m == 6)),
                Method::Rms | Method::Knee | Method::Adaptive => {
                    let v = kf.velocity();
                    let speed = v[0].hypot(v[1]);
                    self.pool.as_mut().map(|p| p.decide(&inn, speed))
                }
            }
        };
        let f = dec.map_or(f_anfis, |d| d.score);
        let th = if dec.is_some() { 1.0 } else { self.cfg.threshold };
        let mut fault = if self.oracle { s.label >= 0.5 } else { f >= th };
        if fault {
            if !self.in_episode {
                self.in_episode = true;
                // The IMU test alone: no other group departed (a zeroed or
                // frozen GPS velocity also fails it, but the Δr test sees it too).
                self.imu_episode = self.ind.imu_folded() && self.ind.r_unfolded() < GATE;
            }
            if !self.imu_episode {
                self.ind.clear_imu();
            } else if !self.oracle && self.ind.r_unfolded() < GATE {
                // The 3 s window still spans the fault for 3 s after it
                // ends; the last second says sooner whether z still drifts.
                // Calm for a few epochs: the episode is over, and the window
                // restarts on post-fault data.
                let calm = self.ind.imu_recent(IMU_RECENT_S) < IMU_CALM;
                self.imu_calm = if calm { self.imu_calm + 1 } else { 0 };
                if self.imu_calm >= RECOVER_EPOCHS {
                    fault = false;
                    self.ind.clear_imu();
                }
            }
        }
        if !fault {
            self.in_episode = false;
            self.imu_episode = false;
            self.imu_calm = 0;
        }
        // While the IMU is the suspect, its bias estimate is not learnt from
        // the fault (or the test would see the learnt error after it ends).
        kf.set_hold_bias(self.imu_episode);

        // Gate: during a fault, withhold the sensors that departed. GPS
        // position and velocity come from one receiver and go together.
        let mut reset = false;
        if fault {
            let start = *self.coast_start.get_or_insert(t);
            if t - start > self.cfg.max_coast {
                reset = true;
            }
            // The IMU consistency condemns the IMU, not the GPS: the GPS
            // velocity is withheld on its own departure only.
            let r_vel = self.ind.r_vel_unfolded();
            let bad = |g: usize| {
                let r = if g == 1 { r_vel } else { ind.r_group[g] };
                r.is_finite() && r > GATE
            };
            // Fault memory: a group that departed stays withheld for the rest
            // of the episode, so a fault that flickers around the gate cannot
            // leak into the filter; a group that never departed (GPS velocity
            // during a position step or ramp) keeps aiding it, which keeps the
            // coast drift, and so the departure's normalisation, small.
            for g in 0..GROUPS {
                self.group_bad[g] |= bad(g);
            }
            // A group that failed the method's own test is withheld too.
            if let Some(d) = &dec {
                for g in 0..GROUPS {
                    self.group_bad[g] |= d.failed[g];
                }
            }
            if self.group_bad[1] && !self.group_bad[0] && ind.r_group[0] > 1.5 {
                // Bad GPS velocity with a position residual off its clean
                // level: same receiver, do not let it re-anchor the estimate.
                self.group_bad[0] = true;
            }
            if self.group_bad[0] && self.ind.incoherence() > INCOHERENT {
                // Position departed and the receiver's own position and
                // velocity disagree epoch after epoch: its velocity is no
                // better than its position (degraded fix).
                self.group_bad[1] = true;
            }
            self.normal_run = 0;
            if self.group_bad[1] {
                self.receiver_lost = true;
            }
            // When the whole receiver was withheld (outage, degraded fix) the
            // filter coasted on the IMU alone and the position offset is its
            // own drift, whatever its size: recover on agreement of the
            // increments and a clean velocity. When only the position was
            // withheld (velocity kept aiding), a large offset is the fault
            // itself (a persisting step) and is kept until `maxCoast`.
            // A position-only episode also needs the position–velocity test
            // back in its clean range, so a ramp that paused the verdict is
            // not re-anchored on.
            let offset_ok = if self.receiver_lost {
                !(ind.r_group[1] > RECOVER_R)
            } else {
                !(ind.r_group[0] > RECOVER_R) && !(ind.pv > RECOVER_PV)
            };
            let calm = (0..2).all(|g| !(ind.inc_group[g] > RECOVER_INC)) && offset_ok && !bad(2);
            self.calm_epochs = if calm { self.calm_epochs + 1 } else { 0 };
            // An IMU episode ends when the IMU agrees with the GPS again, not
            // by re-anchoring on a GPS that never departed.
            if !self.oracle && !self.imu_episode && self.calm_epochs >= RECOVER_EPOCHS && t - start > 0.5 {
                // The GPS is self-consistent again and the offset is within
                // what the coast could have drifted: re-anchor, verdict normal.
                reset = true;
                fault = false;
            }
        } else {
            self.calm_epochs = 0;
            self.coast_start = None;
            self.group_bad = [false; GROUPS];
            // A single normal verdict inside a coast does not end it: the
            // filter's offset is still the coast's until the GPS has been
            // accepted for a few epochs.
            self.normal_run += 1;
            if self.normal_run >= RECOVER_EPOCHS {
                self.receiver_lost = false;
            }
        }
        let mut err = None;
        if reset {
            // Coasted too long to judge (or recovered): re-anchor on GPS.
            kf.reset_to(&y, vel.as_ref());
            self.stats.filter_resets += 1;
            self.coast_start = None;
            self.calm_epochs = 0;
            self.group_bad = [false; GROUPS];
            self.receiver_lost = false;
            self.ind.reset_references();
            self.prev_baro_h = None;
            self.prev_nu = None;
        } else {
            if !self.group_bad[0] {
                match kf.update_position(&y) {
                    Ok(()) => {
                        for a in 0..3 {
                            let post = y[a] - kf.x[a];
                            self.ind.accept(a, prev_r[a], kf.P[(a, a)], post);
                        }
                    }
                    Err(e) => err = Some(e),
                }
            }
            if let (Some(v), false, None) = (&vel, self.group_bad[1], &err) {
                match kf.update_velocity(v) {
                    Ok(()) => {
                        for a in 0..3 {
                            let post = v[a] - kf.x[3 + a];
                            self.ind.accept(3 + a, prev_r[3 + a], kf.P[(3 + a, 3 + a)], post);
                        }
                    }
                    Err(e) => err = Some(e),
                }
            }
        }
        self.prev_pos = kf.position();
        self.prev_vel = kf.velocity();
        if let Some(e) = err {
            self.filter_failed(e);
        }

        // Online cycle: file this epoch by its own verdict (eqs. 15–20), but
        // only a confident one: a fault verdict with F ≥ 0.8 and a fault
        // signature, a normal one with F ≤ 0.2. Borderline verdicts, where a
        // false alarm would sit, are not fed back, so retraining cannot
        // teach itself its own mistakes.
        let anfis = dec.is_none();
        if fault {
            if anfis && f >= CONFIDENT_FAULT && has_signature(ind.r, ind.c) {
                self.d2.push(x);
                self.new_faults += 1;
            }
            if anfis && self.cfg.retrain && !self.oracle && self.retrain_due() {
                self.retrain();
            }
        } else {
            if anfis && f <= CONFIDENT_NORMAL {
                self.d1.push(x);
            }
            if self.cfg.method == Method::Mahalanobis {
                for g in 0..2 {
                    self.maha[g].push(dr[g]);
                }
            }
            self.ind.accept_pv();
            if self.flying() {
                self.ind.accept_imu();
            }
        }
        let driver = ind.r_driver().map_or(255, |g| g as u8);
        Output {
            t,
            status: fault as u8,
            f,
            r: ind.r,
            c: ind.c,
            kind: if fault { kind::RESIDUAL } else { kind::NORMAL },
            gps_epoch: true,
            driver,
        }
    }

    /// Retrain the ANFIS on D1 ∪ D2 (hybrid learning). Keeps the old model
    /// if training produces anything non-finite, or if the candidate
    /// misclassifies more of D0 (the shipped model's own databases) than the
    /// current one: online data may drift, but not so far that the detector
    /// forgets the labelled faults it shipped with.
    pub fn retrain(&mut self) {
        let w = self.retrain_samples();
        let c = &mut self.retrain_cost;
        c.runs += 1;
        c.new_samples += self.new_faults as u64;
        c.samples += w as u64;
        c.sample_ops += (TRAIN_EPOCHS * (self.d1.items().len() + self.d2.items().len()) + 2 * self.d0_x.len()) as u64;
        self.new_faults = 0;
        self.train_x.clear();
        self.train_y.clear();
        for x in self.d1.items() {
            self.train_x.push(*x);
            self.train_y.push(0.0);
        }
        for x in self.d2.items() {
            self.train_x.push(*x);
            self.train_y.push(1.0);
        }
        let mut cand = self.anfis.clone();
        cand.train_hybrid(&self.train_x, &self.train_y, TRAIN_EPOCHS, TRAIN_LR);
        // Validation on D0: the candidate must classify the shipped model's
        // databases at least as well as the current ANFIS does.
        if cand.is_finite() && self.d0_errors(&cand) <= self.d0_errors(&self.anfis) {
            self.anfis = cand;
            self.stats.retrains += 1;
        }
    }

    /// TC new D2 samples, and enough of them to pay for the retrain (see
    /// [`RETRAIN_SAMPLES_PER_NEW`]).
    fn retrain_due(&self) -> bool {
        self.new_faults >= self.cfg.tc && self.new_faults.saturating_mul(RETRAIN_SAMPLES_PER_NEW) >= self.retrain_samples()
    }

    /// Samples one retrain touches: D1 ∪ D2 and D0.
    fn retrain_samples(&self) -> usize {
        self.d1.items().len() + self.d2.items().len() + self.d0_x.len()
    }

    /// What retraining has cost so far.
    pub fn retrain_cost(&self) -> RetrainCost {
        self.retrain_cost
    }

    /// Misclassified D0 samples at the configured threshold.
    fn d0_errors(&self, a: &Anfis) -> usize {
        let th = self.cfg.threshold;
        self.d0_x.iter().zip(&self.d0_y).filter(|(x, y)| (a.eval(x) >= th) != (**y >= 0.5)).count()
    }
}

const GROUPS_ALL_OR_NONE: [[usize; 3]; 5] = [[1, 2, 3], [4, 5, 6], [7, 8, 9], [14, 15, 16], [17, 18, 19]];

/// Flying: moving faster than 1 m/s or more than 2 m above the anchor.
fn kf_flying(kf: &Kf) -> bool {
    kf.velocity().norm() > 1.0 || -kf.position()[2] > 2.0
}

/// `range_of` per column as a table, for the fast path.
const RANGES: [(f64, f64); 25] = {
    let mut a = [(0.0, 0.0); 25];
    let mut i = 0;
    while i < 25 {
        a[i] = range_of(i);
        i += 1;
    }
    a
};

/// Valid ranges per column: a value outside is an input error.
const fn range_of(i: usize) -> (f64, f64) {
    match i {
        0 => (-1e12, 1e12),           // t, s
        1 => (-90.0, 90.0),           // lat
        2 => (-180.0, 180.0),         // lon
        3 => (-2000.0, 1e5),          // alt, m
        4..=6 => (-1e7, 1e7),         // pn/pe/pd, m
        7..=9 => (-2000.0, 2000.0),   // velocity, m/s
        10 => (0.0, 100.0),           // fix
        11 => (0.0, 1000.0),          // sats
        12 | 13 => (0.0, 1e12),       // eph/epv, m
        14..=16 => (-2000.0, 2000.0), // accel, m/s²
        17..=19 => (-200.0, 200.0),   // gyro, rad/s
        20..=23 => (-2.0, 2.0),       // quaternion
        24 => (-2000.0, 1e5),         // baro, m
        _ => (f64::NEG_INFINITY, f64::INFINITY),
    }
}

/// The common case in one branch-free pass: every value NaN or inside its
/// range (an infinity is outside every range), `t` present, and every
/// three-axis group and the quaternion all present or all absent. Rows that
/// fail it go through [`validate_sample`]'s detailed checks for the message.
#[inline]
fn row_is_plainly_valid(s: &Sample) -> bool {
    let v = [
        s.t, s.lat, s.lon, s.alt, s.pn, s.pe, s.pd, s.vn, s.ve, s.vd, s.fix, s.sats, s.eph, s.epv, s.ax, s.ay, s.az,
        s.gx, s.gy, s.gz, s.qw, s.qx, s.qy, s.qz, s.baro,
    ];
    let mut ok = !v[0].is_nan();
    for i in 0..25 {
        ok &= v[i].is_nan() | ((v[i] >= RANGES[i].0) & (v[i] <= RANGES[i].1));
    }
    let nan = |i: usize| v[i].is_nan() as u8;
    let group = |a: usize, n: usize| {
        let c: u8 = (a..a + n).map(nan).sum();
        c == 0 || c as usize == n
    };
    ok &= !s.label.is_infinite();
    ok && group(1, 3) && group(4, 3) && group(7, 3) && group(14, 3) && group(17, 3) && group(20, 4)
}

/// Check one row: `t` present and finite, no infinities, every value in its
/// range, sensor groups complete (all three axes or none).
pub fn validate_sample(s: &Sample, row: u64) -> Result<(), InputError> {
    if row_is_plainly_valid(s) && (s.qw.is_nan() || quat_from_wxyz(s.qw, s.qx, s.qy, s.qz).is_some()) {
        return Ok(());
    }
    validate_detailed(s, row)
}

/// The checks one by one, naming the first field that fails.
fn validate_detailed(s: &Sample, row: u64) -> Result<(), InputError> {
    use crate::sample::COLUMNS;
    if !s.t.is_finite() {
        return Err(InputError { row, field: "t", reason: format!("required and must be finite, got {}", s.t) });
    }
    for (i, name) in COLUMNS.iter().enumerate() {
        let v = s.get(i);
        if v.is_nan() {
            continue;
        }
        let (lo, hi) = range_of(i);
        if !v.is_finite() || v < lo || v > hi {
            return Err(InputError { row, field: name, reason: format!("value {v} outside [{lo}, {hi}]") });
        }
    }
    for g in GROUPS_ALL_OR_NONE.iter().map(|g| g.as_slice()).chain(core::iter::once([20usize, 21, 22, 23].as_slice())) {
        let present = g.iter().filter(|&&i| !s.get(i).is_nan()).count();
        if present != 0 && present != g.len() {
            let missing = g.iter().find(|&&i| s.get(i).is_nan()).copied().unwrap_or(g[0]);
            let have = g.iter().find(|&&i| !s.get(i).is_nan()).copied().unwrap_or(g[0]);
            return Err(InputError {
                row,
                field: COLUMNS[missing],
                reason: format!("missing (NaN) while '{}' is present", COLUMNS[have]),
            });
        }
    }
    if s.has_attitude() && quat_from_wxyz(s.qw, s.qx, s.qy, s.qz).is_none() {
        return Err(InputError { row, field: "qw", reason: "quaternion norm must be near 1".into() });
    }
    Ok(())
}

#[cfg(all(test, not(target_arch = "wasm32")))]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A bad or edge value for column `i`: the bounds, just outside them,
    /// the infinities, NaN.
    fn edge(i: usize, k: usize) -> f64 {
        let (lo, hi) = range_of(i);
        [lo, hi, lo - 1.0, hi + 1.0, f64::INFINITY, f64::NEG_INFINITY, f64::NAN][k % 7]
    }

    proptest! {
        /// The fast path accepts exactly the rows the field-by-field checks
        /// accept: a valid row (each sensor group present or absent, a unit
        /// quaternion) with up to three fields set to edge values.
        #[test]
        fn fast_validation_agrees_with_the_detailed_checks(
            present in proptest::collection::vec(any::<bool>(), 8),
            vals in proptest::collection::vec(-1.0f64..1.0, 26),
            edits in proptest::collection::vec((0..26usize, 0..7usize), 0..4),
        ) {
            let mut s = Sample::at(10.0);
            // Groups: lat/lon/alt, pn/pe/pd, v, accel, gyro, quaternion, then
            // single columns fix..epv and baro, label.
            let groups: [&[usize]; 8] = [&[1, 2, 3], &[4, 5, 6], &[7, 8, 9], &[14, 15, 16], &[17, 18, 19], &[20, 21, 22, 23], &[10, 11, 12, 13], &[24, 25]];
            for (g, cols) in groups.iter().enumerate() {
                if present[g] {
                    for &c in cols.iter() {
                        let (lo, hi) = range_of(c);
                        let (lo, hi) = (lo.max(-1e3), hi.min(1e3));
                        s.set(c, 0.5 * (lo + hi) + 0.5 * (hi - lo) * vals[c]);
                    }
                }
            }
            if present[5] {
                let n = (s.qw * s.qw + s.qx * s.qx + s.qy * s.qy + s.qz * s.qz).sqrt().max(1e-3);
                (s.qw, s.qx, s.qy, s.qz) = (s.qw / n, s.qx / n, s.qy / n, s.qz / n);
            }
            prop_assert!(validate_sample(&s, 7).is_ok() && validate_detailed(&s, 7).is_ok(), "{:?}", s);
            for (c, k) in edits {
                s.set(c, edge(c, k));
            }
            prop_assert_eq!(validate_sample(&s, 7).is_ok(), validate_detailed(&s, 7).is_ok(), "{:?}", s);
        }
    }

    #[test]
    fn a_unit_quaternion_row_passes_and_a_half_quaternion_fails() {
        let mut s = Sample::at(1.0);
        (s.qw, s.qx, s.qy, s.qz) = (1.0, 0.0, 0.0, 0.0);
        assert!(validate_sample(&s, 0).is_ok());
        s.qy = f64::NAN;
        let e = validate_sample(&s, 3).unwrap_err();
        assert_eq!((e.row, e.field), (3, "qy"));
        (s.qw, s.qx, s.qy, s.qz) = (0.3, 0.0, 0.0, 0.0);
        assert_eq!(validate_sample(&s, 0).unwrap_err().field, "qw");
    }
}
