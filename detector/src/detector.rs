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
//!
//! Layout: a GPS epoch runs as named stages (residuals, tests, decision,
//! episode, gating, filter update, learning; see `Detector::gps_epoch`),
//! each a method on the small state it reads and writes: `Clock` (row and
//! fix timing, the outage rule), `LastEstimate` (where the filter stood,
//! the residuals stage), `Consistency` (the filter-independent tests'
//! integrals, the tests stage), `Methods` (the decision), `Episode` and its
//! `Withheld` groups (episode start and end, gating), and `Learning` (the
//! ANFIS and its databases).

use crate::MinMax;
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::anfis::{inputs, Anfis};
use crate::config::Config;
use crate::barojump::{BaroJump, BARO_JUMP_AGREE};
use crate::drift::{DriftTest, Motion, K_CLIMB, K_DYN};
use crate::ramp::RampTest;
use crate::filter::{quat_from_wxyz, FilterError, ImuInput, Innovation, Kf};
use crate::frames::Anchor;
use crate::indicators::{IndicatorEngine, Indicators, GROUPS};
use crate::methods::{self, Decision, EpochInnovations, MahaWindow, Method, PoolState};
pub use crate::model::{has_signature, Model};
use crate::sample::{range_of, Sample};
use navguard_logs::decimal::Shortest;
use crate::dragend::DragEnds;
use crate::flatline::{self, Flatline};
use crate::track::{undoes, VelocityTrack};

/// What kind of verdict a row carries.
pub mod kind {
    /// Normal: the epoch's sensors agree.
    pub const NORMAL: u8 = 0;
    /// Residual-based fault (ANFIS).
    pub const RESIDUAL: u8 = 1;
    /// GPS outage: no fix while flying.
    pub const OUTAGE: u8 = 2;
    /// No verdict possible: no GPS fix seen yet (or since a data gap).
    pub const NO_GPS: u8 = 3;
    /// GPS output frozen: while flying, every fix for longer than an
    /// outage takes repeated the last new one bit for bit (see
    /// `Clock::fresh`).
    pub const STALE: u8 = 4;
    /// GPS degraded by the receiver's own word: a 2D fix, four satellites
    /// or fewer, or an accuracy claim `QUALITY_DECLARED` times its usual
    /// (see `ReceiverQuality::declares_degraded`).
    pub const DEGRADED: u8 = 5;
    /// No verdict possible: the vehicle is upset (tilted past 90°, a crash
    /// or a flip) or was within the last `UPSET_HOLD_S`. The strapdown
    /// prediction cannot judge the sensors then, and every GPS epoch
    /// re-anchors the filter. Status 0, as for [`NO_GPS`].
    pub const UPSET: u8 = 6;
}

/// Tilt beyond which the vehicle is upset: the cosine of the angle between
/// the body's down axis and the local down (90°: the down axis horizontal
/// or above it). No flight the battery draws banks past 50°; the real
/// crashes in the shared logs reach 134–177°.
const UPSET_COS_TILT: f64 = 0.0;
/// Verdicts stay suspended this long after the last upset IMU sample, s: a
/// crash tumbles on (the shared ArduCopter crashes: from the first sample
/// past 90° to the autopilot's CRASH_CHECK, 2.3–3.7 s).
const UPSET_HOLD_S: f64 = 5.0;

/// Per-row output.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Output {
    /// Row time, s (the boot clock of the input).
    pub t: f64,
    /// 0 normal, 1 fault.
    pub status: u8,
    /// F-indicator.
    pub f: f64,
    /// R-indicator: the largest per-group residual ratio (≈ 1 clean).
    pub r: f64,
    /// C-indicator: the residual–Δr correlation (Pearson, ≈ 0.2 clean).
    pub c: f64,
    /// See [`kind`].
    pub kind: u8,
    /// Whether this row was a GPS epoch (a fix was evaluated).
    pub gps_epoch: bool,
    /// What drove R (0 GPS position, 1 GPS velocity, 2 baro, 3 the IMU
    /// through the IMU–GPS velocity consistency, 255 none).
    pub driver: u8,
}

/// A batch's outputs as columns (see [`Detector::push_valid_batch`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct OutputColumns {
    /// [`Output::status`] per row.
    pub status: Vec<u8>,
    /// [`Output::kind`] per row.
    pub kind: Vec<u8>,
    /// [`Output::f`] per row.
    pub f: Vec<f64>,
    /// [`Output::r`] per row.
    pub r: Vec<f64>,
    /// [`Output::c`] per row.
    pub c: Vec<f64>,
}

impl OutputColumns {
    /// Empty every column (keeping their capacity).
    pub fn clear(&mut self) {
        self.status.clear();
        self.kind.clear();
        self.f.clear();
        self.r.clear();
        self.c.clear();
    }
}

/// Rows `0..n` of columns in [`COLUMNS`](crate::sample::COLUMNS) order
/// (a short column reads as NaN) into `rows`, replacing its contents; and
/// one row from values in that order. Here, not in the wasm facade that
/// uses them, so they run at the row path's opt-level.
#[inline(never)] // see `Detector::validate`
pub fn rows_from_columns(cols: &[&[f64]; crate::sample::COLUMNS.len()], n: usize, rows: &mut Vec<Sample>) {
    rows.clear();
    rows.extend((0..n).map(|j| Sample::from_columns(cols, j)));
}

/// Column `i` (in [`COLUMNS`](crate::sample::COLUMNS) order) of `rows` into
/// `out`, replacing its contents; false (and `out` untouched) when every
/// value in it is NaN (absent). For `readLog`'s columns, here for the same
/// reason as [`rows_from_columns`].
#[inline(never)]
pub fn column_of_rows(rows: &[Sample], i: usize, out: &mut Vec<f64>) -> bool {
    if !rows.iter().any(|s| !s.get(i).is_nan()) {
        return false;
    }
    out.clear();
    out.extend(rows.iter().map(|s| s.get(i)));
    true
}

/// One row from its values in [`COLUMNS`](crate::sample::COLUMNS) order
/// (see [`rows_from_columns`]; missing values read as NaN).
#[inline(never)] // see `Detector::validate`
pub fn row_from_values(values: &[f64]) -> Sample {
    row_of(values)
}

#[inline]
fn row_of(values: &[f64]) -> Sample {
    let mut s = Sample::default();
    for (i, v) in values.iter().take(crate::sample::COLUMNS.len()).enumerate() {
        s.set(i, *v);
    }
    s
}

/// Bad input: names the row and the field.
#[derive(Clone, Debug, PartialEq)]
pub struct InputError {
    /// Row number (0-based) of the rejected sample.
    pub row: u64,
    /// The column at fault.
    pub field: &'static str,
    /// Why the value was rejected.
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
    /// Rows pushed.
    pub rows: u64,
    /// GPS epochs judged (rows with a new fix).
    pub gps_epochs: u64,
    /// Rows with a usable IMU sample (specific force and attitude).
    pub imu_rows: u64,
    /// Rows with a barometer sample.
    pub baro_rows: u64,
    /// ANFIS retrainings so far (every TC fault samples).
    pub retrains: u64,
    /// Times the filter was re-anchored on a fix.
    pub filter_resets: u64,
    /// Logging gaps (every sensor silent longer than `dataGap`).
    pub data_gaps: u64,
    /// Filter updates that failed numerically (the filter restarts).
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
    #[cfg_attr(navguard_cold_size, optimize(size))]
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
use crate::indicators::{IMU_ARM_WINDOWS, IMU_CALL};
/// The IMU consistency judges only an IMU logged at least this often, s
/// between samples (25 Hz): sparser records are snapshots of a fast sensor
/// that integrate a turn's changing acceleration poorly (the shared
/// ArduPlane log's 10 Hz IMU: 4 `imu` intervals, 7.2 s, on healthy banked
/// legs at 12–16 m/s). The battery's IMUs run at 50–400 Hz.
const IMU_MAX_PERIOD_S: f64 = 0.04;
/// s: time constant of the IMU's sample interval estimate.
const IMU_PERIOD_TAU_S: f64 = 5.0;
/// An IMU episode ends when z's change over the last `IMU_RECENT_S` s stays
/// below `IMU_CALM` σ for `RECOVER_EPOCHS` epochs. A 0.3 m/s² bias moves z by
/// about 3σ in that second.
const IMU_RECENT_S: f64 = 1.0;
const IMU_CALM: f64 = 1.0;
/// s: the shortest silence of the receiver read as an outage (see
/// `Clock::is_outage`).
const SILENT_OUTAGE_S: f64 = 1.5;
/// s: the longest a position-only episode (the GPS velocity still aiding
/// the estimate) is judged before the estimate re-anchors on the GPS. Its
/// reference, the GPS velocity integrated, drifts slowly, so it can judge a
/// persisting step longer than an IMU-only coast (`maxCoast`). Why not
/// longer: on the randomised battery's eval split, 120 s (with the
/// position–velocity sum held through the episode) kept false episodes
/// going as long as real ones (accuracy 0.771, clean flights 11.0%
/// flagged), while 60 s without the hold gave 0.831 and 6.5%, and the same
/// 3 of 6 60 s steps passed.
const POSITION_COAST_S: f64 = 60.0;
/// s: the same for a position-only episode whose opening jump was shown
/// not to be a drag-off's end (`DragEnds::ruled_out`): the velocity did
/// not shift along the jump by the rate a drag as old as the flight would
/// need, so the jump is a step's onset, and a step lasts as long as it
/// lasts (battery: 10–20 m steps of 60–120 s flagged for their first
/// 60 s). The longest fault the battery draws is 120 s; beyond this the
/// fix is re-anchored onto and its offset kept (`Episode::accepted`).
const POSITION_COAST_LONG_S: f64 = 120.0;
/// A return jump must undo an offset of at least this many σ_Δ...
const RETURN_MIN_SIGMAS: f64 = 6.0;
// ...and, along the offset's direction, between `track::RETURN_UNDONE`
// shares of it (`track::undoes`: a return to where the GPS was before, up
// to the coast's drift; the tracks' return to their origin is judged the
// same way).
/// An episode that ends with the fix this many σ (along the offset; σ the
/// larger of σ_Δ and the position's wander about its velocity track) off
/// the coasted filter keeps the offset (`Episode::ended_off_track`).
/// Lower than `RETURN_MIN_SIGMAS`: keeping one only lets a later jump
/// that undoes it end a fault, and a 15.6 m vertical step under a 1 Hz
/// receiver is 5.4 σ_Δ (battery tune #551).
const KEEP_MIN_SIGMAS: f64 = 4.0;
/// An episode opened on the fix's short mean (`Episode::mean_hold`) holds
/// while that mean stays this many of its σ off the velocity track; the
/// scale puts `MEAN_KEEP` just above the ANFIS boundary, as
/// `HOLD_R_SCALE` does for the per-fix hold.
const MEAN_KEEP: f64 = 4.0;
const MEAN_HOLD_R_SCALE: f64 = 2.8 / MEAN_KEEP;
/// A position-only episode's offset (`Episode::off_sigmas`) into the
/// position group's R: `KEEP_MIN_SIGMAS` lands just above the ANFIS
/// boundary (R ≈ 2.55), so an offset the episode's end would keep holds
/// the episode.
const HOLD_R_SCALE: f64 = 2.8 / KEEP_MIN_SIGMAS;
/// s: time constant of the learnt accelerometer noise.
const IMU_PSD_TAU: f64 = 2.0;
const GATE: f64 = 2.5; // per-group R above which a sensor is withheld during a fault
/// The altitude vote's call, in σ on both references (see
/// `Consistency::altitude_vote`), and its scale into the position group's
/// R: the call lands just above the ANFIS boundary (R ≈ 2.55).
const VOTE_Z: f64 = 4.0;
const VOTE_R_SCALE: f64 = 2.8 / VOTE_Z;
/// Share of a called departure that may remain when both references jump
/// back: the fault's end.
const VOTE_BACK: f64 = 0.5;
/// The baro drift statistic's scale into the baro group's R: its hold level
/// (`drift::DRIFT_Z`) lands just above the ANFIS boundary (R ≈ 2.55).
const DRIFT_R_SCALE: f64 = 2.8 / crate::drift::DRIFT_Z;
/// A drift whose statistic stopped growing (`drift::PLATEAU_S`) is
/// released only when the baro's levels see it within this share of their
/// own hold bar (`held_departure`: 2.5σ off its Doppler level): the
/// change it held is then one the levels learnt as the baro's wander (a
/// fixed wing's static port at a new airspeed, battery tune #1207), not a
/// baro step the levels still see (battery eval #27: 12.7 m for 79 s,
/// held at about 1).
const PLATEAU_HELD: f64 = 0.5;
/// The fix's jump off its velocity track (`VelocityTrack::departed`, 1 at
/// `track::FAR` σ) into the position group's R: `FAR` σ sits just above
/// the boundary, and above `GATE`, so the position is withheld from the
/// jump's own fix on.
const TRACK_R_SCALE: f64 = 2.8;
/// The position ramp statistic's scale into the position group's R, the
/// same way (`ramp::RAMP_Z` just above the boundary).
const RAMP_R_SCALE: f64 = 2.8 / crate::ramp::RAMP_Z;
/// The baro flatline's z-score into the baro group's R, the same way
/// (`flatline::Z` just above the boundary).
const FLAT_R_SCALE: f64 = 2.8 / flatline::Z;
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
/// No fault is called before σ_Δ has learnt from this many consecutive
/// differences on every position axis. Its fast start counts the prior as
/// 4 epochs (`indicators::PRIOR_EPOCHS`), so a receiver 6× noisier than
/// the 0.3 m prior is still judged at a σ_Δ of 0.5–0.8 of its own over
/// its first fixes, and the windows keep those departures for 3 more:
/// twice the prior's count leaves it at most a third of the weight. Tune
/// split: false-positive epochs in the logs' first 30 s 311 → 73, false
/// alarm 0.051 → 0.041, clean flights 0.23% → 0.18%; a fault already
/// present at the first fixes is learnt as the receiver's noise instead
/// (events flagged 184 with 5, 183 with 8). Counted in epochs, not
/// seconds: σ_Δ learns per epoch, whatever the receiver's rate.
const WARMUP_EPOCHS: u32 = 8;
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

/// The streaming detector: the filter and the indicator engine, plus one
/// small state per stage of the GPS epoch (see `Detector::gps_epoch`).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Detector {
    cfg: Config,
    /// The navigation filter; None until the first fix, and after a data
    /// gap or a filter error until the next one.
    kf: Option<Kf>,
    anchor: Option<Anchor>,
    /// The latest IMU sample (time s, input), held for the next prediction.
    imu: Option<(f64, ImuInput)>,
    ind: IndicatorEngine,
    clock: Clock,
    imu_noise: ImuNoise,
    last_est: LastEstimate,
    consistency: Consistency,
    quality: ReceiverQuality,
    episode: Episode,
    methods: Methods,
    learning: Learning,
    /// This row's residuals (pos N/E/D m, vel N/E/D m/s, baro m); NaN where
    /// not computed on this row.
    resid: [f64; 7],
    last: Output,
    last_ind: Indicators,
    stats: Stats,
    oracle: bool,
    /// Boot time (s) until which the vehicle counts as upset (see
    /// [`kind::UPSET`]); NaN when it never was.
    upset_until: f64,
    /// The filter's accelerometer-bias estimate at the last normal epoch
    /// whose IMU test was calm (body, m/s²): what an IMU episode rolls the
    /// estimate back to (see `gps_epoch`).
    bias_calm: [f64; 3],
}

/// A GPS fix in the local frame.
#[derive(Clone, Copy, Debug)]
struct Fix {
    /// Time, s.
    t: f64,
    /// Position NED, m.
    y: Vector3<f64>,
    /// Velocity NED (m/s), when the receiver gives one.
    vel: Option<Vector3<f64>>,
    /// The receiver's horizontal accuracy claim, m (NaN when absent).
    eph: f64,
    /// Its vertical claim, m: `epv`, else 1.5 × `eph` (vertical dilution is
    /// typically 1.5× the horizontal); NaN when neither is given.
    epv: f64,
    /// The receiver's own time of the fix, s (NaN when the log has none).
    gps_time: f64,
    /// Its speed accuracy claim, m/s (NaN when absent).
    sacc: f64,
    /// Satellites in use and fix type (2 = 2D, 3 = 3D), NaN when absent.
    sats: f64,
    fix_type: f64,
}

impl Fix {
    fn new(s: &Sample, anchor: &Anchor) -> Self {
        Fix {
            t: s.t,
            y: anchor.to_ned(s),
            vel: s.has_velocity().then(|| Vector3::new(s.vn, s.ve, s.vd)),
            eph: s.eph,
            epv: if s.epv.is_finite() { s.epv } else { 1.5 * s.eph },
            gps_time: s.gps_time,
            sacc: s.sacc,
            sats: s.sats,
            fix_type: s.fix,
        }
    }

    /// The receiver calls this fix degraded in its own fields: a 2D fix
    /// (no autopilot EKF fuses one), or four satellites or fewer (a 3D fix
    /// with no redundant satellite: no integrity check is possible, and
    /// ArduPilot and PX4 require six to arm).
    fn self_declared_degraded(&self) -> bool {
        self.fix_type == 2.0 || (self.sats.is_finite() && self.sats <= MAX_DEGRADED_SATS)
    }
}

/// The receiver's accuracy claim against its usual one. A receiver that
/// loses satellites or geometry says so (eph, or HDOP standing in for it,
/// grows several-fold); a fix it calls `k` times worse than usual is fed to
/// the filter with `k` times the usual σ, so the epochs of a degraded fix
/// that pass the tests do not drag the estimate along, and the good fix
/// after it is not judged against a dragged estimate (battery: 28% of all
/// false-positive epochs followed a degraded fix). Only a ratio is used: no
/// receiver's absolute eph is assumed.
///
/// The speed accuracy claim (`sacc`, where the log has one) scales the
/// velocity test the same way (see `IndicatorEngine::set_speed_claim`).
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
struct ReceiverQuality {
    /// The usual eph (m).
    pos: UsualClaim,
    /// The usual speed accuracy claim (m/s).
    speed: UsualClaim,
    /// Consecutive fixes the receiver called degraded, up to the last.
    degraded_run: u32,
    /// The receiver declared its last fix degraded (`declares_degraded`).
    declared: bool,
    /// A fix the receiver did not call degraded has been seen: before it
    /// the receiver is still acquiring (the PX4 logs' 2D fixes for 1.7 s
    /// before the first 3D one), which is no fault of a fix it had.
    acquired: bool,
    /// Time of the last fix the receiver declared degraded, s.
    last_declared: Option<f64>,
}

/// How long after its last declared-degraded fix a receiver's jump is its
/// return, s: a few fixes at 1 Hz, and longer than the claim takes to
/// improve before the position does.
const DECLARED_RETURN_S: f64 = 3.0;
/// Forgetting factor of the usual eph, per learnt fix.
const QUALITY_ALPHA: f64 = 0.02;
/// A claim this many times the usual one or more is not learnt as usual.
const QUALITY_DEGRADED: f64 = 2.0;
/// Largest σ scale: beyond it the fix carries no weight worth modelling.
const QUALITY_MAX_SCALE: f64 = 100.0;
/// Degraded fixes in a row before a good claim counts as re-acquisition.
const QUALITY_RUN: u32 = 3;
/// An accuracy claim this many times the usual one is the receiver
/// declaring its fix degraded (flagged `DEGRADED`). Larger than
/// `QUALITY_DEGRADED`: the shared real logs' HDOP reaches 2× its median
/// on healthy stretches (26-11: 4 of 675 records), never 3×.
const QUALITY_DECLARED: f64 = 3.0;
/// Satellites at or below which a fix is degraded by its own count.
const MAX_DEGRADED_SATS: f64 = 4.0;
/// Satellites a receiver must give again to end a stretch it declared
/// degraded: the count ArduPilot's and PX4's GPS checks require before
/// their EKF uses the receiver (`EK3_GPS_CHECK`, `EKF2_REQ_NSATS`).
const MIN_TRUSTED_SATS: f64 = 6.0;

/// One of the receiver's accuracy claims (eph m, sAcc m/s) learnt as its
/// usual level: a mean of ln(claim), so only ratios are used.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
struct UsualClaim {
    /// Learnt usual ln(claim); None until the first claim.
    ln: Option<f64>,
    /// Claims learnt from (saturating): a fast start, as σ_Δ has.
    learnt: u32,
}

impl UsualClaim {
    /// How many times worse than usual the receiver calls a claim of `x`
    /// (1 when it is no worse, or says nothing).
    fn scale(&self, x: f64) -> f64 {
        match self.ln {
            Some(l) if x.is_finite() && x > 0.0 => libm::exp(libm::log(x) - l).clamp(1.0, QUALITY_MAX_SCALE),
            _ => 1.0,
        }
    }

    /// Past the fast start: the usual level forgets at `QUALITY_ALPHA`.
    fn learnt(&self) -> bool {
        f64::from(self.learnt) * QUALITY_ALPHA >= 1.0
    }

    /// Learn a claim from a fix with a normal verdict. Claims of a degraded
    /// fix are not learnt (past the first few), so the usual level follows
    /// a receiver that improves at once and one that worsens only slowly.
    fn learn(&mut self, x: f64) {
        if !(x.is_finite() && x > 0.0) {
            return;
        }
        let lx = libm::log(x);
        let Some(l) = self.ln else {
            self.ln = Some(lx);
            self.learnt = 1;
            return;
        };
        if self.scale(x) >= QUALITY_DEGRADED && self.learnt() {
            return;
        }
        let w = QUALITY_ALPHA.fmax(1.0 / (f64::from(self.learnt) + 1.0));
        self.ln = Some(l + w * (lx - l));
        self.learnt = self.learnt.saturating_add(1);
    }
}

impl ReceiverQuality {
    /// How many times worse than usual the receiver calls a fix of `eph` m
    /// (1 when it is no worse, or says nothing).
    fn scale(&self, eph: f64) -> f64 {
        self.pos.scale(eph)
    }

    /// How many times worse than usual the receiver calls its velocity of
    /// speed accuracy `sacc` m/s (1 when no worse, or it says nothing).
    fn speed_scale(&self, sacc: f64) -> f64 {
        self.speed.scale(sacc)
    }

    /// Whether the receiver, after `QUALITY_RUN` or more fixes it called
    /// degraded, calls this one usual again: it re-acquired, and its fix is
    /// a better anchor than an estimate that coasted on weakly weighted
    /// fixes (whose velocity in particular drifted: the first good epochs
    /// after a degraded stretch were flagged on the velocity group).
    fn reacquired(&mut self, eph: f64) -> bool {
        let degraded = self.scale(eph) >= QUALITY_DEGRADED;
        let back = !degraded && eph.is_finite() && self.degraded_run >= QUALITY_RUN;
        self.degraded_run = if degraded { self.degraded_run.saturating_add(1) } else { 0 };
        back
    }

    /// Whether the receiver declares the fix degraded in its own fields
    /// (2D, ≤ `MAX_DEGRADED_SATS` satellites, or an accuracy claim
    /// `QUALITY_DECLARED` times its learnt usual one), once it has given a
    /// fix it did not call degraded. A declared stretch lasts while the
    /// receiver stays below what it takes to be trusted again: fewer than
    /// `MIN_TRUSTED_SATS` satellites, or a claim `QUALITY_DEGRADED` times
    /// its usual one, within `DECLARED_RETURN_S` of the last fix that
    /// opened it. A usual fix ends it: holding a declaration over the
    /// next usual fixes (1 s and 3 fixes was tried) flagged the good fixes
    /// after a degraded stretch (paper scenario false positives 14 → 164).
    /// The detector's tests still judge the fix (down-weighted, see
    /// `scale`); this is the receiver's word, reported as it is, like a
    /// no-fix report.
    ///
    /// Built for size in the core module, and not inlined: once per GPS
    /// epoch (issue 15's budget).
    #[inline(never)]
    #[cfg_attr(navguard_cold_size, optimize(size))]
    fn declares_degraded(&mut self, fix: &Fix) -> bool {
        let learnt = self.pos.learnt();
        let says = fix.self_declared_degraded();
        self.acquired |= !says;
        // Once declared, a stretch lasts while the receiver has fewer
        // satellites than a fix needs to be used again, or a claim at the
        // level the usual one refuses to learn (`QUALITY_DEGRADED`), for
        // up to `DECLARED_RETURN_S` after the last fix that opened it: a
        // receiver that lost satellites says so fix by fix, and its
        // 5-satellite fixes between 4-satellite ones are no better (battery
        // eval #354: a 20 Hz receiver's 65 s degraded fix was flagged on
        // 654 of its 1,259 epochs, about every other one). The bound keeps
        // a receiver whose usual count is 5 from holding a stretch on its
        // usual fixes (eval #1022: 100 s held after a 12 s degraded fix).
        let scale = self.scale(fix.eph);
        let opens = says || (learnt && scale >= QUALITY_DECLARED);
        let few = fix.sats < MIN_TRUSTED_SATS;
        let recent = self.last_declared.is_some_and(|d| fix.t - d <= DECLARED_RETURN_S);
        let keeps = self.declared && recent && (few || scale >= QUALITY_DEGRADED);
        self.declared = self.acquired && (opens || keeps);
        if self.declared && opens {
            self.last_declared = Some(fix.t);
        }
        self.declared
    }

    /// A fix at `t` the receiver calls usual, within `DECLARED_RETURN_S`
    /// of one it declared degraded: a jump here is the receiver coming
    /// back from the degraded stretch, which the filter had followed at
    /// its reduced weight (battery tune #150: the first usual fix jumped
    /// 10 m back to the truth and was flagged as a step for the 60 s
    /// coast limit).
    fn returning(&self, t: f64) -> bool {
        !self.declared && self.last_declared.is_some_and(|d| t - d <= DECLARED_RETURN_S)
    }

    /// Learn the claims of a fix with a normal verdict.
    fn learn(&mut self, fix: &Fix) {
        self.pos.learn(fix.eph);
        self.speed.learn(fix.sacc);
    }
}

/// Row and fix timing: time order, data gaps, and the receiver's learnt
/// period, which says when silence becomes an outage.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Clock {
    /// Time of the last row, s.
    last_t: Option<f64>,
    /// Time of the last fix, s; moved to the end of a data gap, so the gap
    /// itself does not count as the receiver's silence.
    last_fix: Option<f64>,
    /// Learnt GPS period, s.
    gps_dt: f64,
    /// Mean absolute deviation of the GPS interval, s (receiver jitter).
    gps_jitter: f64,
    /// The last new fix's position and velocity fields, bit for bit.
    last_fields: Option<[u64; 9]>,
}

impl Clock {
    fn new() -> Self {
        Clock { last_t: None, last_fix: None, gps_dt: 0.2, gps_jitter: 0.0, last_fields: None }
    }

    /// Whether a fix row carries a new fix. A receiver measures with noise:
    /// nine position and velocity fields repeated bit for bit (centimetre
    /// quantisation at most) are its last output again, not a measurement,
    /// so such a row counts as silence (`is_outage` decides when silence is
    /// a fault) rather than as an epoch that agrees perfectly and teaches
    /// the filter a frozen position.
    fn fresh(&mut self, s: &Sample) -> bool {
        let fields = [s.lat, s.lon, s.alt, s.pn, s.pe, s.pd, s.vn, s.ve, s.vd].map(f64::to_bits);
        let fresh = self.last_fields != Some(fields);
        self.last_fields = Some(fields);
        fresh
    }

    /// A row at `t` s: the time since the previous row (0 for the first),
    /// s, and whether that is a data gap (longer than `data_gap` s).
    fn row(&mut self, t: f64, data_gap: f64) -> (f64, bool) {
        let dt = self.last_t.map_or(0.0, |lt| t - lt);
        let gap = self.last_t.is_some() && dt > data_gap;
        if gap && self.last_fix.is_some() {
            self.last_fix = Some(t);
        }
        self.last_t = Some(t);
        (dt, gap)
    }

    /// A fix at `t` s: learn the receiver's period and jitter from the
    /// interval since the previous fix (longer ones are losses, not periods).
    fn fix(&mut self, t: f64) {
        if let Some(lf) = self.last_fix {
            let d = t - lf;
            if d > 0.0 && d < 5.0 {
                self.gps_jitter += 0.05 * ((d - self.gps_dt).abs() - self.gps_jitter);
                self.gps_dt += 0.05 * (d - self.gps_dt);
            }
        }
        self.last_fix = Some(t);
    }

    /// Outage at a row without a fix at `t` s: after a fix has been seen,
    /// the receiver says it has none (`reports_no_fix`), or (`flying`) no
    /// fix arrived within `timeout` s. By default silence must outlast
    /// `SILENT_OUTAGE_S` and 3 receiver periods (more for a jittery
    /// receiver): loggers drop GPS records for up to about a second while
    /// the receiver keeps its fix (78 such gaps of 0.5–0.94 s on the shared
    /// ArduPilot logs, the receiver's own clock advancing across each),
    /// whereas a receiver that loses its fix says so (a no-fix record
    /// 1.2 s after the last fix in all 9 real losses there). It lasts
    /// (`in_outage`) until the next fix. A receiver that reports losing its
    /// fix is an outage on the ground too; mere silence counts only in
    /// flight (logs often stop sending GPS after landing).
    fn is_outage(&self, t: f64, reports_no_fix: bool, in_outage: bool, flying: bool, timeout: Option<f64>) -> bool {
        let Some(lf) = self.last_fix else {
            return false;
        };
        if in_outage {
            return true;
        }
        if reports_no_fix && t - lf > 0.5 * self.gps_dt {
            return true;
        }
        flying && t - lf > self.outage_silence(timeout)
    }

    /// How long a silence (s) makes an outage while flying: `timeout`, or
    /// by default the longest of `SILENT_OUTAGE_S`, three GPS periods and
    /// a period plus four of its jitters. Inlined: the core module's
    /// `is_outage` stays as it was (issue 15's budget).
    #[inline(always)]
    fn outage_silence(&self, timeout: Option<f64>) -> f64 {
        timeout.unwrap_or(SILENT_OUTAGE_S.fmax(3.0 * self.gps_dt).fmax(self.gps_dt + 4.0 * self.gps_jitter) + 0.02)
    }
}

/// The accelerometer noise learnt in flight: half the mean square of
/// consecutive differences per axis times the sample interval, an
/// exponential mean over `IMU_PSD_TAU` s: a density ((m/s²)²·s), the same
/// at any IMU rate for the same sensor, that grows with vibration and with
/// snapshot sampling. The filter adds it to its process noise.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
struct ImuNoise {
    /// Previous sample (t s, specific force m/s²).
    prev: Option<(f64, [f64; 3])>,
    psd: f64,
    /// The samples' interval, s (an exponential mean over
    /// `IMU_PERIOD_TAU_S`; 0 before two samples).
    period: f64,
}

impl ImuNoise {
    /// One IMU sample at `t` s; returns the density.
    fn learn(&mut self, t: f64, f: [f64; 3]) -> f64 {
        if let Some((tp, fp)) = self.prev {
            let dt = t - tp;
            if dt > 0.0 && dt < 0.5 {
                let ms = (0..3).map(|a| (f[a] - fp[a]).powi(2)).sum::<f64>() / 6.0;
                self.psd += (dt / IMU_PSD_TAU).fmin(1.0) * (ms * dt - self.psd);
                // A dropped stretch of records is not the logging rate.
                if dt <= IMU_MAX_PERIOD_S * 6.0 {
                    self.period = if self.period > 0.0 { self.period + (dt / IMU_PERIOD_TAU_S).fmin(1.0) * (dt - self.period) } else { dt };
                }
            }
        }
        self.prev = Some((t, f));
        self.psd
    }
}

/// Where the filter's estimate stood when each sensor was last judged: the
/// indicators' predicted change `m` is measured from here.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct LastEstimate {
    /// Position NED (m) and velocity NED (m/s) after the last GPS epoch.
    pos: Vector3<f64>,
    vel: Vector3<f64>,
    /// Predicted baro reading (m) after the last baro sample; None after a
    /// (re)initialisation.
    baro_h: Option<f64>,
}

/// The residuals stage's output for one fix.
#[derive(Clone, Copy, Debug)]
struct Residuals {
    /// Position innovation (ν m, S m²).
    pin: Innovation<3>,
    /// Velocity innovation (ν m/s, S (m/s)²), when the fix has a velocity.
    vin: Option<Innovation<3>>,
    /// Each GPS axis' previous residual, for `IndicatorEngine::accept` once
    /// the axis is fed to the filter.
    prev_r: [f64; 6],
    /// Position reference residuals (the last accepted epoch's), m.
    r_ref: [f64; 3],
}

impl Residuals {
    /// Into the row's residuals (position, then velocity; baro untouched).
    fn write(&self, resid: &mut [f64; 7]) {
        resid[..3].copy_from_slice(&self.pin.nu);
        if let Some(vin) = &self.vin {
            resid[3..6].copy_from_slice(&vin.nu);
        }
    }
}

/// How many σ the fix `nu` (m) sits off the filter along its offset. σ
/// along the offset: a step on one axis is judged by that axis' noise, not
/// by the three axes' together; and by the larger of the epoch-to-epoch
/// noise (`sigma_pos`, σ_Δ) and the position's wander about its velocity
/// track (`sigma_track`), so a receiver that moves smoothly (σ_Δ 0.15 m on
/// the paper's flight) does not keep the offset of a brief false episode,
/// which then ate a ramp's first epochs as its "end".
#[inline(never)]
fn along_sigmas(nu: &[f64; 3], sigma_pos: &[f64; 3], sigma_track: &[f64; 3]) -> f64 {
    let len2: f64 = nu.iter().map(|x| x * x).sum();
    let sigma2: f64 = (0..3).map(|a| (nu[a] * sigma_pos[a].fmax(sigma_track[a])).powi(2)).sum::<f64>();
    (len2 * len2 / sigma2).sqrt()
}

/// The fix's offset `nu` from the filter (m) is a step's onset: at least
/// `KEEP_MIN_SIGMAS` σ off along it (`along_sigmas`), and mostly this
/// epoch's jump off the velocity track (`jump`, m: at least
/// `DRAG_RETURN_NEW` of the offset along it). An offset that built up over
/// epochs the verdict passed is the truth coming back or the receiver's
/// wander, not a fault to hold: a drag-off's end split across a dropped
/// record (battery eval #71: 6.6 m, held for 56 s), a Gauss–Markov
/// receiver's wander walking the windows over the boundary (tune #1253).
#[cfg_attr(navguard_cold_size, optimize(size))]
fn step_onset(nu: &[f64; 3], jump: Option<[f64; 3]>, sigma_pos: &[f64; 3], sigma_track: &[f64; 3]) -> bool {
    let Some(j) = jump else { return false };
    let nu2: f64 = nu.iter().map(|x| x * x).sum();
    along_sigmas(nu, sigma_pos, sigma_track) > KEEP_MIN_SIGMAS && (0..3).map(|a| j[a] * nu[a]).sum::<f64>() >= DRAG_RETURN_NEW * nu2
}

/// A position jump is the end of a drag-off the filter had followed when
/// the velocity jumped with it, in the same direction, by more than its
/// noise (`DRAG_RETURN_Z` σ along the jump). A dragged receiver's position
/// runs ahead of the truth by the drag rate times its age while its
/// velocity runs ahead by the drag rate; when the true fix returns both
/// fall back along the same direction, the position by `age` times as much
/// as the velocity. A step onset leaves the velocity alone, so it is not
/// read as a return; a filter that drifted (a stuck baro pulling its
/// height) has a residual that grew over many epochs, not at this one.
const DRAG_RETURN_Z: f64 = 3.0;
/// The velocity jump's share across the position jump's direction may be
/// at most this fraction of its share along it.
const DRAG_RETURN_ACROSS: f64 = 1.0;
/// Share of the position residual (along its direction) that must be new
/// at this epoch.
const DRAG_RETURN_NEW: f64 = 0.6;
/// The drag's age implied by the two jumps (position / velocity along it),
/// s: at least this, and no longer than the filter has been flying.
const DRAG_RETURN_MIN_AGE_S: f64 = 5.0;

impl Residuals {
    /// The horizontal fix jumped at this epoch: its residual moved by more
    /// than `track::NEAR` of σ_Δ (`sigma_pos`, m), the epoch-to-epoch
    /// change's σ, since the previous epoch.
    #[inline(never)]
    fn jumped_h(&self, sigma_pos: &[f64; 3]) -> bool {
        ((self.pin.nu[0] - self.prev_r[0]) / sigma_pos[0]).hypot((self.pin.nu[1] - self.prev_r[1]) / sigma_pos[1]) > crate::track::NEAR
    }

    /// The jump at this fix looks like the return from a drag-off the
    /// filter followed (see [`DRAG_RETURN_Z`]): true fix back, re-anchor on
    /// it: then the drag's age (true s: the jump over the velocity's jump
    /// and its σ, the shortest drag they allow; 0 without the `dated`
    /// feature). `flown`: time flown with the filter running, s.
    fn drag_returned(&self, flown: f64, track_jump: Option<[f64; 3]>, sigma_dv: [f64; 3]) -> Option<f64> {
        let (Some(vin), Some(gps_jump)) = (&self.vin, track_jump) else { return None };
        let p = &self.pin.nu;
        let p2: f64 = p.iter().map(|x| x * x).sum();
        if !(p2 > 0.0) {
            return None;
        }
        let norm = p2.sqrt();
        let u: [f64; 3] = core::array::from_fn(|a| p[a] / norm);
        let along = |x: [f64; 3]| (0..3).map(|a| x[a] * u[a]).sum::<f64>();
        // NaN when an axis has no previous residual: then nothing is new.
        let new_p = along(core::array::from_fn(|a| p[a] - self.prev_r[a]));
        let moved = along(gps_jump);
        let dv: [f64; 3] = core::array::from_fn(|a| vin.nu[a] - self.prev_r[3 + a]);
        let jump_v = along(dv);
        let sigma = (0..3).map(|a| (u[a] * sigma_dv[a]).powi(2)).sum::<f64>().sqrt();
        let across = (0..3).map(|a| (dv[a] - jump_v * u[a]).powi(2)).sum::<f64>().sqrt();
        let age = norm / jump_v;
        let returned = new_p >= DRAG_RETURN_NEW * norm
            && moved >= DRAG_RETURN_NEW * norm
            && jump_v > DRAG_RETURN_Z * sigma
            && across <= DRAG_RETURN_ACROSS * jump_v
            && (DRAG_RETURN_MIN_AGE_S..=flown).contains(&age);
        // The shortest drag the velocity's jump and its σ allow.
        returned.then(|| if cfg!(feature = "dated") { norm / (jump_v + sigma) } else { 0.0 })
    }
}

impl LastEstimate {
    /// The residuals stage: the fix against the filter's prediction, each
    /// axis observed by the indicator engine with the change the filter
    /// predicted since the last epoch.
    fn residuals(&self, kf: &mut Kf, ind: &mut IndicatorEngine, fix: &Fix) -> Residuals {
        let pin = kf.position_innovation(&fix.y);
        let pos_prior = kf.position();
        let r_ref = core::array::from_fn(|a| ind.reference(a));
        let mut prev_r = [0.0; 6];
        for a in 0..3 {
            prev_r[a] = ind.previous(a);
            ind.observe(a, pin.nu[a], pos_prior[a] - self.pos[a], kf.position_var(a));
        }
        let vel_prior = kf.velocity();
        let vin = fix.vel.map(|v| {
            let vin = kf.velocity_innovation(&v);
            for a in 0..3 {
                prev_r[3 + a] = ind.previous(3 + a);
                ind.observe(3 + a, vin.nu[a], vel_prior[a] - self.vel[a], kf.velocity_var(a));
            }
            vin
        });
        Residuals { pin, vin, prev_r, r_ref }
    }

    /// The filter's estimate after a GPS epoch's update (or re-anchoring).
    fn set_epoch(&mut self, kf: &Kf) {
        self.pos = kf.position();
        self.vel = kf.velocity();
    }
}

/// What the tests stage (`Consistency::tests`) needs to know about the
/// epoch beyond the fix.
#[derive(Clone, Copy, Debug)]
struct EpochState {
    /// The GPS velocity is withheld (a fault verdict on it).
    vel_withheld: bool,
    /// The baro is withheld: held to a lower bar (`Consistency::baro_still_off`).
    baro_withheld: bool,
    /// The receiver is trusted enough to teach the clock rate.
    learn_rate: bool,
    /// The receiver declares this fix degraded (`ReceiverQuality`).
    declared: bool,
    /// The IMU is logged often enough to judge (`IMU_MAX_PERIOD_S`).
    imu_dense: bool,
    /// The receiver's speed accuracy claim against its usual one (≥ 1).
    speed_claim: f64,
    /// A position offset is accepted (`Episode::accepted`).
    accepted: bool,
    /// The episode holds on the fix's short mean (`Episode::mean_hold`).
    mean_hold: bool,
}

/// Running integrals that the filter-independent consistency tests (see
/// `indicators`) compare the sensors against. They advance with every
/// prediction and are read at baro samples and GPS epochs.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Consistency {
    /// The filter's vertical velocity integrated (altitude up, m): the baro
    /// test's reference.
    alt_int: f64,
    /// The filter's IMU-predicted velocity changes summed (m/s): the IMU
    /// test's reference.
    dv_imu: Vector3<f64>,
    /// A prediction since the last GPS epoch ran without IMU, so `dv_imu`
    /// does not measure the IMU alone over that interval.
    imu_gap: bool,
    /// Time flown with the filter running, s: the IMU test joins the
    /// decision once its σ has been learnt in flight.
    flight_time: f64,
    /// Previous GPS fix (t s, position NED m, velocity m/s) for the
    /// position–velocity test.
    last_gps: Option<(f64, Vector3<f64>, Vector3<f64>)>,
    /// Latest baro sample (t s, altitude m) for the baro–GPS test.
    last_baro: Option<(f64, f64)>,
    /// The boot clock's rate against true time.
    rate: ClockRate,
    /// The GPS position against its own velocity integrated.
    track: VelocityTrack,
    /// The baro altitude against the GPS altitude, and against the GPS
    /// vertical velocity integrated: levels with baselines learnt in
    /// flight. A baro that drifts leaves both; a GPS vertical fault only
    /// the first.
    baro_gps_level: VelocityTrack,
    baro_dop_level: VelocityTrack,
    /// The baro's drift against both levels over a long window.
    baro_drift: DriftTest,
    /// The position ramping off its velocity track.
    ramp: RampTest,
    /// The end of a drag-off, confirmed on the velocity's mean
    /// (horizontal and vertical).
    drag_end: DragEnds,
    /// The baro's reading held bit for bit (a stuck sensor, see `flatline`).
    baro_flat: Flatline,
    /// The last GPS epoch the baro's levels saw: (t s, `alt_int` m, GPS
    /// vertical velocity up m/s or NaN when it was not trusted).
    baro_epoch: Option<(f64, f64, f64)>,
    /// The baro's departure from its levels in units of the hold at the
    /// last GPS epoch (`held_departure`; NaN while a level cannot judge):
    /// read at every baro sample, so computed once per epoch.
    baro_held: f64,
    /// A baro step held from its jump (see `barojump`).
    baro_jump: BaroJump,
}

/// Boot-clock rate estimate. Some autopilot builds stamp samples with a boot
/// clock that runs 0.92× true time (the shared 2014 ArduPilot logs:
/// 0.9229–0.9235 by the receiver's own time of week). Timestamps from it
/// make the GPS position move faster than its velocity integrated over the
/// stamps, by 8% of the speed: a ramp in every flight.
///
/// Where the log carries the receiver's own time (`gps_time`), the rate is
/// measured against it ([`ReceiverClock`]): exact within seconds of the
/// first fix, and blind to what the vehicle does. Otherwise the GPS motion
/// says how fast the clock runs: over blocks of at least `CLOCK_BLOCK_S`,
/// its horizontal displacement against its velocity integrated over boot
/// time, regressed through the origin: `scale = Σ ΔP·ΔV / Σ |ΔV|²`. It is
/// used once `Σ |ΔV|²` reaches `CLOCK_MIN_SXX` (about 70 m flown), clamped
/// to `CLOCK_RANGE`. A clock error always points along the velocity; a
/// position fault need not, but a long ramp along a straight leg does, so
/// blocks inside any fault episode do not count. The rate multiplies every
/// time step of the filter and of the position–velocity test.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct ClockRate {
    /// True seconds per boot-clock second: the receiver's rate once it has
    /// one, else the motion-based one.
    scale: f64,
    /// The motion-based rate.
    motion: f64,
    sxy: f64,
    sxx: f64,
    /// Block start: boot time (s) and horizontal GPS position (m).
    start: Option<(f64, [f64; 2])>,
    /// Horizontal GPS velocity integrated since the block start, m.
    dv: [f64; 2],
    /// Boot time of the last epoch observed, s.
    last: Option<f64>,
    /// The rate against the receiver's own time.
    receiver: ReceiverClock,
}

/// Longest GPS gap the velocity track integrates across, s.
const TRACK_MAX_GAP_S: f64 = 3.0;
/// Longest interval between two fixes that the position–velocity test
/// compares, s: a 1 Hz receiver's period with its jitter (at 1.0 s its
/// fixes were compared only when jitter brought two closer, so σ was never
/// learnt and the test spoke from its prior). A longer silence is a
/// dropped record.
const PV_MAX_DT_S: f64 = 1.5;
const CLOCK_BLOCK_S: f64 = 5.0;
const CLOCK_MIN_SXX: f64 = 5.0e3;
/// m: a block must span at least this much flight to count.
const CLOCK_MIN_BLOCK_M: f64 = 10.0;
const CLOCK_RANGE: (f64, f64) = (0.9, 1.15);
/// Rate errors below 1% are left alone by the motion-based estimate: the
/// clocks this corrects are off by several percent (8% on the 2014
/// ArduPilot builds), while that estimate wanders by a fraction of a
/// percent. (The receiver's estimate uses its own standard error instead.)
const CLOCK_DEAD_BAND: f64 = 0.01;

impl ClockRate {
    fn new() -> Self {
        ClockRate { scale: 1.0, motion: 1.0, sxy: 0.0, sxx: 0.0, start: None, dv: [0.0; 2], last: None, receiver: ReceiverClock::default() }
    }

    /// One fix's receiver time `g` (s, NaN when absent) at boot time `t` s.
    fn observe_time(&mut self, t: f64, g: f64) {
        if g.is_nan() {
            return;
        }
        self.receiver.observe(t, g);
        self.scale = self.receiver.rate().unwrap_or(self.motion);
    }

    /// One GPS interval: the previous epoch (boot time `pt` s, position
    /// `pp` m, velocity `pv` m/s, NED) to this one (`t`, `y`, `v`).
    fn observe(&mut self, (pt, pp, pv): (f64, Vector3<f64>, Vector3<f64>), t: f64, y: &Vector3<f64>, v: &Vector3<f64>) {
        // A broken chain (skipped epochs) restarts the block.
        if self.last != Some(pt) || self.start.is_none() {
            self.start = Some((pt, [pp[0], pp[1]]));
            self.dv = [0.0; 2];
        }
        self.last = Some(t);
        for a in 0..2 {
            self.dv[a] += 0.5 * (v[a] + pv[a]) * (t - pt);
        }
        let Some((t0, p0)) = self.start else { return };
        if t - t0 < CLOCK_BLOCK_S {
            return;
        }
        let vv = self.dv[0] * self.dv[0] + self.dv[1] * self.dv[1];
        if vv > CLOCK_MIN_BLOCK_M * CLOCK_MIN_BLOCK_M {
            self.sxy += (y[0] - p0[0]) * self.dv[0] + (y[1] - p0[1]) * self.dv[1];
            self.sxx += vv;
            if self.sxx >= CLOCK_MIN_SXX {
                let k = (self.sxy / self.sxx).clamp(CLOCK_RANGE.0, CLOCK_RANGE.1);
                // Within the dead band the estimate is GPS noise, not a
                // clock: correcting by it would only add its error.
                self.motion = if (k - 1.0).abs() < CLOCK_DEAD_BAND { 1.0 } else { k };
                if self.receiver.rate().is_none() {
                    self.scale = self.motion;
                }
            }
        }
        self.start = Some((t, [y[0], y[1]]));
        self.dv = [0.0; 2];
    }
}

/// The boot clock's rate against the receiver's own time: the slope of
/// receiver time on boot time, fitted by least squares over runs of
/// consistent pairs, each run with its own offset, so a week rollover, a
/// leap second or a receiver that re-synchronised costs one pair, not the
/// fit. A pair whose receiver time repeats (a duplicated record) is
/// skipped; one that goes backwards or is more than `RECEIVER_TOL_S` plus
/// `RECEIVER_TOL_RATE` of the elapsed boot time off the current fit's
/// prediction (a logger that stalled, a corrupt record) opens a new run.
/// The rate counts once it has `RECEIVER_MIN_DOF` residual degrees of
/// freedom; a rate within `RECEIVER_Z` standard errors of 1 (widened to
/// Student's t for the fit's degrees of freedom, as the standard error is
/// itself estimated from a few pairs at first) is taken as 1: a true clock
/// is left alone, and so is a difference its own fit cannot tell from
/// timestamp jitter.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
struct ReceiverClock {
    /// Closed runs' centred sums: Σ(x−x̄)², Σ(x−x̄)(y−ȳ), Σ(y−ȳ)² (s²),
    /// with x boot time and y receiver time.
    sxx: f64,
    sxy: f64,
    syy: f64,
    /// Pairs in closed runs that have at least two, and how many such runs.
    pairs: u64,
    runs: u64,
    /// The open run.
    run: Option<ClockRun>,
}

/// One run of consistent (boot time, receiver time) pairs: its first pair,
/// then running means and centred sums of the pairs relative to it
/// (Welford), so large epochs (GPS seconds ~1e9) lose no precision.
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
struct ClockRun {
    t0: f64,
    g0: f64,
    n: u64,
    mx: f64,
    my: f64,
    cxx: f64,
    cxy: f64,
    cyy: f64,
    /// The last pair accepted (boot s, receiver s).
    last: (f64, f64),
}

/// s: timestamp jitter a pair may show against the fit (logger stamps are
/// taken when the record arrives, tens of ms after the fix).
const RECEIVER_TOL_S: f64 = 0.1;
/// Share of the elapsed boot time a pair may be off the prediction: the
/// widest clock error expected before the fit has a rate of its own.
const RECEIVER_TOL_RATE: f64 = 0.1;
/// Residual degrees of freedom before the rate is used.
const RECEIVER_MIN_DOF: u64 = 3;
/// Standard errors within which a rate is not told from 1.
const RECEIVER_Z: f64 = 3.0;

/// Student's t quantile over the normal one at the same tail, for `nu`
/// degrees of freedom (Cornish–Fisher, three terms: within 8% at 3 degrees
/// of freedom, exact as `nu` grows).
fn t_over_z(z: f64, nu: f64) -> f64 {
    let (z3, z5, z7) = (z * z * z, z * z * z * z * z, z * z * z * z * z * z * z);
    let g1 = (z3 + z) / 4.0;
    let g2 = (5.0 * z5 + 16.0 * z3 + 3.0 * z) / 96.0;
    let g3 = (3.0 * z7 + 19.0 * z5 + 17.0 * z3 - 15.0 * z) / 384.0;
    (z + g1 / nu + g2 / (nu * nu) + g3 / (nu * nu * nu)) / z
}

impl ClockRun {
    fn new(t: f64, g: f64) -> Self {
        ClockRun { t0: t, g0: g, n: 1, mx: 0.0, my: 0.0, cxx: 0.0, cxy: 0.0, cyy: 0.0, last: (t, g) }
    }

    fn add(&mut self, t: f64, g: f64) {
        let (x, y) = (t - self.t0, g - self.g0);
        self.n += 1;
        let n = self.n as f64;
        let dx = x - self.mx;
        let dy = y - self.my;
        self.mx += dx / n;
        self.my += dy / n;
        self.cxx += dx * (x - self.mx);
        self.cxy += dx * (y - self.my);
        self.cyy += dy * (y - self.my);
        self.last = (t, g);
    }
}

impl ReceiverClock {
    /// Sums over closed runs and the open one: (Sxx, Sxy, Syy, residual
    /// degrees of freedom).
    fn sums(&self) -> (f64, f64, f64, u64) {
        let (mut sxx, mut sxy, mut syy, mut pairs, mut runs) = (self.sxx, self.sxy, self.syy, self.pairs, self.runs);
        if let Some(r) = self.run.filter(|r| r.n >= 2) {
            (sxx, sxy, syy) = (sxx + r.cxx, sxy + r.cxy, syy + r.cyy);
            pairs += r.n;
            runs += 1;
        }
        (sxx, sxy, syy, pairs.saturating_sub(runs + 1))
    }

    /// The fitted slope (receiver s per boot s) and its standard error
    /// (scaled so that `RECEIVER_Z` of them make Student's t quantile), once
    /// there are `RECEIVER_MIN_DOF` residual degrees of freedom.
    fn fit(&self) -> Option<(f64, f64)> {
        let (sxx, sxy, syy, dof) = self.sums();
        if dof < RECEIVER_MIN_DOF || sxx <= 0.0 {
            return None;
        }
        let b = sxy / sxx;
        let sse = (syy - b * sxy).fmax(0.0);
        Some((b, libm::sqrt(sse / dof as f64 / sxx) * t_over_z(RECEIVER_Z, dof as f64)))
    }

    /// The rate to use: the fit, or 1 when 1 is within its noise; None
    /// before the fit counts or when it is outside any real clock's range.
    fn rate(&self) -> Option<f64> {
        let (b, se) = self.fit()?;
        if !(CLOCK_RANGE.0..=CLOCK_RANGE.1).contains(&b) {
            return None;
        }
        Some(if (b - 1.0).abs() <= RECEIVER_Z * se { 1.0 } else { b })
    }

    /// One pair: boot time `t` s, receiver time `g` s.
    fn observe(&mut self, t: f64, g: f64) {
        let Some(run) = self.run.as_mut() else {
            self.run = Some(ClockRun::new(t, g));
            return;
        };
        let (lt, lg) = run.last;
        if g == lg || t <= lt {
            return; // a repeated record, or two fixes in one log instant
        }
        let rate = self.fit().map_or(1.0, |(b, _)| b);
        let off = g - (lg + rate * (t - lt));
        if g < lg || off.abs() > RECEIVER_TOL_S + RECEIVER_TOL_RATE * (t - lt) {
            self.close_run();
            self.run = Some(ClockRun::new(t, g));
            return;
        }
        if let Some(run) = self.run.as_mut() {
            run.add(t, g);
        }
    }

    /// Fold the open run into the closed sums (a one-pair run has none).
    fn close_run(&mut self) {
        if let Some(r) = self.run.take().filter(|r| r.n >= 2) {
            self.sxx += r.cxx;
            self.sxy += r.cxy;
            self.syy += r.cyy;
            self.pairs += r.n;
            self.runs += 1;
        }
    }
}

impl Consistency {
    fn new() -> Self {
        Consistency {
            alt_int: 0.0,
            dv_imu: Vector3::zeros(),
            imu_gap: true,
            flight_time: 0.0,
            last_gps: None,
            last_baro: None,
            rate: ClockRate::new(),
            track: VelocityTrack::quick(),
            baro_gps_level: VelocityTrack::default(),
            baro_dop_level: VelocityTrack::default(),
            baro_drift: DriftTest::default(),
            ramp: RampTest::default(),
            drag_end: DragEnds::default(),
            baro_flat: Flatline::default(),
            baro_epoch: None,
            baro_held: f64::NAN,
            baro_jump: BaroJump::default(),
        }
    }

    /// At a fault verdict outside any episode: is this jump the end of a
    /// position fault that was never flagged, or no longer, rather than the
    /// start of a new one? Then the caller re-anchors on the fix and opens
    /// nothing. Three ends: the GPS back onto its own velocity track (a slow
    /// ramp the filter followed); back by the offset a coasted-out episode
    /// re-anchored onto (`Episode::undone`); or, for a fix the receiver
    /// calls `usual`, off its track with its velocity jumping along by more
    /// than `sigma_dv` allows (a drag-off the filter followed, see
    /// `Residuals::drag_returned`), which moves the track's baseline with it.
    /// Either of the last two may take a step's onset for a fault's end
    /// (battery tune #1247: a 5.65 m vertical step re-anchored onto at once),
    /// so the jump re-anchored onto is kept like a coasted-out episode's
    /// offset: the step's own end undoes it instead of opening a 60 s
    /// episode.
    ///
    /// Built for size in the core module: once per GPS epoch (issue 15's
    /// budget).
    #[cfg_attr(navguard_cold_size, optimize(size))]
    fn unflagged_fault_ended(&mut self, t: f64, episode: &mut Episode, res: &Residuals, usual: bool, sigma_dv: [f64; 3]) -> bool {
        // Asked first: a remembered offset is forgotten once undone, even
        // when the track also says the fault ended.
        let undone = episode.undone(t, res);
        let back = undone || self.track.returned() || {
            let age = if usual { res.drag_returned(self.flight_time, self.track.jump(), sigma_dv) } else { None };
            if let Some(age) = age {
                self.track.rebase();
                episode.dating.date(t - age / self.rate.scale);
            }
            age.is_some()
        };
        if undone {
            // The track's baseline learnt the fault while it was accepted
            // (battery tune #551: a 15.6 m vertical step for 117 s): the
            // return is the truth, so the baseline moves with it.
            self.track.rebase();
        } else if back {
            episode.accept(res.pin.nu);
        }
        // The return is a jump of the track, which the ramp test must not
        // read as a ramp once its smoothing has taken it in: at 1 Hz the
        // smoothing takes half of a jump at once, under the ramp test's
        // own jump bar (battery eval #108: a drag-off's 6.3 m return, then
        // 48 s flagged as a ramp).
        if back {
            self.ramp.note_jump();
        }
        back
    }

    /// The baro's levels at a GPS epoch at `t` (position `y` NED m, GPS
    /// velocity `v`, which the detector withheld when `vel_withheld`,
    /// vertical accuracy claim `epv` m; the baro is withheld when
    /// `withheld`), with the latest baro sample. The
    /// level against the GPS altitude needs no velocity. The level against
    /// the vertical velocity integrates the GPS velocity while it is
    /// trusted, and the filter's own (IMU-coasted) vertical velocity while
    /// it is withheld, so a baro fault met during a GPS episode is still
    /// judged against the level learnt before it: restarting the levels
    /// there learnt the faulty baro as the new level, and its return was
    /// flagged for up to 120 s (battery tune #131). A withheld velocity is
    /// still integrated while the baro is withheld or a baro jump is
    /// remembered (see `barojump`): the filter's climb then holds the
    /// jump the baro fed it. Returns the baro drift statistic (see
    /// `drift`), NaN when not judged.
    ///
    /// Built for size in the core module: once per GPS epoch (issue 15's
    /// budget).
    #[cfg_attr(navguard_cold_size, optimize(size))]
    fn baro_levels(&mut self, t: f64, y: &Vector3<f64>, v: Option<&Vector3<f64>>, vel_withheld: bool, epv: f64, withheld: bool) -> (f64, (f64, f64)) {
        let v = v.filter(|_| !vel_withheld || withheld || self.baro_jump.remembered());
        let vup = v.map_or(f64::NAN, |v| -v[2]);
        let prev = self.baro_epoch.replace((t, self.alt_int, vup));
        let baro = self.last_baro.filter(|(tb, _)| t - tb < 0.5).map(|(_, b)| b);
        let (Some(b), Some((pt, alt0, vup0))) = (baro, prev.filter(|(pt, ..)| t - pt > 0.0 && t - pt < TRACK_MAX_GAP_S)) else {
            self.baro_gps_level.clear();
            self.baro_dop_level.clear();
            self.baro_drift.clear();
            self.baro_held = f64::NAN;
            self.baro_jump.clear();
            return (f64::NAN, (f64::NAN, f64::NAN));
        };
        let dt = (t - pt) * self.rate.scale;
        self.baro_gps_level.step(dt, [b + y[2], 0.0, 0.0], [0.0; 3], [0.0; 3]);
        // Both ends on the GPS velocity, or the filter's climb over the
        // interval (its integral, `alt_int`, advances in true time).
        let (v1, v0) = if vup.is_finite() && vup0.is_finite() { (vup, vup0) } else { let c = (self.alt_int - alt0) / dt; (c, c) };
        self.baro_dop_level.step(dt, [b, 0.0, 0.0], [v1, 0.0, 0.0], [v0, 0.0, 0.0]);
        let level = [self.baro_gps_level.level(), self.baro_dop_level.level()];
        let motion = Motion { speed2: v.map_or(f64::NAN, |v| v[0] * v[0] + v[1] * v[1]), climb: v1, height: -y[2], v_ne: v.map_or([f64::NAN; 2], |v| [v[0], v[1]]) };
        for lv in [&mut self.baro_gps_level, &mut self.baro_dop_level] {
            lv.set_motion([motion.speed2, motion.climb]);
        }
        let allow = [K_DYN, K_CLIMB];
        let deps = (self.baro_gps_level.departure_net(allow), self.baro_dop_level.departure_net(allow));
        // A withheld baro is also held off by the step it jumped (see
        // `barojump`), which the GPS altitude's noise may hide.
        self.baro_held = held_departure(deps.0, deps.1);
        self.baro_jump.epoch(t, &self.baro_gps_level, &self.baro_dop_level, withheld, &motion);
        if withheld {
            self.baro_held = self.baro_held.fmax(self.baro_jump.held(t, &self.baro_dop_level, &motion));
        }
        let level_off = !(self.baro_held < PLATEAU_HELD);
        (self.baro_drift.push(dt, level.map(|l| l.unwrap_or(f64::NAN)), motion, epv, level_off), deps)
    }

    /// The GPS altitude's departure from its two other vertical references
    /// (see `tests`), in σ, where both agree in sign (the smaller; 0 when
    /// they disagree, NaN when either is not judged yet). σ is never taken
    /// below the receiver's vertical claim `epv` (m): the levels' baselines
    /// follow a minute, and a Gauss–Markov receiver wanders further than
    /// that teaches. When both references jump back by most of the offset
    /// they held, the fault ended: their baselines move to the fix, so the
    /// wander it left is not judged as a fault of its own.
    /// Also returns whether this fix was that return.
    ///
    /// `may_return`: false inside an episode held on the short mean
    /// (`Episode::mean_hold`), where one fix of a fast noisy receiver
    /// comes back by half its offset by chance (the 6 m vertical step
    /// check's instance 6, 20 Hz, 5σ a fix: re-based 3 s into its 30 s);
    /// the mean says when the step ends.
    fn altitude_vote(&mut self, epv: f64, may_return: bool) -> (f64, bool) {
        let (Some(b), Some(z)) = (self.baro_gps_level.offset(0), self.track.offset(2)) else {
            return (f64::NAN, false);
        };
        let floor = if epv.is_finite() { epv } else { 0.0 };
        let zs = |(now, prev, s): (f64, f64, f64)| {
            let s = s.fmax(floor);
            (now / s, prev / s)
        };
        let ((bn, bp), (zn, zp)) = (zs(b), zs(z));
        // Called at the last fix, and now back by more than half of it (or
        // past its baseline).
        let back = |now: f64, prev: f64| prev.abs() > VOTE_Z && (now * prev < 0.0 || now.abs() < VOTE_BACK * prev.abs());
        if may_return && bp * zp > 0.0 && back(bn, bp) && back(zn, zp) {
            self.baro_gps_level.rebase_axis(0);
            self.track.rebase_axis(2);
            return (0.0, true);
        }
        (if bn * zn > 0.0 { bn.abs().fmin(zn.abs()) } else { 0.0 }, false)
    }

    /// A withheld baro is still off its levels: `baro_held` above 1, which
    /// is 1 at `FAR` σ off its level against the Doppler integral and
    /// `NEAR` σ off its level against the GPS altitude, both net of the
    /// motion's allowance (the smaller of the two; NaN while either level
    /// is too young to judge), at the last GPS epoch. A baro episode opens
    /// when both levels are `FAR` σ off (`tests`); it holds while the baro
    /// stays that far off the Doppler level, precise to decimetres over a
    /// minute, and still `NEAR` σ off the GPS altitude, whose metres of
    /// noise hid a step's offset once the 6 s windows had passed its jump
    /// (battery tune #1224: a 15 m step for 89 s under a 1 Hz Gauss–Markov
    /// receiver, flagged for its first 8 s). The Doppler level alone is no
    /// witness: it keeps the offset a vertical drag-off integrated, long
    /// after the GPS altitude came back onto the baro (tune #1292, #1486).
    ///
    /// `baro_held` is also at least the share of the baro's jump that its
    /// Doppler level still holds (`barojump`), 1 at half of it: the GPS
    /// altitude's noise may hide a step that its jump showed.
    fn baro_still_off(&self) -> bool {
        self.baro_held > 1.0
    }

    /// The level against the GPS altitude came back at this epoch (see
    /// `VelocityTrack::returned`): whose return it was. The baro's
    /// (`Some(true)`) when its level against the Doppler integral came
    /// back too, or jumped by the same amount (that level's baseline may
    /// have learnt a fault that was not flagged to its end: battery tune
    /// #232, a 9.4 m step whose last 4 s passed as normal, then 6 s of
    /// flags on its return). Else the GPS altitude's (`Some(false)`): it
    /// came back onto the baro while the Doppler integral, which carries
    /// no position fault and kept what a dragged velocity integrated, did
    /// not move (a GPS vertical step's or drag-off's end: tune #1427, a
    /// 0.41 m/s drag for 26 s from 13.7 s, whose 11 m return was judged as
    /// a step for 60 s). The baro's, too, when it jumped back by most of
    /// the jump that held it (`BaroJump::ended`).
    fn vertical_return(&self) -> Option<bool> {
        if self.baro_jump.ended() {
            return Some(true);
        }
        if !self.baro_gps_level.returned() {
            return None;
        }
        if self.baro_dop_level.returned() {
            return Some(true);
        }
        Some(match (self.baro_gps_level.offset(0), self.baro_dop_level.offset(0)) {
            (Some((g, gp, _)), Some((d, dp, sd))) => {
                let (jg, jd) = (g - gp, d - dp);
                (jd - jg).abs() < BARO_JUMP_AGREE * jg.abs() && (jd - jg).abs() < crate::track::NEAR * sd
            }
            _ => false,
        })
    }

    /// A position episode's jump confirmed, over the seconds after it, as
    /// a drag-off's end (see `dragend`): the track's level moved with the
    /// truth's return, so its baseline moves to the fix. The earliest
    /// onset of the drags confirmed (row s), if any.
    fn drag_ended(&mut self, t: f64, episode_active: bool) -> Option<f64> {
        let [h, v] = if episode_active { self.drag_end.confirmed(t, self.flight_time, self.rate.scale) } else { [f64::NAN; 2] };
        // The earlier onset, or either when one is NaN (not confirmed).
        let (since, h, v) = (h.fmin(v), !h.is_nan(), !v.is_nan());
        if h {
            self.track.rebase_axis(0);
            self.track.rebase_axis(1);
        }
        if v {
            self.track.rebase_axis(2);
        }
        // A jump for the ramp test too (see `unflagged_fault_ended`).
        if h || v {
            self.ramp.note_jump();
        }
        (h || v).then_some(since)
    }

    /// Whether the slow tests (the baro's drift, the position's ramp) are
    /// judging a fault.
    fn slow_judging(&self) -> [bool; 2] {
        [self.baro_drift.judging(), self.ramp.judging()]
    }

    /// A slow test that called at this epoch (it was not judging `before`,
    /// see `slow_judging`): when its fault began (row s, the fix's `t`
    /// less its age in true s) and the group it condemns (2 the baro, 0
    /// the position). The drift first: it is the baro's, and a vertical
    /// ramp it saw too is the same change.
    fn slow_onset(&self, before: [bool; 2], t: f64) -> Option<(f64, usize)> {
        let (age, g) = if !before[0] && self.baro_drift.judging() {
            // A stuck baro's onset is its run's start (`Dating::stuck`).
            if self.baro_flat.stuck() {
                return None;
            }
            (self.baro_drift.onset_age()?, 2)
        } else if !before[1] && self.ramp.judging() {
            (self.ramp.onset_age()?, 0)
        } else {
            return None;
        };
        Some((t - age / self.rate.scale, g))
    }

    /// A position episode that opened at this epoch, or an episode whose
    /// position was first withheld at it (`opened_on_position`), on a jump
    /// off the velocity track arms the drag-off's end
    /// confirmations, horizontal and vertical (see `dragend`); an episode
    /// that ended, or re-anchored, disarms them.
    #[cfg_attr(navguard_cold_size, optimize(size))]
    #[inline(never)]
    fn arm_drag_end(&mut self, t: f64, opened_on_position: bool, step: &EpisodeStep) {
        if !step.fault || step.reset {
            self.drag_end.disarm();
        } else if opened_on_position {
            self.drag_end.arm(t, self.track.jump());
        }
    }

    /// One prediction of `dt` s moved the filter's velocity from `v0` to
    /// `v1` (m/s), `on_imu` or on the constant-velocity model.
    fn advance(&mut self, dt: f64, v0: Vector3<f64>, v1: Vector3<f64>, flying: bool, on_imu: bool) {
        if flying {
            self.flight_time += dt;
        }
        self.alt_int -= 0.5 * (v0[2] + v1[2]) * dt;
        if on_imu {
            self.dv_imu += v1 - v0;
        } else {
            self.imu_gap = true;
        }
    }

    /// The tests stage: feed the fix to the position–velocity, baro–GPS and
    /// IMU consistency tests, decide whether the IMU test joins R, and close
    /// the epoch's indicators, given what the epoch already knows (`e`).
    /// Also returns whether the GPS altitude came back onto both its other
    /// references at this fix (see `altitude_vote`).
    #[cfg_attr(navguard_cold_size, optimize(size))]
    fn tests(&mut self, ind: &mut IndicatorEngine, fix: &Fix, e: EpochState) -> (Indicators, bool) {
        let (t, y) = (fix.t, fix.y);
        // The receiver's own time, when the log has it, measures the clock
        // whatever the vehicle does (inside episodes too).
        self.rate.observe_time(t, fix.gps_time);
        // Position–velocity consistency: the GPS's own position change
        // against the trapezoid of its velocities (filter-independent).
        // Not while the velocity is withheld: a biased velocity (degraded
        // fix, frozen or zeroed output) would fill the window with its own
        // bias and hold the test up after it clears. The velocity track
        // (`track`) integrates the same velocities, across short gaps too.
        let track_dt = match (&fix.vel, self.last_gps) {
            (Some(v), Some((pt, pp, pv))) if t - pt > 0.0 && t - pt < PV_MAX_DT_S => {
                if e.learn_rate {
                    self.rate.observe((pt, pp, pv), t, &y, v);
                }
                let dtg = (t - pt) * self.rate.scale;
                let u = core::array::from_fn(|a| (y[a] - pp[a]) - 0.5 * (v[a] + pv[a]) * dtg);
                ind.observe_pv(u, !e.vel_withheld);
                // A withheld velocity is suspect: nothing to integrate.
                if e.vel_withheld {
                    self.track.clear();
                    None
                } else {
                    self.track.step(dtg, y.into(), (*v).into(), pv.into());
                    Some(dtg)
                }
            }
            // A dropped record or two: the track integrates across the gap.
            (Some(v), Some((pt, _, pv))) if !e.vel_withheld && t - pt > 0.0 && t - pt < TRACK_MAX_GAP_S => {
                ind.clear_pv();
                let dt = (t - pt) * self.rate.scale;
                self.track.step(dt, y.into(), (*v).into(), pv.into());
                Some(dt)
            }
            _ => {
                ind.clear_pv();
                self.track.clear();
                None
            }
        };
        // The position ramping off its track (see `ramp`).
        // Not across a fix the receiver calls degraded: its position walks
        // off by design, and the walk's end would read as a ramp.
        let ramp = match (track_dt, self.track.d()) {
            (Some(dt), Some(d)) if !e.declared => self.ramp.push(dt, d, [fix.eph, fix.epv], e.speed_claim),
            _ => {
                self.ramp.clear();
                f64::NAN
            }
        };
        self.last_gps = fix.vel.map(|v| (t, y, v));
        let (drift, (to_gps, to_doppler)) = self.baro_levels(t, &y, fix.vel.as_ref(), e.vel_withheld, fix.epv, e.baro_withheld);
        // Baro against the GPS altitude (up), with the latest baro sample.
        if let Some((_, b)) = self.last_baro.filter(|(tb, _)| t - tb < 0.5) {
            ind.observe_baro_gps(t, b + y[2], fix.vel.as_ref().map_or([f64::NAN; 2], motion_of));
        }
        // IMU consistency: GPS horizontal velocity against the filter's
        // IMU-predicted velocity changes, only while every prediction since
        // the last epoch ran on the IMU.
        let imu_gap = self.imu_gap;
        if imu_gap {
            ind.clear_imu();
            self.imu_gap = false;
        }
        let z3 = fix.vel.filter(|_| !e.declared).map(|v| [v[0] - self.dv_imu[0], v[1] - self.dv_imu[1], v[2] - self.dv_imu[2]]);
        match z3 {
            Some(z) => ind.observe_imu(t, z),
            None => ind.clear_imu(),
        }
        // The same `z` measures a drag-off's end (see `dragend`); an IMU gap
        // left changes out of `dv_imu`, so it restarts there.
        self.drag_end.push(t, z3.filter(|_| !imu_gap && !e.vel_withheld));
        ind.set_imu_fold(e.imu_dense && self.flight_time >= IMU_ARM_S && ind.imu_learnt() >= IMU_ARM_WINDOWS);
        let mut out = ind.close_epoch();
        // The position ramping off its velocity track (see `ramp`).
        out.fold(0, ramp * RAMP_R_SCALE);
        // The fix jumping off its velocity track from on it (see
        // `VelocityTrack::departed`): a step's first fixes scored just under
        // the boundary fed the filter, which then followed the step (the
        // 10 m step check's instance 3: 7 of 299 epochs flagged; tune
        // #1644: a 17.6 m step, 517 epochs missed). Not across a fix the
        // receiver calls degraded, like the ramp test.
        if !e.declared {
            out.fold(0, self.track.departed() * TRACK_R_SCALE);
            // Its short mean's onset (`VelocityTrack::mean_departure`),
            // unless an offset was accepted: the track has not learnt it,
            // and the fault's end undoes it (`Episode::undone`).
            if !e.accepted {
                out.fold(0, self.track.mean_departure() * TRACK_R_SCALE);
            }
        }
        // The baro's level: condemned only when it left both references
        // (NaN, not judged, unless both are); and its drift over a long
        // window, against both (see `drift`).
        // A withheld baro is held to a lower bar (`baro_still_off`,
        // `baro_held`, computed with the levels).
        let dep = if e.baro_withheld { self.baro_held * GATE } else if to_gps.is_nan() || to_doppler.is_nan() { f64::NAN } else { to_gps.fmin(to_doppler) * GATE };
        out.fold(2, dep.fmax(drift * DRIFT_R_SCALE));
        // The baro's reading held bit for bit while it still arrives (a
        // baro that stops arriving is not judged on its last run).
        if self.last_baro.is_some_and(|(tb, _)| t - tb < 0.5) {
            out.fold(2, self.baro_flat.z() * FLAT_R_SCALE);
        }
        // The GPS altitude off both other vertical references the same way:
        // the baro (its level against the GPS altitude) and the GPS's own
        // vertical velocity integrated (the track's down axis). Two of three
        // agree, so the GPS position is condemned, not the baro; a baro
        // fault moves only the first, a vertical drag-off only the second.
        let (alt, alt_back) = self.altitude_vote(fix.epv, !e.mean_hold);
        out.fold(0, alt * VOTE_R_SCALE);
        // What these tests folded is the other tests' verdict, not the IMU's.
        for g in [0, 2] {
            ind.fold_unfolded(out.r_group[g]);
        }
        (out, alt_back)
    }
}

/// The decision stage's verdict on one GPS epoch, before the episode logic.
#[derive(Clone, Copy, Debug)]
struct Verdict {
    /// ANFIS input `[ln(1+R), C]`.
    x: [f64; 2],
    /// F-indicator, or the other method's score.
    f: f64,
    fault: bool,
    /// The other method's decision; None for the ANFIS.
    dec: Option<Decision>,
    /// Δr per group (position, velocity) for the `mahalanobis` windows.
    dr: [[f64; 3]; 2],
}

/// State of the detection methods other than the ANFIS (`config.method`).
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
struct Methods {
    /// Previous GPS epoch's innovations (pos, vel) for Δr; None after a
    /// (re)initialisation.
    prev_nu: Option<[f64; 6]>,
    /// Reference windows of the `mahalanobis` method (position, velocity).
    maha: [MahaWindow; 2],
    /// Largest-γ baro innovation (ν m, S m²) since the last GPS epoch.
    baro_inn: Option<(f64, f64)>,
    /// Threshold pool of the `rms`, `knee` and `adaptive` methods.
    pool: Option<PoolState>,
}

impl Methods {
    /// A baro sample's innovation (ν m, S m²): the epoch keeps its largest
    /// normalised one.
    fn note_baro(&mut self, nu: f64, s: f64) {
        let g = |(nu, s): (f64, f64)| nu.abs() / s.fmax(1e-12).sqrt();
        if self.baro_inn.is_none_or(|b| g((nu, s)) > g(b)) {
            self.baro_inn = Some((nu, s));
        }
    }

    /// The decision stage: the configured method's score for the epoch and
    /// whether it is a fault (`label` overrides it: the trainer's oracle).
    fn decide(&mut self, cfg: &Config, anfis: &Anfis, kf: &Kf, res: &Residuals, ind: &Indicators, label: Option<f64>) -> Verdict {
        let x = inputs(ind.r, ind.c);
        let (dec, dr) = self.other_method(cfg.method, kf, res);
        let f = dec.map_or_else(|| anfis.eval(&x), |d| d.score);
        let th = if dec.is_some() { 1.0 } else { cfg.threshold };
        let fault = match label {
            Some(l) => l >= 0.5,
            None => f >= th,
        };
        Verdict { x, f, fault, dec, dr }
    }

    /// Another method's decision on the same innovations (see `methods`)
    /// and Δr per group; nothing to build for the default ANFIS. Built for
    /// size in the core module: the default never needs its work.
    #[cfg_attr(navguard_cold_size, optimize(size))]
    fn other_method(&mut self, method: Method, kf: &Kf, res: &Residuals) -> (Option<Decision>, [[f64; 3]; 2]) {
        let baro = self.baro_inn.take();
        if method == Method::Anfis {
            return (None, [[f64::NAN; 3]; 2]);
        }
        let mut nu = [f64::NAN; 6];
        nu[..3].copy_from_slice(&res.pin.nu);
        let mut inn = EpochInnovations { nu, s: kf.pos_vel_covariance(), m: 3, baro };
        for a in 0..3 {
            inn.s[(a, a)] = res.pin.s[a];
        }
        if let Some(vin) = &res.vin {
            inn.m = 6;
            for a in 0..3 {
                inn.nu[3 + a] = vin.nu[a];
                inn.s[(3 + a, 3 + a)] = vin.s[a];
            }
        }
        let dr = core::array::from_fn(|g| {
            core::array::from_fn(|a| self.prev_nu.map_or(f64::NAN, |p| inn.nu[3 * g + a] - p[3 * g + a]))
        });
        self.prev_nu = Some(inn.nu);
        let dec = match method {
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
        };
        (dec, dr)
    }

    /// A normal epoch: the `mahalanobis` reference windows learn its Δr.
    fn learn_normal(&mut self, method: Method, dr: [[f64; 3]; 2]) {
        if method == Method::Mahalanobis {
            for g in 0..2 {
                self.maha[g].push(dr[g]);
            }
        }
    }
}

/// What the gating stage judges departures on at one GPS epoch.
#[derive(Clone, Copy, Debug)]
struct Evidence<'a> {
    ind: &'a Indicators,
    /// The GPS velocity group's own R (`IndicatorEngine::r_vel_unfolded`).
    r_vel: f64,
    /// Receiver incoherence (`IndicatorEngine::incoherence`).
    incoherence: f64,
    /// The other method's decision; None for the ANFIS.
    dec: Option<&'a Decision>,
    /// This epoch's residuals (for the episode's ends).
    res: &'a Residuals,
    /// Learnt σ_Δ of the position axes, m.
    sigma_pos: [f64; 3],
    /// The fix sits on its own velocity track (`VelocityTrack::on_track`).
    on_track: bool,
    /// The position's wander about its velocity track per axis, m
    /// (`VelocityTrack::sigmas`).
    sigma_track: [f64; 3],
    /// The baro is still off its levels (`Consistency::baro_still_off`).
    baro_off: bool,
}

impl Evidence<'_> {
    /// Group `g` departed at this epoch: its R above the gate. The GPS
    /// velocity is judged on its own R: the IMU consistency folded into the
    /// group's R condemns the IMU, not the GPS.
    fn departed(&self, g: usize) -> bool {
        let r = if g == 1 { self.r_vel } else { self.ind.r_group[g] };
        r.is_finite() && r > GATE
    }
}

/// Which sensor groups (GPS position, GPS velocity, baro) the filter is not
/// fed: the gating stage's state.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
struct Withheld {
    groups: [bool; GROUPS],
    /// Consecutive baro samples consistent with the filter while withheld.
    baro_calm: u32,
}

impl Withheld {
    fn gps_pos(&self) -> bool {
        self.groups[0]
    }

    fn gps_vel(&self) -> bool {
        self.groups[1]
    }

    fn baro(&self) -> bool {
        self.groups[2]
    }

    /// Feed every group again (normal verdict, re-anchoring, data gap). The
    /// baro's calm count restarts at the next baro sample that is fed.
    #[cfg_attr(navguard_cold_size, optimize(size))]
    fn release(&mut self) {
        self.groups = [false; GROUPS];
    }

    /// The gating stage, at a fault epoch: withhold the groups that
    /// departed, and those that failed the method's own test. Fault memory:
    /// a group that departed stays withheld for the rest of the episode, so
    /// a fault that flickers around the gate cannot leak into the filter; a
    /// group that never departed (GPS velocity during a position step or
    /// ramp) keeps aiding it, which keeps the coast drift, and so the
    /// departure's normalisation, small. GPS position and velocity come from
    /// one receiver, so each can take the other with it (below).
    #[cfg_attr(navguard_cold_size, optimize(size))]
    #[inline(never)]
    fn withhold(&mut self, ev: &Evidence) {
        for g in 0..GROUPS {
            self.groups[g] |= ev.departed(g);
        }
        if let Some(d) = ev.dec {
            for g in 0..GROUPS {
                self.groups[g] |= d.failed[g];
            }
        }
        if self.groups[1] && !self.groups[0] && ev.ind.r_group[0] > 1.5 {
            // Bad GPS velocity with a position residual off its clean
            // level: same receiver, do not let it re-anchor the estimate.
            self.groups[0] = true;
        }
        if self.groups[0] && ev.incoherence > INCOHERENT {
            // Position departed and the receiver's own position and
            // velocity disagree epoch after epoch: its velocity is no
            // better than its position (degraded fix).
            self.groups[1] = true;
        }
    }

    /// Feed the baro again (it was withheld for a fault that is over).
    fn release_baro(&mut self) {
        self.groups[2] = false;
        self.baro_calm = 0;
    }

    /// `release`, but a withheld baro still off its levels or its jump
    /// (`baro_off`, see `Consistency::baro_still_off`) stays withheld: the
    /// end of a GPS episode, or the filter re-anchored on the GPS, does not
    /// end the baro's fault (battery tune #1608: a 12 m step held by its
    /// jump was released when a GPS return ended the episode 22 s in, and
    /// its end, 27 s later, was judged as a drift for 50 s).
    fn release_unless_baro_off(&mut self, baro_off: bool) {
        let baro = baro_off && self.baro();
        self.release();
        self.groups[2] = baro;
    }

    /// A baro sample with consistency `cons` (see `indicators`): a withheld
    /// baro that follows the filter's climb again for a few samples is
    /// released. Returns whether it was released on this sample.
    fn baro_released(&mut self, cons: f64) -> bool {
        if !self.groups[2] {
            self.baro_calm = 0;
            return false;
        }
        self.baro_calm = if cons < BARO_RECOVER { self.baro_calm + 1 } else { 0 };
        if self.baro_calm < RECOVER_EPOCHS {
            return false;
        }
        self.baro_calm = 0;
        self.groups[2] = false;
        true
    }

    /// The filter update stage: feed the fix's groups that are not
    /// withheld, with σ scaled by `k` (see `ReceiverQuality`); the
    /// indicator engine learns each fed axis' posterior residual. A failed
    /// update leaves the rest unfed.
    fn feed(&self, kf: &mut Kf, ind: &mut IndicatorEngine, fix: &Fix, prev_r: &[f64; 6], k: f64) -> Result<(), FilterError> {
        if !self.gps_pos() {
            kf.update_position_scaled(&fix.y, k)?;
            let p = kf.position();
            for a in 0..3 {
                ind.accept(a, prev_r[a], kf.position_var(a), fix.y[a] - p[a]);
            }
        } else {
            (0..3).for_each(|a| ind.learn_withheld(a, prev_r[a]));
        }
        match (&fix.vel, self.gps_vel()) {
            (Some(v), false) => {
                kf.update_velocity_scaled(v, k)?;
                let vel = kf.velocity();
                for a in 0..3 {
                    ind.accept(3 + a, prev_r[3 + a], kf.velocity_var(a), v[a] - vel[a]);
                }
            }
            (Some(_), true) => (3..6).for_each(|a| ind.learn_withheld(a, prev_r[a])),
            (None, _) => {}
        }
        Ok(())
    }
}

/// `Consistency::baro_held` from the baro's departures from its
/// GPS-altitude and Doppler levels (`VelocityTrack::departure_net`, 1 at
/// `FAR` σ): 1 at `NEAR` σ off the first and `FAR` σ off the second.
fn held_departure(to_gps: f64, to_doppler: f64) -> f64 {
    if to_gps.is_nan() || to_doppler.is_nan() {
        return f64::NAN;
    }
    (to_gps * crate::track::FAR / crate::track::NEAR).fmin(to_doppler)
}

/// A baro fault is over (a stuck baro reads again, or the baro came back
/// onto its levels): what the baro's windows, its Δr reference and the
/// filter's baro offset hold is the fault's, so they restart, and the baro
/// is fed again.
#[cfg_attr(navguard_cold_size, optimize(size))]
#[inline(never)]
fn restart_baro(kf: Option<&mut Kf>, ind: &mut IndicatorEngine, withheld: &mut Withheld, last_est: &mut LastEstimate) {
    ind.reset_axis(6);
    ind.clear_baro();
    ind.clear_baro_gps();
    withheld.release_baro();
    if let Some(kf) = kf {
        kf.reset_baro();
    }
    last_est.baro_h = None;
}

/// The motion a baro's healthy error follows, from a velocity (NED m/s):
/// horizontal speed² (m/s)² and climb rate (m/s, up).
fn motion_of(v: &Vector3<f64>) -> [f64; 2] {
    [v[0] * v[0] + v[1] * v[1], -v[2]]
}

/// The baro's filter update; the indicator engine learns the posterior
/// residual (`prev_r`: the axis' previous one), and the baro test learns
/// its σ from samples under a `normal` verdict.
fn feed_baro(kf: &mut Kf, ind: &mut IndicatorEngine, baro: f64, prev_r: f64, normal: bool) -> Result<(), FilterError> {
    kf.update_baro(baro)?;
    let p_post = kf.baro_height_var();
    let post = kf.baro_innovation(baro).nu[0];
    ind.accept(6, prev_r, p_post, post);
    if normal {
        ind.accept_baro();
    }
    Ok(())
}

/// How long a slow fault's call is kept for its jump back after its test
/// stopped judging it, row s (see `Dating::slow`): the release comes on the
/// smoothed level, a smoothing's time (2 s) after the jump.
#[cfg(feature = "dated")]
const SLOW_GRACE_S: f64 = 5.0;

/// When the faults a detector saw end, without flagging them throughout,
/// began (issue 14 item 4: `Detector::retro_since`): the audit's
/// reconciled verdict labels the rows from then to the end as the fault;
/// the causal verdict is untouched. Only with the `dated` feature: the
/// core wasm module is the streaming API, whose verdict is causal, and
/// leaves the dating to the audit and lab modules; without the feature
/// `Dating` is an empty struct whose methods do nothing.
#[cfg(feature = "dated")]
#[derive(Clone, Debug, Default)]
struct Dating {
    /// When the fault whose offset is `Episode::accepted` began (row s), if
    /// known: the first fault epoch of the episode that coasted out onto
    /// it. None for an offset kept at a jump read as a fault's end
    /// (`ended_off_track`, `unflagged_fault_ended`, a drag-off's end), whose
    /// onset nothing dates: on the battery, dating those by the episode or
    /// the jump put most of the spans they gave on healthy epochs. Not in
    /// snapshots: a restored detector keeps the offset but cannot date it.
    accepted_since: Option<f64>,
    /// The onset (row s) of the fault that ended at this row, if dated: a
    /// coasted-out offset undone, or a drag-off's end, whose age its
    /// velocity's jump tells; or a slow fault's, called earlier, whose
    /// offset jumped back at this row (see `slow`). It lives one row.
    retro: Option<f64>,
    /// The group (`DRIVER_NAMES`) and the kind (`kind`) of the fault
    /// `retro` dates.
    group: usize,
    kind: u8,
    /// The baro's stuck run being called is dated (once per run).
    stuck_dated: bool,
    /// A slow fault called, dated only when the GPS or the baro then
    /// jumps back (`slow_epoch`): the offset that grew was the fault's,
    /// undone at once. A slow test's false call on a wandering healthy
    /// error fades instead (battery tune #1006, eval #102: dated from the
    /// call, 30 and 16 s of healthy epochs each).
    slow: Option<SlowCall>,
}

/// A slow fault called (see `Consistency::slow_onset`), row s.
#[cfg(feature = "dated")]
#[derive(Clone, Copy, Debug)]
struct SlowCall {
    /// Its onset.
    since: f64,
    /// Its group (`DRIVER_NAMES`).
    group: usize,
    /// The last row its test judged it.
    last: f64,
}

#[cfg(feature = "dated")]
impl Dating {
    /// A new row: nothing dated yet.
    fn clear(&mut self) {
        self.retro = None;
        self.group = 0;
        self.kind = kind::RESIDUAL;
    }

    /// An offset is kept (`Episode::accepted`) whose fault began at `since`.
    fn kept(&mut self, since: Option<f64>) {
        self.accepted_since = since;
    }

    /// The kept offset was undone at `t` (s): its fault is dated when its
    /// onset is known and no older than the longest a position episode is
    /// judged (`POSITION_COAST_LONG_S`). Past that, the jump that undoes
    /// it is as likely another fault's (battery eval #291 and #27: offsets
    /// kept 147 and 192 s through baro steps, then matched by a degraded
    /// fix's end and a frozen fix's).
    fn undone(&mut self, t: f64) {
        self.retro = self.accepted_since.filter(|since| t - since <= POSITION_COAST_LONG_S);
    }

    /// A fault that began at `since` (row s) ended at this row.
    fn date(&mut self, since: f64) {
        self.retro = Some(since);
    }

    /// A slow fault of group `g` called at row `t` (s) began at the row s
    /// `onset` gives, if any (only evaluated with the feature: the
    /// onset's fit is no part of the streaming module). The earliest
    /// call's onset is kept while its test judges (see `slow`).
    fn called(&mut self, t: f64, onset: impl FnOnce() -> Option<(f64, usize)>) {
        if self.slow.is_none() {
            self.slow = onset().map(|(since, group)| SlowCall { since, group, last: t });
        }
    }

    /// At row `t` (s), `at` gives whether a slow test judges a fault and
    /// whether the GPS or the baro jumped back. A call is forgotten
    /// `SLOW_GRACE_S` after its test stopped judging without a jump back;
    /// a jump back dates it from its onset to here (unless a fault that
    /// ended here began earlier).
    fn slow_epoch(&mut self, t: f64, at: impl FnOnce() -> (bool, bool)) {
        let Some(call) = self.slow.as_mut() else { return };
        let (judging, back) = at();
        if judging {
            call.last = t;
        } else if t - call.last > SLOW_GRACE_S {
            self.slow = None;
            return;
        }
        if back {
            let call = *call;
            self.slow = None;
            if self.retro.is_none_or(|r| call.since < r) {
                (self.retro, self.group) = (Some(call.since), call.group);
            }
        }
    }

    /// `at` gives (`t`, `last_fix`, `gps_dt`, `silence`, `kind`), read only
    /// with the feature: no fresh fix has come since row s `last_fix`, and
    /// `kind` (an outage or a stale fix) is called at row `t`. The receiver
    /// went silent, or repeated its fix, from the next fix it owed (half a
    /// GPS period `gps_dt` s on), and at most the `silence` s that make an
    /// outage back (a silence on the ground is none: real log 09-10 at 201.6 s,
    /// called 3.1 s later, once flying). Not when it owed none before (an
    /// outage the receiver's status declared at once).
    fn silent(&mut self, at: impl FnOnce() -> (f64, f64, f64, f64, u8)) {
        let (t, last_fix, gps_dt, silence, kind) = at();
        if t - last_fix > 1.5 * gps_dt {
            (self.retro, self.kind) = (Some((last_fix + 0.5 * gps_dt).fmax(t - silence)), kind);
        }
    }

    /// `at` gives whether, at a fault verdict, the baro's reading is held
    /// (`stuck`), and since its run's first sample at row s `since`. Dated
    /// once per run: the run is the fault, from its start (a repeat is
    /// certain, not a fit).
    fn stuck(&mut self, at: impl FnOnce() -> (bool, f64)) {
        let (stuck, since) = at();
        if stuck && !self.stuck_dated {
            (self.retro, self.group) = (Some(since), 2);
        }
        self.stuck_dated = stuck;
    }

    fn since(&self) -> Option<f64> {
        self.retro
    }

    fn group(&self) -> usize {
        self.group
    }

    fn kind(&self) -> u8 {
        self.kind
    }
}

/// Without the `dated` feature: nothing is dated (see above).
#[cfg(not(feature = "dated"))]
#[derive(Clone, Debug, Default)]
struct Dating;

#[cfg(not(feature = "dated"))]
impl Dating {
    fn clear(&mut self) {}
    fn kept(&mut self, _: Option<f64>) {}
    fn undone(&mut self, _: f64) {}
    fn date(&mut self, _: f64) {}
    fn called(&mut self, _: f64, _: impl FnOnce() -> Option<(f64, usize)>) {}
    fn slow_epoch(&mut self, _: f64, _: impl FnOnce() -> (bool, bool)) {}
    fn silent(&mut self, _: impl FnOnce() -> (f64, f64, f64, f64, u8)) {}
    fn stuck(&mut self, _: impl FnOnce() -> (bool, f64)) {}
    fn since(&self) -> Option<f64> {
        None
    }
    fn group(&self) -> usize {
        0
    }
    fn kind(&self) -> u8 {
        kind::RESIDUAL
    }
}

/// A fault episode: from the first fault verdict (or outage) to the epoch
/// that ends it, with the groups it withholds.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
struct Episode {
    /// Inside a fault episode; `imu`: the IMU consistency drove its first
    /// verdict. Any other episode restarts the IMU window at every epoch, so
    /// the GPS velocities of an outage or a GPS fault never sit in the
    /// window that judges the clean epochs after it.
    active: bool,
    imu: bool,
    /// Consecutive IMU-episode epochs whose last second was calm.
    imu_calm: u32,
    /// When the filter began to coast (the first fault epoch, or the last
    /// fix before an outage), s.
    coast_start: Option<f64>,
    /// Consecutive fault epochs whose GPS agrees with the filter.
    calm_epochs: u32,
    /// The episode withheld the GPS velocity or was an outage: the filter
    /// has coasted on the IMU alone.
    receiver_lost: bool,
    /// Consecutive normal GPS verdicts.
    normal_run: u32,
    withheld: Withheld,
    /// The position offset (m, NED) a position-only episode re-anchored
    /// onto when it coasted out: the fault the filter stopped judging. A
    /// later jump that undoes it is that fault's end, not a new one.
    accepted: Option<[f64; 3]>,
    /// When the faults it saw end began (see `Dating`). Not in snapshots.
    #[serde(skip)]
    dating: Dating,
    /// The position jump that opened this episode was no drag-off's end
    /// (`DragEnds::ruled_out`): it is judged for `POSITION_COAST_LONG_S`.
    long_coast: bool,
    /// The position was withheld on a step's onset (`step_onset`): the
    /// fix's offset off the coasted filter is then the fault's evidence
    /// (`Episode::held`).
    fresh: bool,
    /// The episode opened on the fix's short mean leaving its velocity
    /// track (`VelocityTrack::mean_departure`): it holds while the mean
    /// stays off.
    mean_hold: bool,
}

/// What the episode stage decided at a GPS epoch.
#[derive(Clone, Copy, Debug, PartialEq)]
struct EpisodeStep {
    /// The epoch's verdict is a fault.
    fault: bool,
    /// Re-anchor the filter on this fix (coasted too long, or recovered).
    reset: bool,
    /// The episode ended on the GPS's return (`Episode::returned`).
    returned: bool,
}

impl Episode {
    /// A row without a fix declared an outage.
    #[cfg_attr(navguard_cold_size, optimize(size))]
    #[inline(never)]
    fn outage(&mut self, last_fix: Option<f64>) {
        self.active = true;
        self.imu = false;
        // The filter coasts; the first fix back is judged against it.
        self.receiver_lost = true;
        if self.coast_start.is_none() {
            self.coast_start = last_fix;
        }
    }

    /// The episode stage, first half: a fault verdict opens an episode (or
    /// continues one), an IMU episode ends once the IMU is calm again, and a
    /// normal verdict closes it. Returns whether the epoch stays a fault.
    #[cfg_attr(navguard_cold_size, optimize(size))]
    #[inline(never)]
    fn open(&mut self, fault: bool, ind: &mut IndicatorEngine, oracle: bool) -> bool {
        let mut fault = fault;
        if fault {
            if !self.active {
                self.active = true;
                // The IMU test alone: no other group departed (a zeroed or
                // frozen GPS velocity also fails it, but the Δr test sees it too).
                self.imu = ind.imu_folded() && ind.r_unfolded() < GATE;
            }
            if !self.imu {
                ind.clear_imu();
            } else if !oracle && ind.r_unfolded() < GATE {
                // The 3 s window still spans the fault for 3 s after it
                // ends; the last second says sooner whether z still drifts.
                // Calm for a few epochs: the episode is over, and the window
                // restarts on post-fault data.
                let calm = ind.imu_recent(IMU_RECENT_S) < IMU_CALM;
                self.imu_calm = if calm { self.imu_calm + 1 } else { 0 };
                if self.imu_calm >= RECOVER_EPOCHS {
                    fault = false;
                    ind.clear_imu();
                }
            }
        }
        if !fault {
            self.active = false;
            self.imu = false;
            self.imu_calm = 0;
        }
        fault
    }

    /// The episode stage, second half, with the gating stage inside it: a
    /// fault epoch withholds what departed and may end the episode by
    /// re-anchoring (past `max_coast` s, or recovered); a normal one
    /// releases every group.
    #[cfg_attr(navguard_cold_size, optimize(size))]
    fn step(&mut self, t: f64, fault: bool, ev: &Evidence, max_coast: f64, oracle: bool) -> EpisodeStep {
        if !fault {
            self.ended_off_track(ev);
            self.normal_epoch(ev.baro_off);
            return EpisodeStep { fault: false, reset: false, returned: false };
        }
        let start = *self.coast_start.get_or_insert(t);
        self.withheld.withhold(ev);
        self.normal_run = 0;
        if self.withheld.gps_vel() {
            self.receiver_lost = true;
        }
        let coasted_out = t - start > self.coast_limit(max_coast);
        let returned = !oracle && self.returned(ev);
        if returned && self.accepted.is_some() {
            self.dating.undone(t);
        }
        let ended = !oracle && (self.recovered(t - start, ev, oracle) || returned);
        if returned {
            self.accepted = None;
        } else if ended {
            // Recovered with the fix still off: see `ended_off_track`.
            self.ended_off_track(ev);
        }
        if coasted_out && !ended && self.withheld.gps_pos() && !self.receiver_lost && !self.imu {
            self.accepted = Some(ev.res.pin.nu);
            self.dating.kept(Some(start));
        }
        EpisodeStep { fault: !ended, reset: coasted_out || ended, returned }
    }

    /// A position-only episode that ended (a normal verdict, or recovered)
    /// while the fix is still `KEEP_MIN_SIGMAS` σ off the coasted filter:
    /// the verdict's windows let a persisting step pass (battery tune #599:
    /// a 6.4 m step under a 0.47 m receiver, flagged for one epoch), or the
    /// recovery took it for the filter's drift (tune #551: a 15.6 m
    /// vertical step, recovered 7 s in), and the filter follows it. Its
    /// offset is kept like a coasted-out episode's, so the step's own end
    /// undoes it instead of opening a new episode.
    ///
    /// Built for size in the core module (issue 15's budget: it pays for
    /// the `Dating` hooks around it).
    #[cfg_attr(navguard_cold_size, optimize(size))]
    fn ended_off_track(&mut self, ev: &Evidence) {
        if self.off_sigmas(&ev.res.pin.nu, &ev.sigma_pos, &ev.sigma_track) > KEEP_MIN_SIGMAS {
            self.accept(ev.res.pin.nu);
        }
    }

    /// Keep `nu` (m) as the offset of a fault no longer judged, whose
    /// onset is not known (see `Dating::accepted_since`).
    fn accept(&mut self, nu: [f64; 3]) {
        self.accepted = Some(nu);
        self.dating.kept(None);
    }

    /// The position group's R from the fix's offset `nu` (m) off the
    /// coasted filter (`off_sigmas`, scaled by `HOLD_R_SCALE`) in an
    /// episode that opened on a step's onset; NaN otherwise.
    #[cfg_attr(navguard_cold_size, optimize(size))]
    fn held(&self, nu: &[f64; 3], sigma_pos: &[f64; 3], sigma_track: &[f64; 3]) -> f64 {
        if self.fresh { self.off_sigmas(nu, sigma_pos, sigma_track) * HOLD_R_SCALE } else { f64::NAN }
    }

    /// `along_sigmas` in a position-only episode; NaN otherwise (the
    /// filter's offset after a whole-receiver or IMU coast is its own
    /// drift).
    fn off_sigmas(&self, nu: &[f64; 3], sigma_pos: &[f64; 3], sigma_track: &[f64; 3]) -> f64 {
        if !self.withheld.gps_pos() || self.receiver_lost || self.imu {
            return f64::NAN;
        }
        along_sigmas(nu, sigma_pos, sigma_track)
    }

    /// How long the episode may coast, s: an IMU-only coast (the whole
    /// receiver withheld) `max_coast`; a position-only one, judged against
    /// the GPS velocity integrated, `POSITION_COAST_S`.
    fn coast_limit(&self, max_coast: f64) -> f64 {
        if self.receiver_lost {
            max_coast
        } else {
            max_coast.fmax(if self.long_coast { POSITION_COAST_LONG_S } else { POSITION_COAST_S })
        }
    }

    /// A return jump ends a position-only episode: in one epoch the GPS
    /// position came back to where the last accepted epoch had it, undoing
    /// most of the offset along its direction (projecting ignores the
    /// estimate's drift across it, such as its height while a horizontal
    /// step is withheld). The GPS is the truth again: re-anchor on it
    /// rather than read the estimate's coast drift as a new fault. The
    /// offset is the one since the episode began or, when an earlier
    /// episode of the same fault coasted out and re-anchored onto the
    /// faulty fix, that one's offset added to it.
    fn returned(&self, ev: &Evidence) -> bool {
        if !self.withheld.gps_pos() || self.receiver_lost || self.imu {
            return false;
        }
        let res = ev.res;
        let since: [f64; 3] = core::array::from_fn(|a| res.prev_r[a] - res.r_ref[a]);
        let jump: [f64; 3] = core::array::from_fn(|a| res.pin.nu[a] - res.prev_r[a]);
        let min2 = RETURN_MIN_SIGMAS * RETURN_MIN_SIGMAS * ev.sigma_pos.iter().map(|x| x * x).sum::<f64>();
        let with_accepted = self.accepted.map(|acc| core::array::from_fn(|a| since[a] + acc[a]));
        [Some(since), with_accepted].into_iter().flatten().any(|off| undoes(&jump, &off, min2))
    }

    /// Outside any episode: the GPS jumped back by most of the offset a
    /// coasted-out position episode re-anchored onto: the fault it stopped
    /// judging ended. Forgets the offset once undone.
    fn undone(&mut self, t: f64, res: &Residuals) -> bool {
        let back = self.accepted.is_some_and(|off| undoes(&res.pin.nu, &off, 0.0));
        if back {
            self.accepted = None;
            self.dating.undone(t);
        }
        back
    }

    /// Whether the episode, `elapsed` s old, is over and the filter should
    /// re-anchor on GPS. When the whole receiver was withheld (outage,
    /// degraded fix) the filter coasted on the IMU alone and the position
    /// offset is its own drift, whatever its size: recover on agreement of
    /// the increments and a clean velocity. When only the position was
    /// withheld (velocity kept aiding), a large offset is the fault itself
    /// (a persisting step) and is kept until `maxCoast`. A position-only
    /// episode also needs the position–velocity test back in its clean
    /// range, so a ramp that paused the verdict is not re-anchored on. An
    /// IMU episode ends when the IMU agrees with the GPS again (`open`), not
    /// by re-anchoring on a GPS that never departed.
    fn recovered(&mut self, elapsed: f64, ev: &Evidence, oracle: bool) -> bool {
        let ind = ev.ind;
        let offset_ok = if self.receiver_lost {
            !(ind.r_group[1] > RECOVER_R)
        } else {
            // Or the GPS never left its own velocity track: the filter
            // drifted (a stuck baro pulled its height), not the GPS.
            (!(ind.r_group[0] > RECOVER_R) && !(ind.pv > RECOVER_PV)) || ev.on_track
        };
        let calm = (0..2).all(|g| !(ind.inc_group[g] > RECOVER_INC)) && offset_ok && !ev.departed(2) && !(self.withheld.baro() && ev.baro_off);
        self.calm_epochs = if calm { self.calm_epochs + 1 } else { 0 };
        !oracle && !self.imu && self.calm_epochs >= RECOVER_EPOCHS && elapsed > 0.5
    }

    /// A normal GPS verdict; `baro_off`: the baro is still off (see
    /// `Withheld::release_unless_baro_off`).
    fn normal_epoch(&mut self, baro_off: bool) {
        self.calm_epochs = 0;
        self.coast_start = None;
        self.long_coast = false;
        self.withheld.release_unless_baro_off(baro_off);
        // A single normal verdict inside a coast does not end it: the
        // filter's offset is still the coast's until the GPS has been
        // accepted for a few epochs.
        self.normal_run += 1;
        if self.normal_run >= RECOVER_EPOCHS {
            self.receiver_lost = false;
        }
    }

    /// The filter was re-anchored on GPS: nothing coasts any more.
    /// `baro_off`: the baro is still off (see `Withheld::release_unless_baro_off`).
    #[cfg_attr(navguard_cold_size, optimize(size))]
    #[inline(never)]
    fn reanchored(&mut self, baro_off: bool) {
        self.coast_start = None;
        self.calm_epochs = 0;
        self.long_coast = false;
        self.withheld.release_unless_baro_off(baro_off);
        self.receiver_lost = false;
    }
}

/// The online-learning state (eqs. 15–20): the ANFIS, its databases, and
/// the validation set a retrained ANFIS must not do worse on.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Learning {
    anfis: Anfis,
    d1: Ring,
    d2: Ring,
    /// D2 entries since the last retraining.
    new_faults: usize,
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
    cost: RetrainCost,
}

impl Learning {
    #[cfg_attr(navguard_cold_size, optimize(size))]
    #[inline(never)]
    fn new(model: &Model, q: usize) -> Self {
        Learning {
            anfis: model.anfis.clone(),
            d1: Ring::new(q, &model.d1),
            d2: Ring::new(q, &model.d2),
            new_faults: 0,
            train_x: Vec::with_capacity(2 * q),
            train_y: Vec::with_capacity(2 * q),
            d0_x: model.d1.iter().chain(model.d2.iter()).copied().collect(),
            d0_y: model.d1.iter().map(|_| 0.0).chain(model.d2.iter().map(|_| 1.0)).collect(),
            cost: RetrainCost::default(),
        }
    }

    /// TC new D2 samples, and enough of them to pay for the retrain (see
    /// [`RETRAIN_SAMPLES_PER_NEW`]).
    fn retrain_due(&self, tc: usize) -> bool {
        self.new_faults >= tc && self.new_faults.saturating_mul(RETRAIN_SAMPLES_PER_NEW) >= self.retrain_samples()
    }

    /// Samples one retrain touches: D1 ∪ D2 and D0.
    fn retrain_samples(&self) -> usize {
        self.d1.items().len() + self.d2.items().len() + self.d0_x.len()
    }

    /// File an ANFIS epoch (input `x`, F-indicator `f`) by its own verdict
    /// (eqs. 15–20), but only a confident one: a fault verdict with
    /// F ≥ 0.8 and a fault signature, a normal one with F ≤ 0.2. Borderline
    /// verdicts, where a false alarm would sit, are not fed back, so
    /// retraining cannot teach itself its own mistakes.
    fn file(&mut self, fault: bool, f: f64, x: [f64; 2], ind: &Indicators) {
        if fault {
            if f >= CONFIDENT_FAULT && has_signature(ind.r, ind.c) {
                self.d2.push(x);
                self.new_faults += 1;
            }
        } else if f <= CONFIDENT_NORMAL {
            self.d1.push(x);
        }
    }
}

impl Detector {
    /// Detector with the config's model, or the embedded default.
    #[inline]
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
        det.methods.pool = pool;
        Ok(det)
    }

    /// Detector with an explicit model (the config's `model` field is ignored).
    #[inline]
    #[cfg_attr(navguard_cold_size, optimize(size))]
    pub fn with_model(cfg: Config, model: &Model) -> Self {
        Detector {
            kf: None,
            anchor: None,
            imu: None,
            ind: IndicatorEngine::new(cfg.indicator_settings()),
            clock: Clock::new(),
            imu_noise: ImuNoise::default(),
            last_est: LastEstimate { pos: Vector3::zeros(), vel: Vector3::zeros(), baro_h: None },
            consistency: Consistency::new(),
            quality: ReceiverQuality::default(),
            episode: Episode::default(),
            methods: Methods::default(),
            learning: Learning::new(model, cfg.q),
            resid: [f64::NAN; 7],
            last: Output { kind: kind::NO_GPS, driver: 255, ..Output::default() },
            last_ind: Indicators::default(),
            stats: Stats::default(),
            oracle: false,
            upset_until: f64::NAN,
            bias_calm: [0.0; 3],
            cfg,
        }
    }

    /// After deserializing a snapshot: check the config and every buffer's
    /// shape against a fresh detector of that config (so a corrupt or forged
    /// snapshot is an error, not an index panic later), and restore the
    /// scratch buffers that snapshots do not carry.
    #[inline]
    #[cfg_attr(navguard_cold_size, optimize(size))]
    pub(crate) fn check_restored(&mut self) -> Result<(), String> {
        let checked = self.cfg.to_input().check()?;
        if checked != self.cfg {
            return Err("config does not validate to itself".into());
        }
        let q = self.cfg.q;
        let l = &mut self.learning;
        l.d1.check_shape(q, "D1")?;
        l.d2.check_shape(q, "D2")?;
        self.ind.check_shape(&self.cfg.indicator_settings())?;
        if l.d0_x.len() != l.d0_y.len() {
            return Err(format!("D0: {} samples but {} labels", l.d0_x.len(), l.d0_y.len()));
        }
        crate::model::check_anfis(&l.anfis).map_err(|e| format!("anfis: {e}"))?;
        self.consistency.baro_flat.check()?;
        for w in &self.methods.maha {
            w.check_shape()?;
        }
        let pooled = matches!(self.cfg.method, Method::Rms | Method::Knee | Method::Adaptive);
        match &self.methods.pool {
            Some(p) if pooled => p.eval.check_shape()?,
            None if !pooled => {}
            _ => {
                return Err(format!(
                    "threshold pool present/absent does not match method \"{}\"",
                    self.cfg.method.name()
                ))
            }
        }
        l.train_x = Vec::with_capacity(2 * q);
        l.train_y = Vec::with_capacity(2 * q);
        Ok(())
    }

    #[cfg(all(test, not(target_arch = "wasm32")))]
    pub(crate) fn forge_ring_head_for_test(&mut self, head: usize) {
        self.learning.d1.head = head;
    }

    /// Teacher forcing for building training data: decisions follow the
    /// row's `label` instead of the ANFIS (used by the model trainer only).
    pub fn set_oracle(&mut self, on: bool) {
        self.oracle = on;
    }

    /// The checked config this detector runs.
    pub fn config(&self) -> &Config {
        &self.cfg
    }

    /// Counters since the detector was made (rows, epochs, retrains, resets).
    pub fn stats(&self) -> Stats {
        self.stats
    }

    /// The current ANFIS (after any online retraining).
    pub fn anfis(&self) -> &Anfis {
        &self.learning.anfis
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

    /// The indicator engine (learnt σ_Δ per axis and the windows), for
    /// diagnosis.
    pub fn indicator_engine(&self) -> &IndicatorEngine {
        &self.ind
    }

    /// The learnt boot-clock rate: true seconds per log second (1 until
    /// learnt, or when 1 is within the estimate's noise).
    pub fn clock_rate(&self) -> f64 {
        self.consistency.rate.scale
    }

    /// When the last `push` ended a fault that was not flagged throughout
    /// (an offset the detector stopped judging, undone by the GPS's jump
    /// back; a drag-off's end, its age told by its velocity's jump; or a
    /// slow drift or ramp, called late, whose offset jumped back here):
    /// the row time (s) the fault began. For a whole-log audit's
    /// reconciled verdict, which labels the rows from then to this one as
    /// the fault; the causal `status` is untouched.
    pub fn retro_since(&self) -> Option<f64> {
        self.episode.dating.since()
    }

    /// The group (index into `indicators::DRIVER_NAMES`) of the fault
    /// `retro_since` dates: the position's, or the baro's for a baro drift
    /// (or a vertical drag-off the baro drift test called).
    pub fn retro_group(&self) -> usize {
        self.episode.dating.group()
    }

    /// The kind (`kind`) of the fault `retro_since` dates: `RESIDUAL`, or
    /// `OUTAGE` or `STALE` for the silence before an outage or a stale fix
    /// was called.
    pub fn retro_kind(&self) -> u8 {
        self.episode.dating.kind()
    }

    /// Latest indicators (per-group detail included).
    pub fn indicators(&self) -> Indicators {
        self.last_ind
    }

    /// Check a row without touching state. `row` is used for the message.
    // Not inlined into a caller of another crate: the core wasm module
    // builds the facade that calls it for size, and inlined code takes the
    // caller's opt-level (the range check is then not vectorised).
    #[inline(never)]
    pub fn validate(&self, s: &Sample, row: u64) -> Result<(), InputError> {
        self.check_row(s, row)
    }

    /// [`Detector::validate`] over a batch (row numbers from `first_row`),
    /// and the batch's own time order from `*last_t` on (updated to the
    /// last good row's time): the first bad row's index in `rows`, with its
    /// error, or `None` when its time goes back from the row before it
    /// (`*last_t`). The wasm facade's first pass over a batch; here so that
    /// it runs at the row path's opt-level (see `validate`).
    #[inline(never)]
    pub fn validate_batch(&self, rows: &[Sample], first_row: u64, last_t: &mut f64) -> Result<(), (usize, Option<InputError>)> {
        for (k, s) in rows.iter().enumerate() {
            self.check_row(s, first_row + k as u64).map_err(|e| (k, Some(e)))?;
            if s.t < *last_t {
                return Err((k, None));
            }
            *last_t = s.t;
        }
        Ok(())
    }

    #[inline]
    fn check_row(&self, s: &Sample, row: u64) -> Result<(), InputError> {
        validate_sample(s, row)?;
        if let Some(lt) = self.clock.last_t {
            if s.t < lt {
                return Err(InputError {
                    row,
                    field: "t",
                    reason: format!("time goes backwards: {} after {}", Shortest(s.t), Shortest(lt)),
                });
            }
        }
        Ok(())
    }

    /// Process one row. On `Err` nothing changed.
    #[inline(never)] // see `validate`
    pub fn push(&mut self, s: &Sample) -> Result<Output, InputError> {
        self.check_row(s, self.stats.rows)?;
        Ok(self.push_valid(s))
    }

    /// Process a row already validated (see [`Detector::validate`]): predict
    /// the filter to the row's time with the IMU held from an earlier row,
    /// hold this row's IMU, feed its baro, then judge its fix (or its lack
    /// of one).
    #[inline(never)] // see `validate`
    pub fn push_valid(&mut self, s: &Sample) -> Output {
        self.stats.rows += 1;
        self.resid = [f64::NAN; 7];
        self.episode.dating.clear();
        let t = s.t;
        let (dt, gap) = self.clock.row(t, self.cfg.data_gap);
        if gap {
            self.data_gap();
        }
        if dt > 0.0 {
            self.predict(t, dt);
        }
        self.hold_imu(t, s);
        if s.has_baro() {
            self.consistency.last_baro = Some((t, s.baro));
            let revived = self.consistency.baro_flat.push(t, s.baro);
            self.stats.baro_rows += 1;
            if revived {
                self.baro_revived();
            }
            self.baro_row(t, s.baro);
        }
        let mut out = if s.has_fix() && self.clock.fresh(s) {
            self.gps_epoch(s)
        } else {
            self.between_fixes(t, s)
        };
        out.t = t;
        self.last = out;
        // A fix the receiver itself declares degraded is reported as such,
        // between fixes too, unless there is no fix to speak of. The
        // detector's own verdict (`self.last`) learns and feeds as before,
        // with the fix down-weighted by its claim.
        if self.quality.declared && !matches!(out.kind, kind::OUTAGE | kind::STALE | kind::NO_GPS) {
            out.status = 1;
            out.kind = kind::DEGRADED;
        }
        out
    }

    /// [`Detector::push`] of a row given as values in
    /// [`COLUMNS`](crate::sample::COLUMNS) order (NaN = absent), its output
    /// written after them as `[t, status, f, r, c, kind, gps_epoch]` (the
    /// wasm package's row buffer: `io` holds at least `COLUMNS.len() + 7`
    /// values). On `Err` nothing changed, `io` included.
    #[inline(never)] // see `validate`
    pub fn push_values(&mut self, io: &mut [f64]) -> Result<(), InputError> {
        let n = crate::sample::COLUMNS.len();
        let s = row_of(io);
        self.check_row(&s, self.stats.rows)?;
        let o = self.push_valid(&s);
        let vals = [o.t, o.status as f64, o.f, o.r, o.c, o.kind as f64, if o.gps_epoch { 1.0 } else { 0.0 }];
        for (d, v) in io.iter_mut().skip(n).zip(vals) {
            *d = v;
        }
        Ok(())
    }

    /// [`Detector::push_valid`] over a batch of rows already validated,
    /// their outputs appended to `out`. The wasm facade's batch loop lives
    /// here, in the row path's crate, so it runs at the detector's
    /// opt-level (the facade is built for size).
    #[inline(never)] // see `validate`
    pub fn push_valid_batch(&mut self, rows: &[Sample], out: &mut OutputColumns) {
        for s in rows {
            let o = self.push_valid(s);
            out.status.push(o.status);
            out.kind.push(o.kind);
            out.f.push(o.f);
            out.r.push(o.r);
            out.c.push(o.c);
        }
    }

    /// Every sensor stopped: a logging gap, not a navigation fault. No
    /// verdict carries across it: it starts from "no GPS yet".
    #[cfg_attr(navguard_cold_size, optimize(size))]
    #[inline(never)]
    fn data_gap(&mut self) {
        self.stats.data_gaps += 1;
        self.last = Output { kind: kind::NO_GPS, driver: 255, ..Output::default() };
        self.kf = None;
        self.imu = None;
        self.ind.reset_references();
        self.last_est.baro_h = None;
        self.episode.coast_start = None;
        self.episode.withheld.release();
        // A reading logged before the gap and one after it are not a run.
        self.consistency.baro_flat.restart();
    }

    /// Predict the filter by `dt` boot-clock s to `t`, on the held IMU if
    /// it is recent; the step is taken in true time (see `ClockRate`).
    fn predict(&mut self, t: f64, dt: f64) {
        let imu = self.imu.filter(|(ti, _)| t - ti <= IMU_TIMEOUT).map(|(_, u)| u);
        let Some(kf) = self.kf.as_mut() else { return };
        let dt = dt * self.consistency.rate.scale;
        let v0 = kf.velocity();
        match kf.predict(dt, imu.as_ref()) {
            Ok(()) => self.consistency.advance(dt, v0, kf.velocity(), kf_flying(kf), imu.is_some()),
            Err(e) => self.filter_failed(e),
        }
    }

    /// Hold the row's IMU sample for the next prediction.
    fn hold_imu(&mut self, t: f64, s: &Sample) {
        if s.has_accel() && s.has_attitude() {
            if let Some(q) = quat_from_wxyz(s.qw, s.qx, s.qy, s.qz) {
                // R₃₃ of body→NED: the body's down axis on the local down.
                let (x, y) = (q.quaternion().i, q.quaternion().j);
                if 1.0 - 2.0 * (x * x + y * y) <= UPSET_COS_TILT {
                    self.upset_until = t + UPSET_HOLD_S;
                }
                self.imu = Some((t, ImuInput { f_body: Vector3::new(s.ax, s.ay, s.az), q }));
                self.stats.imu_rows += 1;
                let psd = self.imu_noise.learn(t, [s.ax, s.ay, s.az]);
                if let Some(kf) = self.kf.as_mut() {
                    kf.set_accel_psd(psd);
                }
            }
        }
    }

    /// A row without a fix carries the last epoch's verdict, or is an
    /// outage (see `Clock::is_outage`).
    fn between_fixes(&mut self, t: f64, s: &Sample) -> Output {
        let mut o = self.last;
        o.gps_epoch = false;
        let in_outage = matches!(self.last.kind, kind::OUTAGE | kind::STALE);
        if self.clock.is_outage(t, s.reports_no_fix(), in_outage, self.flying(), self.cfg.outage_timeout) {
            o.status = 1;
            // A repeated fix says the receiver still reports one: frozen.
            o.kind = if s.has_fix() { kind::STALE } else { kind::OUTAGE };
            if let (false, Some(lf)) = (in_outage, self.clock.last_fix) {
                let (clock, timeout) = (&self.clock, self.cfg.outage_timeout);
                self.episode.dating.silent(|| (t, lf, clock.gps_dt, clock.outage_silence(timeout), o.kind));
            }
            o.f = 1.0;
            self.ind.clear_imu();
            self.episode.outage(self.clock.last_fix);
        } else if matches!(o.kind, kind::OUTAGE | kind::STALE) {
            o.status = 0;
            o.kind = kind::NORMAL;
        }
        o
    }

    /// Flying: moving faster than 1 m/s or more than 2 m above the anchor.
    fn flying(&self) -> bool {
        self.kf.as_ref().is_some_and(kf_flying)
    }

    #[cfg_attr(navguard_cold_size, optimize(size))]
    #[inline(never)]
    fn filter_failed(&mut self, _e: FilterError) {
        // Re-initialise at the next fix; keep the verdict history.
        self.stats.filter_errors += 1;
        self.kf = None;
        self.ind.reset_references();
        self.last_est.baro_h = None;
        self.consistency.imu_gap = true;
    }

    /// A baro sample: its residual and vertical consistency are observed; a
    /// withheld baro may be released; a fed one updates the filter.
    fn baro_row(&mut self, t: f64, baro: f64) {
        let Some(kf) = self.kf.as_mut() else { return };
        if !kf.baro_initialised() {
            // The first sample fixes the baro offset (no shared datum).
            if kf.update_baro(baro).is_ok() {
                self.last_est.baro_h = Some(kf.baro_height());
            }
            return;
        }
        let inn = kf.baro_innovation(baro);
        self.resid[6] = inn.nu[0];
        self.methods.note_baro(inn.nu[0], inn.s[0]);
        let m = self.last_est.baro_h.map_or(0.0, |p| kf.baro_height() - p);
        let prev = self.ind.previous(6);
        self.ind.observe(6, inn.nu[0], m, inn.s[0]);
        let cons = self.ind.observe_baro(t, baro - self.consistency.alt_int, self.episode.withheld.baro(), motion_of(&kf.velocity()));
        // A held reading follows a hover's filter: not a recovery.
        // Nor one still off its levels (see `Consistency::baro_still_off`).
        let cons = if self.consistency.baro_flat.stuck() || self.consistency.baro_still_off() { f64::INFINITY } else { cons };
        if self.episode.withheld.baro_released(cons) {
            // The withheld baro follows the filter's climb again (its change
            // since before the fault is consistent): the fault is over, but
            // the offset state absorbed part of it before detection, so
            // re-anchor the offset instead of judging the baro against it.
            kf.reset_baro();
            self.ind.reset_axis(6);
            self.ind.clear_baro();
            if kf.update_baro(baro).is_ok() {
                self.last_est.baro_h = Some(kf.baro_height());
            }
            return;
        }
        if !self.episode.withheld.baro() {
            if let Err(e) = feed_baro(kf, &mut self.ind, baro, prev, self.last.status == 0) {
                self.filter_failed(e);
                return;
            }
        }
        self.last_est.baro_h = Some(kf.baro_height());
    }

    /// A baro called stuck reads again: what its windows and its offset
    /// hold is the fault's, so they restart, and the baro is fed again (its
    /// return jump, 27 m on battery tune #224, otherwise stayed in the
    /// 6 s windows and was flagged for 6 s after the fault).
    #[cfg_attr(navguard_cold_size, optimize(size))]
    #[inline(never)]
    fn baro_revived(&mut self) {
        self.consistency.baro_jump.block();
        restart_baro(self.kf.as_mut(), &mut self.ind, &mut self.episode.withheld, &mut self.last_est);
    }

    /// The first fix, or the first after a data gap or a filter error,
    /// starts the filter on it.
    #[cfg_attr(navguard_cold_size, optimize(size))]
    #[inline(never)]
    fn start_filter(&mut self, fix: &Fix) {
        let noise = self.cfg.filter_noise();
        let v0 = fix.vel.unwrap_or_else(Vector3::zeros);
        let vs = if fix.vel.is_some() { noise.gps_vel } else { 3.0 };
        let mut kf = Kf::new(noise, fix.y, v0, noise.gps_pos_h, vs);
        kf.set_accel_psd(self.imu_noise.psd);
        self.kf = Some(kf);
        self.last_est.pos = fix.y;
        self.last_est.vel = v0;
        self.ind.reset_references();
        self.consistency.imu_gap = true;
        self.episode.coast_start = None;
        self.methods.prev_nu = None;
    }

    /// A GPS epoch, stage by stage: residuals (the fix against the filter's
    /// prediction), tests (indicators closed), decision (the method's
    /// verdict), episode (its start and IMU part), gating (what the filter
    /// is not fed) and the episode's end, filter update (or re-anchoring),
    /// learning (databases, retraining, reference windows).
    #[cfg_attr(navguard_cold_size, optimize(size))]
    fn gps_epoch(&mut self, s: &Sample) -> Output {
        self.stats.gps_epochs += 1;
        self.clock.fix(s.t);
        let anchor = *self.anchor.get_or_insert_with(|| Anchor::from_sample(s));
        let fix = Fix::new(s, &anchor);
        // The receiver's own word, at every fix (the first after a start or
        // a data gap too, so no earlier declaration outlives it): reported
        // by `push_valid`, and a velocity it calls degraded does not judge
        // the IMU.
        let declared = self.quality.declares_degraded(&fix);
        let Some(kf) = self.kf.as_mut() else {
            self.start_filter(&fix);
            return Output { t: fix.t, status: 0, f: 0.0, r: 0.0, c: 0.0, kind: kind::NORMAL, gps_epoch: true, driver: 255 };
        };
        // Not on a fix the receiver declares degraded: the detector reports
        // those by the receiver's word, and the velocity tests' verdicts
        // on them are what ends such a stretch (battery tune #680 with
        // speed claims: an 81 s degraded fix whose sAcc rose fivefold; with
        // its velocity tests scaled, 294 false-positive epochs followed).
        let speed_claim = if declared { 1.0 } else { self.quality.speed_scale(fix.sacc) };
        self.ind.set_speed_claim(speed_claim);
        let res = self.last_est.residuals(kf, &mut self.ind, &fix);
        res.write(&mut self.resid);
        let vel_withheld = self.episode.withheld.gps_vel();
        // Not inside any episode: a 60 s position ramp along a straight leg
        // does not average out over headings and taught the clock a wrong
        // rate that then flagged the 30 s after the ramp (tests/long_faults.rs).
        let learn_rate = !self.episode.active && !self.episode.receiver_lost;
        let imu_dense = self.imu_noise.period > 0.0 && self.imu_noise.period <= IMU_MAX_PERIOD_S;
        let epoch = EpochState { vel_withheld, baro_withheld: self.episode.withheld.baro(), learn_rate, declared, imu_dense, speed_claim, accepted: self.episode.accepted.is_some(), mean_hold: self.episode.mean_hold };
        let slow_before = self.consistency.slow_judging();
        let (mut ind, alt_back) = self.consistency.tests(&mut self.ind, &fix, epoch);
        // A position-only episode that opened on a step's onset lasts while
        // the fix stays off the coasted filter (`Episode::held`): the
        // windows' R is an RMS over epochs from before the onset, so a
        // step's second epoch read as normal and the filter followed the
        // step (the 5 m step check's instance 4: 8 of 150 epochs flagged).
        let sigma_pos: [f64; 3] = core::array::from_fn(|a| self.ind.sigma(a));
        let sigma_coast = core::array::from_fn(|a| self.ind.coast_sigma(a));
        let sigma_track = self.consistency.track.sigmas();
        // An episode opened on the short mean's onset holds on the mean:
        // a noisy fast receiver's step is a few of its per-fix σ.
        let mut held = self.episode.held(&res.pin.nu, &sigma_coast, &sigma_track);
        if self.episode.mean_hold && self.episode.withheld.gps_pos() {
            held = held.fmax(self.consistency.track.mean_sigmas() * MEAN_HOLD_R_SCALE);
        }
        ind.fold(0, held);
        self.ind.fold_unfolded(held);
        self.last_ind = ind;
        let label = self.oracle.then_some(s.label);
        let mut verdict = self.methods.decide(&self.cfg, &self.learning.anfis, kf, &res, &ind, label);
        if !self.oracle && self.ind.position_learnt() < WARMUP_EPOCHS {
            verdict.fault = false;
        }
        let fault_ended = verdict.fault
            && !self.oracle
            && !self.episode.active
            && (self.quality.returning(fix.t) || self.consistency.unflagged_fault_ended(
                fix.t,
                &mut self.episode,
                &res,
                self.quality.scale(fix.eph) < QUALITY_DEGRADED,
                core::array::from_fn(|a| self.ind.sigma(3 + a)),
            ));
        // The GPS back where it was before a fault the filter had followed:
        // its altitude on the baro's level after a drift the two GPS
        // references shared (a vertical drag-off, see `drift`), or its
        // position on its velocity track after a ramp (see `ramp`), or its
        // altitude back onto both the baro and its own vertical velocity
        // integrated after they both condemned it (`altitude_vote`).
        // Or its altitude back onto the baro's level while the Doppler
        // integral stayed (`vertical_return`), during an episode or at a
        // fault verdict.
        let judged = !self.oracle && (self.episode.active || verdict.fault);
        let vertical = if judged { self.consistency.vertical_return() } else { None };
        // The GPS altitude's return alone needs its horizontal fix not to
        // have jumped with it (`Residuals::jumped_h`): a receiver whose
        // noise grew jumps on every axis, and its altitude lands back on
        // the baro's level by chance (the paper flight's noise fault, seed
        // 2: 16 re-anchorings in its 15 s, two epochs missed at each).
        let vertical = vertical.filter(|&baro| baro || !res.jumped_h(&sigma_pos));
        // Not the GPS altitude's return alone inside an episode held on
        // the short mean: one fix of a fast noisy receiver lands back on
        // the baro's level by chance (the 6 m vertical step check's
        // instance 1, 10 Hz, 11 s into its step); the mean says when the
        // step ends.
        let gps_back = self.consistency.baro_drift.gps_returned() || self.consistency.ramp.returned() || alt_back || (vertical == Some(false) && !self.episode.mean_hold);
        // The baro back on both its levels, from beyond `FAR` σ to within
        // `NEAR` (see `track`): the end of a baro fault. The jump back is
        // in the baro's 6 s windows and its Δr, which a baro released
        // during the fault had re-based on the faulty level (battery tune
        // #175: a 7.9 m step for 66 s, its end flagged for 5.6 s).
        let baro_back = vertical == Some(true);
        // The slow fault called is dated at a jump back (`Dating::slow`),
        // read before the returns restart the slow tests: a ramp's or a
        // drift's collapse, or the GPS altitude or the baro back. Not a
        // ramp's release on its fading (`RampTest::returned` says either).
        let c = &self.consistency;
        self.episode.dating.slow_epoch(fix.t, || {
            let drift_fell = slow_before[0] && c.baro_drift.released_growing();
            let back = !declared && (c.ramp.jumped_back_now() || drift_fell || alt_back || vertical.is_some());
            (c.slow_judging().contains(&true), back)
        });
        if baro_back {
            restart_baro(Some(&mut *kf), &mut self.ind, &mut self.episode.withheld, &mut self.last_est);
            // The drift window's start may sit on the fault's level (one
            // learnt from the flight's first seconds, see
            // `VelocityTrack::back_to_origin`).
            self.consistency.baro_drift.clear();
        }
        let drag_since = self.consistency.drag_ended(fix.t, self.episode.active);
        let drag_end = drag_since.is_some();
        self.episode.long_coast |= self.consistency.drag_end.ruled_out();
        if let Some(since) = drag_since {
            self.episode.dating.date(since);
            // The confirmation can take a step's onset for a drag-off's end
            // (a manoeuvre moved the velocity's mean; battery tune #599): the
            // offset re-anchored onto is kept like a coasted-out episode's,
            // so the step's own end undoes it instead of opening a new one.
            self.episode.accept(res.pin.nu);
        }
        // An upset vehicle (see `kind::UPSET`): nothing is judged, and the
        // filter re-anchors at every epoch until it is over.
        let upset = fix.t <= self.upset_until;
        if upset {
            // The upset's attitude made the IMU's predicted velocity
            // changes meaningless: its windows restart after it (the
            // vertical one spans 6 s, longer than the 5 s hold).
            self.ind.clear_imu();
        }
        let restart = !self.oracle && (self.quality.reacquired(fix.eph) || fault_ended || gps_back || drag_end || upset || baro_back);
        let was_active = self.episode.active;
        let was_imu = self.episode.imu;
        let fault = self.episode.open(verdict.fault && !restart, &mut self.ind, self.oracle);
        // While the IMU is the suspect, its bias estimate is not learnt from
        // the fault (or the test would see the learnt error after it ends):
        // through an IMU episode, and whenever the IMU test calls, armed or
        // not. Before it has armed no episode opens: battery tune #1444, a
        // 0.86 m/s² bias from 10 s, was learnt as the sensor's bias (0.66
        // of it) until the test went quiet and armed, and its end opened
        // an IMU episode to the end of the flight (164 FP epochs).
        kf.set_hold_bias(self.episode.imu || ind.imu >= IMU_CALL);
        // The filter learnt part of the fault as the sensor's bias over the
        // seconds the IMU test took to call it (battery eval #284: 0.26 of
        // a 1.16 m/s² bias), which the estimate, held through the episode,
        // then carried past the fault's end: an IMU episode to the end of
        // the flight. The episode rolls it back to the last calm epoch's,
        // from before the onset.
        if self.episode.imu && !was_imu {
            kf.set_accel_bias(&self.bias_calm.into());
        } else if !fault && self.ind.imu_recent(IMU_RECENT_S) < IMU_CALM {
            self.bias_calm = kf.accel_bias().into();
        }
        let ev = Evidence {
            ind: &ind,
            r_vel: self.ind.r_vel_unfolded(),
            incoherence: self.ind.incoherence(),
            dec: verdict.dec.as_ref(),
            res: &res,
            sigma_pos,
            on_track: self.consistency.track.on_track(),
            sigma_track,
            baro_off: self.consistency.baro_still_off(),
        };
        let pos_before = self.episode.withheld.gps_pos();
        let mut step = self.episode.step(fix.t, fault, &ev, self.cfg.max_coast, self.oracle);
        step.reset |= restart;
        // A slow fault flagged from its call on began before it: its onset
        // is kept for the reconciled verdict (issue 14 item 4), which dates
        // it if the offset then jumps back (`Dating::slow`).
        // Not on a fix the receiver declares degraded: the slow tests judge
        // against the GPS, which it disowns (real log 26-11: a baro drift
        // called and confirmed inside its 64 s degraded stretch).
        if step.fault && !step.reset && !self.oracle && !declared {
            let c = &self.consistency;
            self.episode.dating.called(fix.t, || c.slow_onset(slow_before, fix.t));
        }
        // A stuck baro's run is the fault from its first sample.
        let flat = &self.consistency.baro_flat;
        self.episode.dating.stuck(|| (step.fault && flat.stuck(), flat.run_start()));
        // The position withheld from this epoch on, whether the episode
        // opened here or on another group: a vertical drag-off is first
        // blamed on the baro (the GPS altitude and its Doppler integral
        // move together, the baro leaves both), and its end is the
        // position's jump inside that episode (battery tune #1614: a 0.92
        // m/s drag for 7 s whose 6.5 m return was judged as a step for 56 s).
        let opened_on_position = !self.oracle && (!was_active || !pos_before) && self.episode.withheld.gps_pos();
        self.consistency.arm_drag_end(fix.t, opened_on_position, &step);
        if opened_on_position {
            self.episode.fresh = step_onset(&res.pin.nu, self.consistency.track.jump(), &sigma_coast, &sigma_track);
            // Not inside an episode: its position jump is read by the
            // episode's own return and drag-end tests.
            self.episode.mean_hold = !was_active && self.consistency.track.mean_departure() >= 1.0;
        }
        // The hold ends with the episode, or when it coasts out: the
        // offset is then accepted (`Episode::accepted`).
        if !step.fault || step.reset {
            self.episode.mean_hold = false;
        }
        // A jump read as a fault's end (a restart, or the episode's own
        // return) is not a new fault's onset. Not every episode's end: a
        // step's first epochs may open and close an episode before the
        // mean calls (the 6 m vertical step check's instances 1 and 6, 10
        // and 20 Hz receivers: 6% of their epochs flagged; 40% and 15% with
        // this rule, 100% with the returns above not taken in a hold).
        if restart || step.returned {
            self.consistency.track.settle_mean();
        }
        if !step.fault && !step.reset {
            self.consistency.track.learn();
            self.consistency.baro_gps_level.learn();
            self.consistency.baro_dop_level.learn();
            // The slow windows take no start from a fix the receiver
            // declares degraded: its offset would read as a drift or a
            // ramp once the receiver is back (tests/receiver_quality.rs).
            if !declared {
                self.consistency.baro_drift.learn();
                self.consistency.ramp.learn();
            }
            self.consistency.drag_end.learn();
        }
        let fed = if step.reset {
            // Coasted too long to judge (or recovered): re-anchor on GPS.
            kf.reset_to(&fix.y, fix.vel.as_ref());
            Ok(())
        } else {
            self.episode.withheld.feed(kf, &mut self.ind, &fix, &res.prev_r, self.quality.scale(fix.eph))
        };
        if !step.fault {
            self.quality.learn(&fix);
        }
        self.last_est.set_epoch(kf);
        if step.reset {
            self.reanchored();
        }
        if let Err(e) = fed {
            self.filter_failed(e);
        }
        // A restart epoch's indicators are the fault's: nothing to learn.
        if !restart {
            self.learn(step.fault, &verdict, &ind);
        }
        Output {
            t: fix.t,
            status: step.fault as u8,
            f: verdict.f,
            r: ind.r,
            c: ind.c,
            kind: if upset && !self.oracle {
                kind::UPSET
            } else if step.fault {
                kind::RESIDUAL
            } else {
                kind::NORMAL
            },
            gps_epoch: true,
            driver: ind.r_driver().map_or(255, |g| g as u8),
        }
    }

    /// The filter was re-anchored on GPS: every reference restarts.
    #[cfg_attr(navguard_cold_size, optimize(size))]
    #[inline(never)]
    fn reanchored(&mut self) {
        self.stats.filter_resets += 1;
        self.episode.reanchored(self.consistency.baro_still_off());
        self.ind.reset_references();
        self.last_est.baro_h = None;
        self.methods.prev_nu = None;
    }

    /// The learning stage: the ANFIS files the epoch (see `Learning::file`)
    /// and retrains after TC new faults; a normal epoch also teaches the
    /// reference windows of the other tests.
    fn learn(&mut self, fault: bool, v: &Verdict, ind: &Indicators) {
        let anfis = v.dec.is_none();
        if anfis {
            self.learning.file(fault, v.f, v.x, ind);
        }
        if fault {
            if anfis && self.cfg.retrain && !self.oracle && self.learning.retrain_due(self.cfg.tc) {
                self.retrain();
            }
        } else {
            self.methods.learn_normal(self.cfg.method, v.dr);
            self.ind.accept_pv();
            self.ind.accept_baro_gps();
            if self.flying() {
                self.ind.accept_imu();
            }
        }
    }

    /// Retrain the ANFIS on D1 ∪ D2 (hybrid learning). Keeps the old model
    /// if training produces anything non-finite, or if the candidate
    /// misclassifies more of D0 (the shipped model's own databases) than the
    /// current one: online data may drift, but not so far that the detector
    /// forgets the labelled faults it shipped with.
    #[cfg_attr(navguard_cold_size, optimize(size))]
    pub fn retrain(&mut self) {
        let l = &mut self.learning;
        let w = l.retrain_samples();
        l.cost.runs += 1;
        l.cost.new_samples += l.new_faults as u64;
        l.cost.samples += w as u64;
        l.cost.sample_ops += (TRAIN_EPOCHS * (l.d1.items().len() + l.d2.items().len()) + 2 * l.d0_x.len()) as u64;
        self.learning.new_faults = 0;
        self.learning.train_x.clear();
        self.learning.train_y.clear();
        for x in self.learning.d1.items() {
            self.learning.train_x.push(*x);
            self.learning.train_y.push(0.0);
        }
        for x in self.learning.d2.items() {
            self.learning.train_x.push(*x);
            self.learning.train_y.push(1.0);
        }
        let mut cand = self.learning.anfis.clone();
        cand.train_hybrid(&self.learning.train_x, &self.learning.train_y, TRAIN_EPOCHS, TRAIN_LR);
        // Validation on D0: the candidate must classify the shipped model's
        // databases at least as well as the current ANFIS does.
        if cand.is_finite() && self.d0_errors(&cand) <= self.d0_errors(&self.learning.anfis) {
            self.learning.anfis = cand;
            self.stats.retrains += 1;
        }
    }

    /// What retraining has cost so far.
    pub fn retrain_cost(&self) -> RetrainCost {
        self.learning.cost
    }

    /// Misclassified D0 samples at the configured threshold.
    #[cfg_attr(navguard_cold_size, optimize(size))]
    fn d0_errors(&self, a: &Anfis) -> usize {
        let th = self.cfg.threshold;
        let l = &self.learning;
        l.d0_x.iter().zip(&l.d0_y).filter(|(x, y)| (a.eval(x) >= th) != (**y >= 0.5)).count()
    }
}

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
    const GT: (f64, f64) = range_of(26);
    ok &= s.gps_time.is_nan() | ((s.gps_time >= GT.0) & (s.gps_time <= GT.1));
    const SA: (f64, f64) = range_of(27);
    ok &= s.sacc.is_nan() | ((s.sacc >= SA.0) & (s.sacc <= SA.1));
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

/// The checks one by one, naming the first field that fails: the row's
/// own ([`Sample::first_invalid`], compiled in the log crate, for size:
/// 6 KB of cold code at this crate's opt-level), then the quaternion's norm.
fn validate_detailed(s: &Sample, row: u64) -> Result<(), InputError> {
    if let Some((field, reason)) = s.first_invalid() {
        return Err(InputError { row, field, reason });
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

    /// Residuals of a fix whose position residual is `p` (previous `p0`)
    /// and velocity residual `v` (previous zero).
    fn drag_res(p: [f64; 3], p0: [f64; 3], v: [f64; 3]) -> Residuals {
        let mut prev_r = [0.0; 6];
        prev_r[..3].copy_from_slice(&p0);
        Residuals {
            pin: Innovation { nu: p, s: [1.0; 3] },
            vin: Some(Innovation { nu: v, s: [0.04; 3] }),
            prev_r,
            r_ref: [0.0; 3],
        }
    }

    const SIGMA_DV: [f64; 3] = [0.1; 3];

    #[test]
    fn a_position_and_velocity_jump_back_together_is_a_return() {
        // 30 m back along north with 0.5 m/s (5 σ): a 60 s drag undone.
        // Its age is dated on the velocity's jump plus one σ (0.1 m/s):
        // 30 m over 0.6 m/s, the shortest drag the jump allows.
        let r = drag_res([-30.0, 0.0, 0.0], [0.2, 0.0, 0.0], [-0.5, 0.05, 0.0]);
        let age = r.drag_returned(100.0, Some([-30.1, 0.0, 0.0]), SIGMA_DV).unwrap();
        assert!((age - 50.0).abs() < 1e-9, "age {age}");
        // The same in the vertical: 20 m over 0.4 + 0.1 m/s.
        let r = drag_res([0.0, 0.0, 20.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.4]);
        let age = r.drag_returned(100.0, Some([0.0, 0.0, 20.0]), SIGMA_DV).unwrap();
        assert!((age - 40.0).abs() < 1e-9, "age {age}");
    }

    #[test]
    fn a_step_onset_or_a_pulled_filter_is_not() {
        let track = Some([-30.0, 0.0, 0.0]);
        // Step onset: the velocity did not jump (2 σ of noise).
        assert!(drag_res([-30.0, 0.0, 0.0], [0.0; 3], [-0.2, 0.0, 0.0]).drag_returned(100.0, track, SIGMA_DV).is_none());
        // The velocity jumped across the position jump, not along it.
        assert!(drag_res([-30.0, 0.0, 0.0], [0.0; 3], [-0.5, 0.6, 0.0]).drag_returned(100.0, track, SIGMA_DV).is_none());
        // Against it: the position ran back while the velocity ran on.
        assert!(drag_res([-30.0, 0.0, 0.0], [0.0; 3], [0.5, 0.0, 0.0]).drag_returned(100.0, track, SIGMA_DV).is_none());
        // The residual grew over earlier epochs (a drifting filter).
        assert!(drag_res([-30.0, 0.0, 0.0], [-25.0, 0.0, 0.0], [-0.5, 0.0, 0.0]).drag_returned(100.0, track, SIGMA_DV).is_none());
        // The GPS stayed on its own track: the filter moved (a baro pull).
        assert!(drag_res([-30.0, 0.0, 0.0], [0.0; 3], [-0.5, 0.0, 0.0]).drag_returned(100.0, Some([-0.3, 0.0, 0.0]), SIGMA_DV).is_none());
        // No track yet, or no velocity.
        assert!(drag_res([-30.0, 0.0, 0.0], [0.0; 3], [-0.5, 0.0, 0.0]).drag_returned(100.0, None, SIGMA_DV).is_none());
        let mut r = drag_res([-30.0, 0.0, 0.0], [0.0; 3], [-0.5, 0.0, 0.0]);
        r.vin = None;
        assert!(r.drag_returned(100.0, track, SIGMA_DV).is_none());
        // NaN previous residuals (references just reset): nothing is new.
        assert!(drag_res([-30.0, 0.0, 0.0], [f64::NAN; 3], [-0.5, 0.0, 0.0]).drag_returned(100.0, track, SIGMA_DV).is_none());
    }

    #[test]
    fn a_step_onset_is_a_new_jump_of_4_sigma_along_its_offset() {
        let (sigma, track) = ([1.0, 1.0, 2.0], [0.5, 0.5, 3.0]);
        // 5 m north: 5σ along it, whatever the vertical's σ.
        assert!((along_sigmas(&[5.0, 0.0, 0.0], &sigma, &track) - 5.0).abs() < 1e-12);
        // The larger of the two σ per axis: 6 m down is 2σ of the track's 3 m.
        assert!((along_sigmas(&[0.0, 0.0, 6.0], &sigma, &track) - 2.0).abs() < 1e-12);
        // Along a diagonal: σ² weighted by the offset's share on each axis.
        let s = along_sigmas(&[3.0, 0.0, 3.0], &sigma, &track);
        assert!((s - 18f64.sqrt() / 5f64.sqrt()).abs() < 1e-12, "{s}");
        assert!(along_sigmas(&[0.0; 3], &sigma, &track).is_nan());
        // A 5 m step at this epoch is an onset...
        assert!(step_onset(&[5.0, 0.0, 0.0], Some([4.8, 0.1, 0.0]), &sigma, &track));
        // ...not under 4σ, nor when most of it was there before the jump
        // (0.4 of it new), nor across it, nor with no track yet.
        assert!(!step_onset(&[3.5, 0.0, 0.0], Some([3.5, 0.0, 0.0]), &sigma, &track));
        assert!(!step_onset(&[5.0, 0.0, 0.0], Some([2.0, 0.0, 0.0]), &sigma, &track));
        assert!(!step_onset(&[5.0, 0.0, 0.0], Some([0.0, 5.0, 0.0]), &sigma, &track));
        assert!(!step_onset(&[5.0, 0.0, 0.0], None, &sigma, &track));
    }

    #[test]
    fn a_jump_undoes_an_offset_only_by_most_of_it_along_it() {
        let off = [10.0, 5.0, 0.0];
        assert!(undoes(&[-10.0, -5.0, 0.0], &off, 0.0));
        // Plus the drift since the re-anchoring (ramp): 1.3 of it.
        assert!(undoes(&[-13.0, -6.5, 1.0], &off, 0.0));
        assert!(!undoes(&[-4.0, -2.0, 0.0], &off, 0.0), "0.4 of it");
        assert!(!undoes(&[-16.0, -8.0, 0.0], &off, 0.0), "1.6 of it");
        assert!(!undoes(&[10.0, 5.0, 0.0], &off, 0.0), "away from it");
        assert!(!undoes(&[5.0, -10.0, 0.0], &off, 0.0), "across it");
        // Shorter than the noise floor, or nothing to undo.
        assert!(!undoes(&[-10.0, -5.0, 0.0], &off, 200.0));
        assert!(!undoes(&[-10.0, -5.0, 0.0], &[0.0; 3], 0.0));
        assert!(!undoes(&[f64::NAN; 3], &off, 0.0));
    }

    #[test]
    fn the_implied_drag_age_must_fit_the_flight() {
        let track = Some([-30.0, 0.0, 0.0]);
        // 30 m at 0.5 m/s is a 60 s drag: not after 40 s of flight.
        assert!(drag_res([-30.0, 0.0, 0.0], [0.0; 3], [-0.5, 0.0, 0.0]).drag_returned(40.0, track, SIGMA_DV).is_none());
        assert!(drag_res([-30.0, 0.0, 0.0], [0.0; 3], [-0.5, 0.0, 0.0]).drag_returned(61.0, track, SIGMA_DV).is_some());
        // 3 m at 1 m/s is 3 s: shorter than any drag worth re-anchoring on
        // (a baro step pulls the filter's height and velocity like this).
        assert!(drag_res([-3.0, 0.0, 0.0], [0.0; 3], [-1.0, 0.0, 0.0]).drag_returned(100.0, Some([-3.0, 0.0, 0.0]), SIGMA_DV).is_none());
    }

    #[test]
    fn a_usual_claim_scales_by_the_ratio_and_does_not_learn_a_degraded_fix() {
        let mut q = UsualClaim::default();
        assert_eq!(q.scale(7.0), 1.0, "nothing learnt: no scale");
        for _ in 0..100 {
            q.learn(1.2);
        }
        assert!((q.scale(6.0) - 5.0).abs() < 1e-9 && q.scale(0.6) == 1.0 && q.scale(f64::NAN) == 1.0);
        // A long degraded stretch that passed the tests is not learnt.
        for _ in 0..500 {
            q.learn(8.0);
        }
        assert!((q.scale(6.0) - 5.0).abs() < 1e-9, "{}", q.scale(6.0));
        // A better receiver is followed (forgetting factor 0.02 per fix).
        for _ in 0..400 {
            q.learn(0.5);
        }
        assert!((q.scale(1.0) - 2.0).abs() < 1e-2, "{}", q.scale(1.0));
        assert_eq!(q.scale(1e9), 100.0);
    }

    /// The receiver's declaration, fix by fix: a 2D fix, ≤ 4 satellites,
    /// or a claim 3× its usual one (once the usual one is learnt), and only
    /// once the receiver has given a fix it did not call degraded.
    #[test]
    fn the_receiver_declares_a_degraded_fix_in_its_own_fields() {
        let mut q = ReceiverQuality::default();
        let fix = |eph: f64, sats: f64, fix_type: f64| Fix { t: 0.0, y: Vector3::zeros(), vel: None, eph, epv: f64::NAN, gps_time: f64::NAN, sacc: f64::NAN, sats, fix_type };
        // Still acquiring (2D, then 4 satellites): not declared.
        assert!(!q.declares_degraded(&fix(5.0, 9.0, 2.0)) && !q.declares_degraded(&fix(5.0, 4.0, 3.0)));
        for _ in 0..60 {
            q.pos.learn(1.0);
            assert!(!q.declares_degraded(&fix(1.0, 9.0, 3.0)));
        }
        assert!(!q.declares_degraded(&fix(2.9, 9.0, 3.0)), "2.9x its usual claim is not a declaration");
        assert!(q.declares_degraded(&fix(3.1, 9.0, 3.0)), "3.1x is");
        assert!(q.declares_degraded(&fix(1.0, 4.0, 3.0)) && q.declares_degraded(&fix(1.0, 9.0, 2.0)));
        assert!(!q.declares_degraded(&fix(1.0, 6.0, 3.0)), "6 satellites and a usual claim end the stretch");
        assert!(!q.declares_degraded(&fix(1.0, 5.0, 3.0)), "5 satellites and a usual claim");
        // No sats or fix type in the log: only the claim can declare.
        assert!(!q.declares_degraded(&fix(1.0, f64::NAN, f64::NAN)) && q.declares_degraded(&fix(4.0, f64::NAN, f64::NAN)));
    }

    /// A declared stretch lasts while the receiver stays below what it
    /// takes to be trusted again: fewer than 6 satellites, or a claim 2×
    /// its usual one (3× opens a stretch). A usual fix with 6 ends it, and
    /// neither alone opens one.
    #[test]
    fn a_declared_stretch_lasts_until_the_receiver_is_trusted_again() {
        let mut q = ReceiverQuality::default();
        let fix = |eph: f64, sats: f64| Fix { t: 0.0, y: Vector3::zeros(), vel: None, eph, epv: f64::NAN, gps_time: f64::NAN, sacc: f64::NAN, sats, fix_type: 3.0 };
        let at = |t: f64, sats: f64| Fix { t, ..fix(1.0, sats) };
        for _ in 0..60 {
            q.pos.learn(1.0);
            assert!(!q.declares_degraded(&fix(1.0, 9.0)));
        }
        assert!(!q.declares_degraded(&fix(2.5, 9.0)) && !q.declares_degraded(&fix(1.0, 5.0)), "neither opens a stretch");
        assert!(q.declares_degraded(&fix(1.0, 4.0)), "4 satellites open one");
        assert!(q.declares_degraded(&fix(1.0, 5.0)), "5 satellites keep it");
        assert!(q.declares_degraded(&fix(2.5, 9.0)), "2.5x the usual claim keeps it");
        assert!(!q.declares_degraded(&fix(1.9, 9.0)), "1.9x with 9 satellites ends it");
        assert!(q.declares_degraded(&fix(3.1, 9.0)) && q.declares_degraded(&fix(2.1, 9.0)));
        assert!(!q.declares_degraded(&fix(1.0, 6.0)), "a usual fix with 6 satellites ends it");
        // A log without sats: the claim alone keeps it.
        assert!(q.declares_degraded(&fix(3.5, f64::NAN)) && q.declares_degraded(&fix(2.2, f64::NAN)) && !q.declares_degraded(&fix(1.5, f64::NAN)));
        // For up to 3 s after the last fix that opened it: a receiver whose
        // usual count is 5 does not hold it on its usual fixes.
        assert!(q.declares_degraded(&at(10.0, 4.0)) && q.declares_degraded(&at(12.9, 5.0)) && !q.declares_degraded(&at(13.1, 5.0)));
        assert!(!q.declares_degraded(&at(13.2, 5.0)), "and it stays ended");
    }

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
            vals in proptest::collection::vec(-1.0f64..1.0, 28),
            edits in proptest::collection::vec((0..28usize, 0..7usize), 0..4),
        ) {
            let mut s = Sample::at(10.0);
            // Groups: lat/lon/alt, pn/pe/pd, v, accel, gyro, quaternion, then
            // single columns fix..epv and baro, label, gps_time, sacc.
            let groups: [&[usize]; 8] = [&[1, 2, 3], &[4, 5, 6], &[7, 8, 9], &[14, 15, 16], &[17, 18, 19], &[20, 21, 22, 23], &[10, 11, 12, 13], &[24, 25, 26, 27]];
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

    /// Clean indicators: every group at R 1, increments 1, no pv.
    fn clean() -> Indicators {
        Indicators { r: 1.0, r_group: [1.0; GROUPS], inc_group: [1.0; GROUPS], pv: f64::NAN, ..Indicators::default() }
    }

    fn evidence(ind: &Indicators) -> Evidence<'_> {
        // Residuals that sit on their references: no return jump.
        let res: &'static Residuals = Box::leak(Box::new(Residuals {
            pin: Innovation::default(),
            vin: None,
            prev_r: [0.0; 6],
            r_ref: [0.0; 3],
        }));
        Evidence { ind, r_vel: ind.r_group[1], incoherence: 0.0, dec: None, res, sigma_pos: [0.1; 3], on_track: false, sigma_track: [0.3; 3], baro_off: false }
    }

    #[test]
    fn the_clock_learns_a_10_hz_period_and_silence_becomes_an_outage_after_1_5_s() {
        let mut c = Clock::new();
        assert_eq!(c.row(0.0, 1.0), (0.0, false));
        for k in 0..400 {
            c.fix(0.1 * k as f64);
        }
        // From the 0.2 s prior the period converges to 0.1 s, jitter to 0.
        assert!((c.gps_dt - 0.1).abs() < 1e-6 && c.gps_jitter < 1e-6, "{} {}", c.gps_dt, c.gps_jitter);
        let lf = 39.9;
        // Silence: 1.5 s + 20 ms after the last fix (a logger's dropped
        // records last up to about a second), in flight only.
        assert!(!c.is_outage(lf + 1.0, false, false, true, None));
        assert!(!c.is_outage(lf + 1.51, false, false, true, None));
        assert!(c.is_outage(lf + 1.53, false, false, true, None));
        assert!(!c.is_outage(lf + 1.53, false, false, false, None));
        assert!(!c.is_outage(lf + 1.53, false, false, true, Some(2.0)));
        assert!(c.is_outage(lf + 0.18, false, false, true, Some(0.17)));
        // A 1 Hz receiver: 3 periods.
        let mut slow = Clock::new();
        for k in 0..400 {
            slow.fix(k as f64);
        }
        assert!(!slow.is_outage(399.0 + 2.9, false, false, true, None));
        assert!(slow.is_outage(399.0 + 3.1, false, false, true, None));
        // The receiver's own "no fix" counts after half a period, on the ground too.
        assert!(!c.is_outage(lf + 0.04, true, false, false, None));
        assert!(c.is_outage(lf + 0.06, true, false, false, None));
        // Before any fix nothing is an outage.
        assert!(!Clock::new().is_outage(100.0, true, true, true, None));
    }

    #[test]
    fn a_data_gap_moves_the_last_fix_to_its_end() {
        let mut c = Clock::new();
        c.row(10.0, 1.0);
        c.fix(10.0);
        assert_eq!(c.row(10.5, 1.0), (0.5, false));
        assert_eq!(c.last_fix, Some(10.0));
        assert_eq!(c.row(13.0, 1.0), (2.5, true));
        assert_eq!(c.last_fix, Some(13.0));
    }

    #[test]
    fn gating_withholds_departed_groups_and_the_receiver_takes_its_other_half() {
        // Velocity departed with the position off its clean level: both go.
        let mut ind = clean();
        (ind.r_group[0], ind.r_group[1]) = (1.6, 3.0);
        let mut w = Withheld::default();
        w.withhold(&evidence(&ind));
        assert_eq!(w.groups, [true, true, false]);
        // Velocity alone with a clean position: the position keeps aiding.
        ind.r_group[0] = 1.4;
        let mut w = Withheld::default();
        w.withhold(&evidence(&ind));
        assert_eq!(w.groups, [false, true, false]);
        // Position departed and the receiver incoherent: velocity goes too.
        let mut ind = clean();
        ind.r_group[0] = 3.0;
        let mut w = Withheld::default();
        w.withhold(&Evidence { incoherence: 4.5, ..evidence(&ind) });
        assert_eq!(w.groups, [true, true, false]);
        // Fault memory: a group stays withheld after its R falls back.
        w.withhold(&evidence(&clean()));
        assert_eq!(w.groups, [true, true, false]);
        // The IMU consistency folded into the velocity R does not withhold
        // the GPS velocity: its own R decides.
        let mut ind = clean();
        ind.r_group[1] = 6.0;
        let mut w = Withheld::default();
        w.withhold(&Evidence { r_vel: 1.0, ..evidence(&ind) });
        assert_eq!(w.groups, [false, false, false]);
        // Another method's failed group is withheld on its word.
        let dec = Decision { score: 2.0, failed: [false, false, true] };
        w.withhold(&Evidence { dec: Some(&dec), ..evidence(&clean()) });
        assert_eq!(w.groups, [false, false, true]);
    }

    #[test]
    fn a_withheld_baro_is_released_after_five_consecutive_calm_samples() {
        let mut w = Withheld::default();
        assert!(!w.baro_released(0.1), "a baro that is fed is not released");
        w.groups[2] = true;
        for cons in [1.0, 1.0, 1.0, 1.0, 2.0, 1.0, 1.0, 1.0, 1.0] {
            assert!(!w.baro_released(cons));
        }
        assert!(w.baro_released(1.0));
        assert_eq!((w.groups[2], w.baro_calm), (false, 0));
    }

    #[test]
    fn an_episode_re_anchors_after_its_coast_limit_or_after_five_calm_epochs() {
        let ind = clean();
        // The whole receiver withheld (an IMU-only coast), past maxCoast
        // (20 s): re-anchor, still a fault.
        let mut e = Episode::default();
        let mut bad = clean();
        bad.r_group[0] = 10.0;
        bad.r_group[1] = 10.0;
        assert_eq!(e.step(100.0, true, &evidence(&bad), 20.0, false), EpisodeStep { fault: true, reset: false, returned: false });
        assert_eq!(e.step(120.5, true, &evidence(&bad), 20.0, false), EpisodeStep { fault: true, reset: true, returned: false });
        // Position only (the GPS velocity still aiding): judged for 60 s.
        let mut e = Episode::default();
        let mut pos = clean();
        pos.r_group[0] = 10.0;
        assert_eq!(e.step(100.0, true, &evidence(&pos), 20.0, false), EpisodeStep { fault: true, reset: false, returned: false });
        assert_eq!(e.step(159.0, true, &evidence(&pos), 20.0, false), EpisodeStep { fault: true, reset: false, returned: false });
        assert_eq!(e.step(160.5, true, &evidence(&pos), 20.0, false), EpisodeStep { fault: true, reset: true, returned: false });
        // Agreement for 5 epochs (and over 0.5 s): recovered, verdict normal.
        let mut e = Episode::default();
        for k in 0..4 {
            let st = e.step(10.0 + 0.2 * k as f64, true, &evidence(&ind), 20.0, false);
            assert_eq!(st, EpisodeStep { fault: true, reset: false, returned: false }, "epoch {k}");
        }
        assert_eq!(e.step(10.8, true, &evidence(&ind), 20.0, false), EpisodeStep { fault: false, reset: true, returned: false });
        // A position-only episode keeps a large offset as the fault itself.
        let mut e = Episode::default();
        let mut step = clean();
        step.r_group[0] = 4.5;
        for k in 0..10 {
            assert!(!e.step(10.0 + 0.2 * k as f64, true, &evidence(&step), 20.0, false).reset);
        }
        // An IMU episode, or the trainer's oracle, never recovers that way.
        let mut e = Episode { imu: true, ..Episode::default() };
        let mut o = Episode::default();
        for k in 0..10 {
            let t = 10.0 + 0.2 * k as f64;
            assert!(!e.step(t, true, &evidence(&ind), 20.0, false).reset);
            assert!(!o.step(t, true, &evidence(&ind), 20.0, true).reset);
        }
        // A normal verdict releases every group; the receiver counts as lost
        // until five normal epochs.
        let mut e = Episode { receiver_lost: true, coast_start: Some(3.0), ..Episode::default() };
        e.withheld.groups = [true, true, true];
        for k in 0..5 {
            assert!(e.receiver_lost, "epoch {k}");
            assert_eq!(e.step(20.0, false, &evidence(&ind), 20.0, false), EpisodeStep { fault: false, reset: false, returned: false });
            assert_eq!((e.withheld.groups, e.coast_start), ([false; GROUPS], None));
        }
        assert!(!e.receiver_lost);
    }

    /// Residuals of an epoch whose previous position residual was `prev`,
    /// the reference `r_ref`, and this one `now` (m).
    fn residuals(r_ref: [f64; 3], prev: [f64; 3], now: [f64; 3]) -> &'static Residuals {
        let mut pin = Innovation::default();
        pin.nu = now;
        let mut prev_r = [0.0; 6];
        prev_r[..3].copy_from_slice(&prev);
        Box::leak(Box::new(Residuals { pin, vin: None, prev_r, r_ref }))
    }

    #[test]
    fn a_return_jump_that_undoes_the_offset_ends_a_position_episode() {
        let mut pos = clean();
        pos.r_group[0] = 10.0;
        let open = |e: &mut Episode| e.step(100.0, true, &evidence(&pos), 20.0, false);
        // A 10 m step north held, then the GPS back to within 1 m (the
        // estimate's drift across the offset, here 2 m down, does not count).
        let mut e = Episode::default();
        open(&mut e);
        let back = Evidence { res: residuals([0.0; 3], [10.0, 0.0, 0.0], [0.8, 0.3, 2.0]), ..evidence(&pos) };
        assert_eq!(e.step(160.0, true, &back, 20.0, false), EpisodeStep { fault: false, reset: true, returned: true });
        // A jump that undoes a third of it, or overshoots to the other side
        // by as much, is no return.
        for now in [[6.7, 0.0, 0.0], [-6.0, 0.0, 0.0]] {
            let mut e = Episode::default();
            open(&mut e);
            let ev = Evidence { res: residuals([0.0; 3], [10.0, 0.0, 0.0], now), ..evidence(&pos) };
            assert_eq!(e.step(160.0, true, &ev, 20.0, false), EpisodeStep { fault: true, reset: false, returned: false }, "{now:?}");
        }
        // An offset within 6 σ_Δ of the reference is noise, not a step to undo.
        let mut e = Episode::default();
        open(&mut e);
        let small = Evidence { res: residuals([0.0; 3], [0.5, 0.0, 0.0], [0.0; 3]), ..evidence(&pos) };
        assert_eq!(e.step(160.0, true, &small, 20.0, false), EpisodeStep { fault: true, reset: false, returned: false });
        // An IMU-only coast (receiver withheld) does not end on a jump: its
        // offset is the IMU's drift.
        let mut e = Episode { receiver_lost: true, ..Episode::default() };
        open(&mut e);
        assert_eq!(e.step(110.0, true, &back, 20.0, false), EpisodeStep { fault: true, reset: false, returned: false });
    }

    #[test]
    fn the_learnt_accelerometer_noise_is_a_density_the_same_at_any_rate() {
        // White noise of σ 1 m/s² per sample: consecutive differences have
        // variance 2σ² per axis, so the density is σ²·dt: 0.01 (m/s²)²·s at
        // 100 Hz and 0.0025 at 400 Hz.
        for (rate, want) in [(100.0, 0.01), (400.0, 0.0025)] {
            let mut n = ImuNoise::default();
            let mut rng = crate::rng::Rng::new(7);
            let mut psd = 0.0;
            for k in 0..(rate as usize * 60) {
                let f = [rng.normal(), rng.normal(), rng.normal() - 9.81];
                psd = n.learn(k as f64 / rate, f);
            }
            assert!((psd / want - 1.0).abs() < 0.15, "rate {rate}: {psd} against {want}");
        }
    }

    #[test]
    fn the_imu_period_is_its_logging_rate_and_dropouts_do_not_count() {
        let f = [0.0, 0.0, -9.81];
        // 200 Hz with a 0.2 s and a 2 s dropout: still dense.
        let mut n = ImuNoise::default();
        let mut t = 0.0;
        for k in 0..4000 {
            n.learn(t, f);
            t += if k == 1000 { 0.2 } else if k == 2000 { 2.0 } else { 0.005 };
        }
        assert!((n.period - 0.005).abs() < 1e-3 && n.period <= IMU_MAX_PERIOD_S, "{}", n.period);
        // 10 Hz: sparse.
        let mut n = ImuNoise::default();
        for k in 0..600 {
            n.learn(k as f64 * 0.1, f);
        }
        assert!((n.period - 0.1).abs() < 1e-9 && n.period > IMU_MAX_PERIOD_S, "{}", n.period);
    }

    #[test]
    fn the_clock_rate_is_learnt_from_gps_displacement_against_integrated_velocity() {
        // A vehicle circling at 12 m/s, stamped by a boot clock at 0.923×:
        // boot intervals are 0.923 of true ones, so the GPS moves 1/0.923
        // of its velocity integrated over boot time.
        let mut r = ClockRate::new();
        let (rate, w, speed) = (0.923, 0.05, 12.0);
        let at = |tt: f64| {
            let (sn, cs) = (w * tt).sin_cos();
            (Vector3::new(speed / w * sn, speed / w * (1.0 - cs), 0.0), Vector3::new(speed * cs, speed * sn, 0.0))
        };
        let mut prev = None;
        for k in 0..1200 {
            let tt = 0.2 * k as f64;
            let (p, v) = at(tt);
            let t = tt * rate;
            if let Some(pv) = prev {
                r.observe(pv, t, &p, &v);
            }
            prev = Some((t, p, v));
        }
        assert!((r.scale - 1.0 / rate).abs() < 0.003, "{}", r.scale);
        // True time, or within the dead band: no correction.
        let mut r = ClockRate::new();
        let mut prev = None;
        for k in 0..1200 {
            let t = 0.2 * k as f64;
            let (p, v) = at(t);
            if let Some(pv) = prev {
                r.observe(pv, t, &p, &v);
            }
            prev = Some((t, p, v));
        }
        assert!((r.scale - 1.0).abs() < 0.003, "{}", r.scale);
    }
    /// Fixes at 5 Hz for `secs` true s: boot time `boot + rate × true` plus
    /// ±`jitter` s of logger stamp jitter, receiver time to the ms on a GPS
    /// seconds epoch; `edit` may change or drop each pair (true s, boot s,
    /// receiver s). Returns the clock after every pair.
    fn receiver_run(rate: f64, secs: f64, jitter: f64, mut edit: impl FnMut(f64, f64, f64) -> Option<(f64, f64)>) -> Vec<(f64, f64)> {
        let mut rng = crate::rng::Rng::new(7);
        let mut c = ClockRate::new();
        let mut out = vec![];
        let mut last_t = f64::NEG_INFINITY;
        for k in 0..(secs * 5.0) as usize {
            let tt = 0.2 * k as f64;
            let t = (30.0 + rate * tt + jitter * (2.0 * rng.uniform() - 1.0)).max(last_t);
            let g = 1.3e9 + (tt * 1e3).round() / 1e3;
            if let Some((t, g)) = edit(tt, t, g) {
                last_t = t;
                c.observe_time(t, g);
                out.push((tt, c.scale));
            }
        }
        out
    }

    #[test]
    fn the_receivers_time_gives_a_093_or_097_clock_within_01_percent_in_10_s() {
        for rate in [0.93, 0.97] {
            let run = receiver_run(rate, 10.0, 0.01, |_, t, g| Some((t, g)));
            let (tt, k) = *run.last().unwrap();
            assert!(tt < 10.0 && (k * rate - 1.0).abs() < 1e-3, "rate {rate}: scale {k} after {tt} s");
            // Usable within 2 s of the first fix already (to 0.5%).
            let k2 = run.iter().find(|(tt, _)| *tt >= 2.0).unwrap().1;
            assert!((k2 * rate - 1.0).abs() < 5e-3, "rate {rate}: scale {k2} after 2 s");
        }
        // Without gps_time nothing is learnt from it; the rate stays 1.
        let mut c = ClockRate::new();
        c.observe_time(1.0, f64::NAN);
        assert!(c.receiver.run.is_none() && c.scale == 1.0);
    }

    /// Feed the altitude vote's two references one 5 Hz epoch: the GPS
    /// altitude's offset `e` (m, up) against a baro and a Doppler track
    /// that carry white noise of 0.3 m; learn on normal epochs as the
    /// detector does. Returns the vote and whether it saw a return.
    fn vote_epoch(c: &mut Consistency, rng: &mut crate::rng::Rng, e: f64, epv: f64, learn: bool) -> (f64, bool) {
        let dt = 0.2;
        c.baro_gps_level.step(dt, [0.3 * rng.normal() - e, 0.0, 0.0], [0.0; 3], [0.0; 3]);
        c.track.step(dt, [0.0, 0.0, 0.3 * rng.normal() - e], [0.0; 3], [0.0; 3]);
        let out = c.altitude_vote(epv, true);
        if learn {
            c.track.learn();
            c.baro_gps_level.learn();
        }
        out
    }

    #[test]
    fn the_altitude_vote_calls_a_step_both_references_see_and_its_return() {
        let mut c = Consistency::new();
        let mut rng = crate::rng::Rng::new(3);
        for _ in 0..200 {
            let (v, back) = vote_epoch(&mut c, &mut rng, 0.0, 1.0, true);
            assert!(!back && !(v > VOTE_Z), "calm: {v}");
        }
        // A 6 m step: 6σ of a 1 m claim on both, the same way.
        let mut called = 0;
        for _ in 0..50 {
            let (v, _) = vote_epoch(&mut c, &mut rng, 6.0, 1.0, false);
            called += (v > VOTE_Z) as usize;
        }
        assert!(called >= 45, "{called} of 50 step epochs called");
        // Back: the return is seen once and the baselines move to the fix.
        let (v, back) = vote_epoch(&mut c, &mut rng, 0.0, 1.0, false);
        assert!(back && v == 0.0, "{v} {back}");
        let (v, back) = vote_epoch(&mut c, &mut rng, 0.0, 1.0, true);
        assert!(!back && v < 2.0, "{v} {back}");
    }

    #[test]
    fn the_altitude_vote_takes_the_receivers_claim_as_its_sigma_floor() {
        // The same 6 m step under a receiver that claims 2 m: 3σ, not called.
        let mut c = Consistency::new();
        let mut rng = crate::rng::Rng::new(3);
        for _ in 0..200 {
            vote_epoch(&mut c, &mut rng, 0.0, 2.0, true);
        }
        let (v, _) = vote_epoch(&mut c, &mut rng, 6.0, 2.0, false);
        assert!(v > 2.0 && v < 3.5, "{v}");
    }

    #[test]
    fn one_reference_alone_or_two_disagreeing_condemn_nothing() {
        let mut c = Consistency::new();
        let mut rng = crate::rng::Rng::new(5);
        for _ in 0..200 {
            vote_epoch(&mut c, &mut rng, 0.0, 0.5, true);
        }
        // The baro alone departs (its level moves, the track does not).
        c.baro_gps_level.step(0.2, [8.0, 0.0, 0.0], [0.0; 3], [0.0; 3]);
        c.track.step(0.2, [0.0; 3], [0.0; 3], [0.0; 3]);
        assert_eq!(c.altitude_vote(0.5, true), (0.0, false));
        // Both depart, opposite ways.
        c.track.step(0.2, [0.0, 0.0, -8.0], [0.0; 3], [0.0; 3]);
        assert_eq!(c.altitude_vote(0.5, true).0, 0.0);
    }

    #[test]
    fn the_t_quantile_factor_matches_students_table() {
        // Two-sided 99.73% (z = 3) quantiles of Student's t: 9.22 at 3
        // degrees of freedom, 5.51 at 5, 3.96 at 10, 3.27 at 30.
        for (nu, t) in [(3.0, 9.22), (5.0, 5.51), (10.0, 3.96), (30.0, 3.27)] {
            let got = 3.0 * t_over_z(3.0, nu);
            assert!((got / t - 1.0).abs() < 0.08, "nu {nu}: {got} against {t}");
        }
        assert!((t_over_z(3.0, 1e6) - 1.0).abs() < 1e-5);
    }

    #[test]
    fn a_true_clock_is_left_at_exactly_1() {
        for secs in [3.0, 10.0, 300.0] {
            let run = receiver_run(1.0, secs, 0.01, |_, t, g| Some((t, g)));
            assert_eq!(run.last().unwrap().1, 1.0, "after {secs} s");
        }
        // Jitter alone never moves it: every scale along a 300 s flight is 1.
        let r = receiver_run(1.0, 300.0, 0.03, |_, t, g| Some((t, g))); let bad: Vec<_> = r.iter().filter(|(_, k)| *k != 1.0).collect(); assert!(bad.is_empty(), "{} {:?}", bad.len(), &bad[..bad.len().min(20)]);
    }

    #[test]
    fn rollovers_repeats_stalls_and_corrupt_receiver_times_do_not_corrupt_the_rate() {
        let rate = 0.923;
        let run = receiver_run(rate, 200.0, 0.01, |tt, t, g| match tt {
            // A week rollover: time of week back to 0 at 40 s.
            _ if tt >= 40.0 => Some((t, g - 1.3e9 - 40.0 + if tt >= 120.0 { 1.0 } else { 0.0 })),
            // The receiver repeats its record (same time, later stamp).
            _ if (20.0..22.0).contains(&tt) => Some((t, 1.3e9 + 20.0)),
            // One corrupt time, ahead and behind.
            _ if (25.0..25.1).contains(&tt) => Some((t, g + 3600.0)),
            _ if (26.0..26.1).contains(&tt) => Some((t, g - 0.7)),
            // The logger stalls: boot time jumps 2 s ahead of the receiver.
            _ if tt >= 30.0 => Some((t + 2.0, g)),
            _ => Some((t, g)),
        });
        // A leap second at 120 s (the +1 above) and the edits: after the
        // first 10 s the rate never leaves 0.1% of the truth.
        for (tt, k) in run.iter().filter(|(tt, _)| *tt >= 10.0) {
            assert!((k * rate - 1.0).abs() < 1e-3, "scale {k} at {tt} s");
        }
        let (_, k) = run.last().unwrap();
        assert!((k * rate - 1.0).abs() < 1e-4, "final scale {k}");
    }
}

/// The snapshot codec of this file's state types ([`crate::codec`]): each
/// struct's fields in declaration order (a field left out does not compile;
/// `skip`: not saved, rebuilt on restore).
mod codec_impls {
    use super::*;
    use crate::codec::impl_codec;

    impl_codec!(Output { t, status, f, r, c, kind, gps_epoch, driver });
    impl_codec!(Stats { rows, gps_epochs, imu_rows, baro_rows, retrains, filter_resets, data_gaps, filter_errors });
    impl_codec!(Ring { buf, head, len });
    impl_codec!(Detector { cfg, kf, anchor, imu, ind, clock, imu_noise, last_est, consistency, quality, episode, methods, learning, resid, last, last_ind, stats, oracle, upset_until, bias_calm });
    impl_codec!(ReceiverQuality { pos, speed, degraded_run, declared, acquired, last_declared });
    impl_codec!(UsualClaim { ln, learnt });
    impl_codec!(Clock { last_t, last_fix, gps_dt, gps_jitter, last_fields });
    impl_codec!(ImuNoise { prev, psd, period });
    impl_codec!(LastEstimate { pos, vel, baro_h });
    impl_codec!(Consistency { alt_int, dv_imu, imu_gap, flight_time, last_gps, last_baro, rate, track, baro_gps_level, baro_dop_level, baro_drift, ramp, drag_end, baro_flat, baro_epoch, baro_held, baro_jump });
    impl_codec!(ClockRate { scale, motion, sxy, sxx, start, dv, last, receiver });
    impl_codec!(ReceiverClock { sxx, sxy, syy, pairs, runs, run });
    impl_codec!(ClockRun { t0, g0, n, mx, my, cxx, cxy, cyy, last });
    impl_codec!(Methods { prev_nu, maha, baro_inn, pool });
    impl_codec!(Withheld { groups, baro_calm });
    impl_codec!(Episode { active, imu, imu_calm, coast_start, calm_epochs, receiver_lost, normal_run, withheld, accepted, long_coast, fresh, mean_hold } skip { dating });
    impl_codec!(Learning { anfis, d1, d2, new_faults, d0_x, d0_y } skip { train_x, train_y, cost });
}
