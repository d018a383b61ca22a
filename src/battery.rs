//! Randomised development battery (issue 14, item 9): a seeded generator of
//! independent flights and the harness that measures a detector on them.
//!
//! Each flight is drawn from its seed ([`Flight::draw`]); every draw is kept
//! in the [`Flight`] struct (serialised as the `# battery:` comment of the
//! CSV) so results can be cut by condition. The physics:
//!
//! - **Trajectory** ([`Path`]): speed, heading and climb are piecewise
//!   half-cosine channels, so the vertical position is closed form and the
//!   horizontal one is integrated (Simpson) on a fixed 50 Hz grid that does
//!   not depend on any sensor rate. Multirotor hover, survey lawn-mower,
//!   aggressive (4–6 m/s² manoeuvres; with rotor drag and wind the tilt
//!   reaches 40–50° at speed) and fixed-wing-like (ground roll, banked
//!   turns); every flight takes off from and lands on the ground.
//! - **GPS**: white, Gauss–Markov or mixed position noise (σ 0.3–3 m
//!   horizontal, 1.6–2.4× vertical), white velocity noise, 1–20 Hz, with
//!   `eph`/`epv`/`sats` consistent with the drawn σ. Logger gaps (records
//!   dropped while the receiver keeps its fix, unlabelled) and single dropped
//!   records; real fix losses are the `outage` fault (rows with `fix` 0 and
//!   no position).
//! - **IMU** 50–400 Hz, consumer MEMS to tactical grade, *snapshot-sampled*:
//!   each row is the instantaneous specific force plus airframe vibration
//!   (blade-pass sinusoids, aliased at low rates) and white noise. Slow error
//!   processes (attitude error, bias wander) live on a fixed 10 Hz grid, so
//!   the same flight at another IMU rate shares them.
//! - **Baro** 10–50 Hz: datum offset, Gauss–Markov error, white noise,
//!   dynamic-pressure error ∝ airspeed², prop-wash error ∝ climb rate and a
//!   ground-effect band near take-off and landing.
//! - **Boot clock**: `t` = boot offset + rate × true time, rate 0.92–1.0.
//!   Every GPS row carries the receiver's time (`gps_time`): true time plus
//!   a GPS-seconds epoch, to the ms, so the rate can be measured against it.
//! - **Faults** ([`FaultKind`]), 3–120 s, some starting in the first 20 s.
//!   `label` (GPS rows only, as in [`crate::sim`]) is 1 exactly on the rows
//!   whose true time lies in a fault's `[start, end)`.
//!
//! Independent random streams (one per sensor, salted from the seed) keep the
//! GPS and baro records of a flight bit-identical across IMU rates.
//!
//! Splits: `tune` seeds 1,000,000+, `eval` seeds 2,000,000+ (disjoint); GPS
//! at 20 Hz and the `mixed` noise family occur only in `eval`.

use nalgebra::{UnitQuaternion, Vector3};
use serde::Serialize;

use crate::audit::RetroSpans;
use crate::config::Config;
use crate::detector::Detector;
use crate::frames::Anchor;
use crate::metrics::{Accumulator, Metrics};
use crate::sample::Sample;
use crate::sim::{smooth, thrust_attitude, GaussMarkov, Rng, ORIGIN};

const PI: f64 = core::f64::consts::PI;
const G: f64 = crate::filter::GRAVITY;

// ---------------------------------------------------------------------------
// Splits and seeds

/// Which seed range a flight comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Split {
    /// For tuning and training: seeds `TUNE_BASE + i`.
    Tune,
    /// For reporting only: seeds `EVAL_BASE + i`; also has conditions never
    /// drawn in `tune` (GPS 20 Hz, mixed GPS noise).
    Eval,
}

/// First seed of the tune split (flights `0..1_000_000`).
pub const TUNE_BASE: u64 = 1_000_000;
/// First seed of the eval split (flights `0..1_000_000`).
pub const EVAL_BASE: u64 = 2_000_000;
/// Flights per split (seed range length).
pub const SPLIT_LEN: u64 = 1_000_000;
/// Eval-split flight index where the specific checks' flights start (the
/// random eval flights use indices below it).
pub const CHECK_BASE: u64 = 500_000;

impl Split {
    /// Parse a split name (`tune` or `eval`), as given to `--split`.
    pub fn parse(s: &str) -> Result<Split, String> {
        match s {
            "tune" => Ok(Split::Tune),
            "eval" => Ok(Split::Eval),
            _ => Err(format!("split: unknown split \"{s}\" (tune, eval)")),
        }
    }
    /// Lower-case name (`tune`, `eval`), as parsed and printed.
    pub fn name(self) -> &'static str {
        match self {
            Split::Tune => "tune",
            Split::Eval => "eval",
        }
    }
    /// Seed of flight `index` of this split.
    pub fn seed(self, index: u64) -> u64 {
        let base = match self {
            Split::Tune => TUNE_BASE,
            Split::Eval => EVAL_BASE,
        };
        base + index % SPLIT_LEN
    }
    /// GPS rates drawn in this split, Hz.
    pub fn gps_rates(self) -> &'static [f64] {
        match self {
            Split::Tune => &[1.0, 2.0, 5.0, 10.0],
            Split::Eval => &[1.0, 2.0, 5.0, 10.0, 20.0],
        }
    }
    /// GPS noise families drawn in this split.
    pub fn noise_families(self) -> &'static [NoiseFamily] {
        match self {
            Split::Tune => &[NoiseFamily::White, NoiseFamily::GaussMarkov],
            Split::Eval => &[NoiseFamily::White, NoiseFamily::GaussMarkov, NoiseFamily::Mixed],
        }
    }
}

// ---------------------------------------------------------------------------
// Draws

/// GPS position noise family (`mixed` is drawn only in `eval`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum NoiseFamily {
    /// Independent per epoch.
    White,
    /// First-order Gauss–Markov (τ 30–300 s) plus 5% white.
    GaussMarkov,
    /// Gauss–Markov and white sharing the variance (30–70% Gauss–Markov).
    Mixed,
}

/// IMU grade: sets the ranges the noise, bias and attitude error are drawn from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ImuGrade {
    /// Consumer MEMS: 150–400 µg/√Hz, bias σ 0.05–0.3 m/s², tilt error 0.3–1°, heading 1–3°.
    Consumer,
    /// Industrial: 60–150 µg/√Hz, bias σ 0.01–0.05 m/s², tilt error 0.1–0.3°, heading 0.5–1°.
    Industrial,
    /// Tactical: 20–60 µg/√Hz, bias σ 0.002–0.01 m/s², tilt error 0.02–0.08°, heading 0.1–0.3°.
    Tactical,
}

/// Trajectory family of a flight (drawn uniformly unless a check pins it).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum PathKind {
    /// Multirotor position hold with small moves and height changes.
    Hover,
    /// Multirotor lawn-mower survey legs.
    Survey,
    /// Multirotor sprints, stops, hard turns, climbs and drops.
    Aggressive,
    /// Fixed-wing-like: ground roll, climb-out, banked turns, glide landing.
    FixedWing,
}

impl PathKind {
    /// Every kind, in draw order (drawn uniformly).
    pub const ALL: [PathKind; 4] = [PathKind::Hover, PathKind::Survey, PathKind::Aggressive, PathKind::FixedWing];
    /// Kebab-case name, as in the tables and flight lines.
    pub fn name(self) -> &'static str {
        match self {
            PathKind::Hover => "hover",
            PathKind::Survey => "survey",
            PathKind::Aggressive => "aggressive",
            PathKind::FixedWing => "fixed-wing",
        }
    }
    fn multirotor(self) -> bool {
        self != PathKind::FixedWing
    }
}

/// Fault kinds of the battery. Magnitude units per kind in [`Fault`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum FaultKind {
    /// GPS position step (m), horizontal or vertical.
    Step,
    /// GPS position and velocity frozen at their onset values.
    Frozen,
    /// Position-only ramp (m/s) with a truthful GPS velocity.
    Ramp,
    /// Position and velocity dragged off together (m/s), spoofing-like.
    DragOff,
    /// Receiver reports no fix (`fix` 0, no position).
    Outage,
    /// Degraded fix: offset (m) plus a random walk, few satellites.
    Degraded,
    /// Accelerometer bias (m/s²) on one body axis.
    AccelBias,
    /// Baro step (m).
    BaroStep,
    /// Baro output held at its onset value.
    BaroStuck,
    /// Baro drift (m/s).
    BaroDrift,
}

impl FaultKind {
    /// Every kind, in draw order (drawn uniformly).
    pub const ALL: [FaultKind; 10] = [
        FaultKind::Step,
        FaultKind::Frozen,
        FaultKind::Ramp,
        FaultKind::DragOff,
        FaultKind::Outage,
        FaultKind::Degraded,
        FaultKind::AccelBias,
        FaultKind::BaroStep,
        FaultKind::BaroStuck,
        FaultKind::BaroDrift,
    ];
    /// Kebab-case name, as in the tables and flight lines.
    pub fn name(self) -> &'static str {
        match self {
            FaultKind::Step => "step",
            FaultKind::Frozen => "frozen",
            FaultKind::Ramp => "ramp",
            FaultKind::DragOff => "drag-off",
            FaultKind::Outage => "outage",
            FaultKind::Degraded => "degraded",
            FaultKind::AccelBias => "accel-bias",
            FaultKind::BaroStep => "baro-step",
            FaultKind::BaroStuck => "baro-stuck",
            FaultKind::BaroDrift => "baro-drift",
        }
    }
    /// Magnitude range drawn for this kind (units as in [`Fault`]).
    pub fn magnitude_range(self) -> (f64, f64) {
        match self {
            FaultKind::Step => (5.0, 20.0),
            FaultKind::Ramp | FaultKind::DragOff => (0.3, 1.0),
            FaultKind::Degraded => (5.0, 12.0),
            FaultKind::AccelBias => (0.3, 1.5),
            FaultKind::BaroStep => (3.0, 15.0),
            FaultKind::BaroDrift => (0.1, 0.5),
            FaultKind::Frozen | FaultKind::Outage | FaultKind::BaroStuck => (0.0, 0.0),
        }
    }
    /// Whether a vertical variant is drawn.
    fn has_axis(self) -> bool {
        matches!(self, FaultKind::Step | FaultKind::Ramp | FaultKind::DragOff | FaultKind::AccelBias)
    }
}

/// Axis of a fault's offset; only step, ramp, drag-off and accel bias draw `Vertical`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Axis {
    /// North–east plane (body x–y for the accelerometer).
    Horizontal,
    /// Down (body z for the accelerometer).
    Vertical,
}

/// One injected fault.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct Fault {
    /// What fails.
    pub kind: FaultKind,
    /// Horizontal or vertical (always horizontal for kinds without an axis).
    pub axis: Axis,
    /// m (step, degraded, baro-step), m/s (ramp, drag-off, baro-drift),
    /// m/s² (accel-bias); 0 for frozen, outage, baro-stuck.
    pub magnitude: f64,
    /// Direction: heading of a horizontal offset (rad), or the sign (±1)
    /// of a vertical one (positive = up for GPS and baro).
    pub direction: f64,
    /// True-time interval `[start, end)`, s from the log start.
    pub start: f64,
    /// End of the true-time interval (exclusive), s from the log start.
    pub end: f64,
    /// The same interval on the log's boot clock (`t` column), s.
    pub start_log: f64,
    /// End of the interval on the boot clock (`t` column), s.
    pub end_log: f64,
    /// Drag-off: time over which the velocity offset builds up, s.
    pub onset: f64,
}

impl Fault {
    /// Fault length, true s (`end − start`).
    pub fn duration(&self) -> f64 {
        self.end - self.start
    }
    fn active(&self, t: f64) -> bool {
        t >= self.start && t < self.end
    }
    /// Unit offset direction in NED for GPS faults (vertical sign: up = −d).
    fn ned_dir(&self) -> Vector3<f64> {
        match self.axis {
            Axis::Horizontal => Vector3::new(libm::cos(self.direction), libm::sin(self.direction), 0.0),
            Axis::Vertical => Vector3::new(0.0, 0.0, -self.direction.signum()),
        }
    }
}

/// GPS receiver draws.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct GpsDraw {
    /// Epochs per second (true time).
    pub rate: f64,
    /// Position noise family.
    pub family: NoiseFamily,
    /// Position error σ, m (1σ per axis horizontal; vertical).
    pub sigma_h: f64,
    /// Vertical position error σ, m (1.6–2.4× `sigma_h`).
    pub sigma_v: f64,
    /// Gauss–Markov correlation time, s, and its share of the variance.
    pub tau: f64,
    /// Gauss–Markov share of the position variance (0 white, 0.95 Gauss–Markov, 0.3–0.7 mixed).
    pub gm_share: f64,
    /// Velocity white noise σ, m/s (horizontal per axis; vertical).
    pub vel_sigma_h: f64,
    /// Vertical velocity noise σ, m/s (1.3–2× `vel_sigma_h`).
    pub vel_sigma_v: f64,
    /// Reported `eph` = eph_scale × σ_h (× satellite factor); `epv` likewise.
    pub eph_scale: f64,
    /// Typical satellites used.
    pub sats: f64,
    /// Probability that a single record is dropped by the logger.
    pub drop_prob: f64,
    /// Logger gaps (true time `[a, b)`, s): records dropped, fix kept.
    pub gaps: Vec<[f64; 2]>,
    /// Phase of the first epoch, s.
    pub phase: f64,
    /// The receiver reports its speed accuracy (`sacc` = `eph_scale` ×
    /// `vel_sigma_h` × the satellite factor; five times that while
    /// degraded, the onset's while frozen). Off in the drawn battery, whose
    /// figures the README tracks; `Flight::with_speed_claims` turns it on.
    pub reports_sacc: bool,
}

/// IMU draws.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct ImuDraw {
    /// Samples per second (true time), Hz: 50, 100, 200 or 400.
    pub rate: f64,
    /// Grade the noise, bias and attitude-error ranges are drawn from.
    pub grade: ImuGrade,
    /// Accelerometer white noise density, m/s²/√Hz.
    pub accel_density: f64,
    /// Turn-on accelerometer bias, m/s² (body x, y, z).
    pub accel_bias: [f64; 3],
    /// Gyro white noise density, rad/s/√Hz.
    pub gyro_density: f64,
    /// Attitude error: constant tilt σ and Gauss–Markov wander σ (deg),
    /// heading error σ (deg).
    pub tilt_sigma_deg: f64,
    /// Gauss–Markov tilt wander σ per axis, deg (τ 20–60 s).
    pub wander_sigma_deg: f64,
    /// Constant heading error σ, deg.
    pub heading_sigma_deg: f64,
    /// Airframe vibration RMS at full throttle, m/s² per horizontal axis
    /// (vertical 1.5×), and the blade-pass frequency, Hz.
    pub vibration: f64,
    /// Blade-pass frequency, Hz (60–220); its harmonic (1.9–2.1×) adds at half amplitude.
    pub vibration_hz: f64,
}

/// Barometer draws.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct BaroDraw {
    /// Samples per second (true time), Hz: 10, 20, 25 or 50.
    pub rate: f64,
    /// Time of the first sample, true s (0–0.02).
    pub phase: f64,
    /// Datum offset, m.
    pub offset: f64,
    /// Gauss–Markov error σ (m), τ (s); white noise σ (m).
    pub gm_sigma: f64,
    /// Gauss–Markov correlation time, s (10–60).
    pub gm_tau: f64,
    /// White noise σ, m (0.05–0.3).
    pub white: f64,
    /// Dynamic-pressure error per airspeed², m/(m/s)².
    pub k_dynamic: f64,
    /// Prop-wash error per climb rate, m/(m/s) (positive: reads high when climbing).
    pub k_climb: f64,
    /// Ground-effect error on the ground (m), fading out by `ground_height` m.
    pub ground_effect: f64,
    /// Height at which the ground effect has faded to 0, m (1.5–4).
    pub ground_height: f64,
}

/// Boot-clock draws: `t_log = boot + rate × t_true`; the receiver's time
/// `gps_time = gps_epoch + t_true`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct ClockDraw {
    /// Boot-clock seconds per true second: 1 (half the flights) or 0.92–1.0.
    pub rate: f64,
    /// Boot-clock time at true time 0, s (5–60).
    pub boot: f64,
    /// GPS seconds (since 1980) at true time 0: 2011–2027.
    pub gps_epoch: f64,
}

/// Trajectory draws (the shape itself is built from `seed` by [`Path::build`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct PathDraw {
    /// Trajectory family.
    pub kind: PathKind,
    /// Flight length (true time), s.
    pub duration: f64,
    /// Wind (north, east), m/s.
    pub wind: [f64; 2],
    /// Multirotor drag: linear (1/s) and quadratic (1/m) coefficients.
    pub drag_linear: f64,
    /// Quadratic drag coefficient, 1/m (0.008–0.015 multirotor; 0 fixed-wing).
    pub drag_quadratic: f64,
}

/// One battery flight: every draw.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct Flight {
    /// Which seed range the flight comes from.
    pub split: Split,
    /// Flight index within the split.
    pub index: u64,
    /// Seed the flight is drawn from (`split.seed(index)`).
    pub seed: u64,
    /// Trajectory draws.
    pub path: PathDraw,
    /// GPS receiver draws.
    pub gps: GpsDraw,
    /// IMU draws.
    pub imu: ImuDraw,
    /// Barometer draws.
    pub baro: BaroDraw,
    /// Boot-clock and receiver-time draws.
    pub clock: ClockDraw,
    /// Injected faults, sorted by start (none for a clean flight).
    pub faults: Vec<Fault>,
    /// Summary of the built path: lift-off and touch-down (true s), peak
    /// height (m), speed (m/s), tilt (deg) and horizontal acceleration (m/s²).
    pub liftoff: f64,
    /// Touch-down, true s.
    pub touchdown: f64,
    /// Peak height above the take-off point, m.
    pub max_height: f64,
    /// Peak horizontal ground speed, m/s.
    pub max_speed: f64,
    /// Peak tilt of the body z axis from vertical, deg.
    pub max_tilt_deg: f64,
    /// Peak horizontal acceleration, m/s².
    pub max_accel_h: f64,
}

const SALT_DRAW: u64 = 0x0D1A_F00D_0000_0001;
const SALT_PATH: u64 = 0x0D1A_F00D_0000_0002;
const SALT_GPS: u64 = 0x0D1A_F00D_0000_0003;
const SALT_IMU: u64 = 0x0D1A_F00D_0000_0004;
const SALT_BARO: u64 = 0x0D1A_F00D_0000_0005;
const SALT_SLOW: u64 = 0x0D1A_F00D_0000_0006;
/// Its own stream, so the receiver-time epoch moved no other draw.
const SALT_CLOCK: u64 = 0x0D1A_F00D_0000_0007;

fn pick<T: Copy>(rng: &mut Rng, xs: &[T]) -> T {
    let i = ((rng.uniform() * xs.len() as f64) as usize).min(xs.len().saturating_sub(1));
    xs[i]
}

fn log_uniform(rng: &mut Rng, lo: f64, hi: f64) -> f64 {
    libm::exp(rng.range(libm::log(lo), libm::log(hi)))
}

/// Per-flight choices the specific checks pin.
#[derive(Clone, Copy, Debug, Default)]
pub struct Overrides {
    /// Trajectory family to use instead of drawing one (frozen GPS needs a moving vehicle).
    pub path: Option<PathKind>,
    /// Minimum flight length, s.
    pub min_duration: Option<f64>,
}

impl Flight {
    /// Flight `index` of `split`: every condition and fault drawn from its seed.
    pub fn draw(split: Split, index: u64) -> Flight {
        let mut f = Flight::conditions(split, index, Overrides::default());
        let mut rng = Rng::new(f.seed ^ SALT_DRAW ^ 0xFA);
        f.faults = draw_faults(&f, &mut rng);
        f
    }

    /// The flight's conditions without faults.
    pub fn conditions(split: Split, index: u64, ov: Overrides) -> Flight {
        let seed = split.seed(index);
        let mut rng = Rng::new(seed ^ SALT_DRAW);
        let kind = ov.path.unwrap_or_else(|| pick(&mut rng, &PathKind::ALL));
        let (dlo, dhi) = match kind {
            PathKind::Hover => (150.0, 300.0),
            PathKind::Survey | PathKind::FixedWing => (240.0, 480.0),
            PathKind::Aggressive => (180.0, 360.0),
        };
        let duration = rng.range(dlo, dhi).max(ov.min_duration.unwrap_or(0.0));
        let wind_speed = rng.range(0.0, 6.0);
        let wind_dir = rng.range(0.0, 2.0 * PI);
        let path = PathDraw {
            kind,
            duration,
            wind: [wind_speed * libm::cos(wind_dir), wind_speed * libm::sin(wind_dir)],
            drag_linear: if kind.multirotor() { rng.range(0.1, 0.2) } else { 0.0 },
            drag_quadratic: if kind.multirotor() { rng.range(0.008, 0.015) } else { 0.0 },
        };

        let gps = draw_gps(split, duration, &mut rng);
        let imu = draw_imu(&mut rng);
        let baro = BaroDraw {
            rate: pick(&mut rng, &[10.0, 20.0, 25.0, 50.0]),
            phase: rng.range(0.0, 0.02),
            offset: rng.range(-30.0, 30.0),
            gm_sigma: rng.range(0.2, 1.0),
            gm_tau: rng.range(10.0, 60.0),
            white: rng.range(0.05, 0.3),
            k_dynamic: rng.range(-0.02, 0.02),
            k_climb: rng.range(-0.8, 0.8),
            ground_effect: rng.range(0.3, 2.0) * if rng.uniform() < 0.5 { -1.0 } else { 1.0 },
            ground_height: rng.range(1.5, 4.0),
        };
        let clock = ClockDraw {
            rate: if rng.uniform() < 0.5 { 1.0 } else { rng.range(0.92, 1.0) },
            boot: rng.range(5.0, 60.0),
            gps_epoch: libm::round(Rng::new(seed ^ SALT_CLOCK).range(1.0e9, 1.5e9)),
        };
        let mut f = Flight {
            split,
            index,
            seed,
            path,
            gps,
            imu,
            baro,
            clock,
            faults: vec![],
            liftoff: 0.0,
            touchdown: 0.0,
            max_height: 0.0,
            max_speed: 0.0,
            max_tilt_deg: 0.0,
            max_accel_h: 0.0,
        };
        let p = Path::build(&f);
        f.liftoff = p.liftoff;
        f.touchdown = p.touchdown;
        let (h, s, tilt, acc) = p.extremes(&f.path);
        f.max_height = h;
        f.max_speed = s;
        f.max_tilt_deg = tilt;
        f.max_accel_h = acc;
        f
    }

    /// The same flight with another IMU rate (every other draw unchanged).
    pub fn with_imu_rate(&self, rate: f64) -> Flight {
        let mut f = self.clone();
        f.imu.rate = rate;
        f
    }

    /// The same flight with a receiver that reports its speed accuracy
    /// (`GpsDraw::reports_sacc`); every other row is the same.
    pub fn with_speed_claims(&self) -> Flight {
        let mut f = self.clone();
        f.gps.reports_sacc = true;
        f
    }

    /// Add a fault over true time `[start, start + length)`, s.
    pub fn add_fault(&mut self, kind: FaultKind, axis: Axis, magnitude: f64, direction: f64, start: f64, length: f64) {
        let end = (start + length).min(self.path.duration);
        let onset = if kind == FaultKind::DragOff { 3.0 } else { 0.0 };
        self.faults.push(Fault {
            kind,
            axis,
            magnitude,
            direction,
            start,
            end,
            start_log: self.log_time(start),
            end_log: self.log_time(end),
            onset,
        });
    }

    /// Boot-clock time of a true time, s (quantised to 1 µs like the rows).
    pub fn log_time(&self, t: f64) -> f64 {
        libm::round((self.clock.boot + self.clock.rate * t) * 1e6) / 1e6
    }

    /// The receiver's time of a true time, s (to the ms, as receivers report).
    pub fn gps_time(&self, t: f64) -> f64 {
        self.clock.gps_epoch + libm::round(t * 1e3) / 1e3
    }

    /// Whether any fault is active at true time `t`.
    pub fn faulty_at(&self, t: f64) -> bool {
        self.faults.iter().any(|f| f.active(t))
    }

    /// A one-line description.
    pub fn describe(&self) -> String {
        let faults: Vec<String> = self
            .faults
            .iter()
            .map(|f| format!("{} {:?} {:.2} at {:.1}-{:.1} s", f.kind.name(), f.axis, f.magnitude, f.start, f.end))
            .collect();
        format!(
            "{} #{} seed {}: {} {:.0} s, GPS {} Hz {:?} σ {:.2} m{}, IMU {} Hz {:?} vib {:.1}, clock {:.3}; faults: {}",
            self.split.name(),
            self.index,
            self.seed,
            self.path.kind.name(),
            self.path.duration,
            self.gps.rate,
            self.gps.family,
            self.gps.sigma_h,
            if self.gps.reports_sacc { " with sAcc" } else { "" },
            self.imu.rate,
            self.imu.grade,
            self.imu.vibration,
            self.clock.rate,
            if faults.is_empty() { "none".into() } else { faults.join("; ") }
        )
    }
}

fn draw_gps(split: Split, duration: f64, rng: &mut Rng) -> GpsDraw {
    let rate = pick(rng, split.gps_rates());
    let family = pick(rng, split.noise_families());
    let sigma_h = log_uniform(rng, 0.3, 3.0);
    let sigma_v = sigma_h * rng.range(1.6, 2.4);
    let tau = log_uniform(rng, 30.0, 300.0);
    let gm_share = match family {
        NoiseFamily::White => 0.0,
        NoiseFamily::GaussMarkov => 0.95,
        NoiseFamily::Mixed => rng.range(0.3, 0.7),
    };
    let vel_sigma_h = 0.02 + sigma_h * rng.range(0.04, 0.1);
    let vel_sigma_v = vel_sigma_h * rng.range(1.3, 2.0);
    let eph_scale = rng.range(0.8, 1.5);
    let sats = libm::round((18.0 - 3.0 * sigma_h + 1.5 * rng.normal()).clamp(6.0, 24.0));
    let drop_prob = if rng.uniform() < 0.4 { 0.0 } else { rng.range(0.0, 0.03) };
    // Logger gaps: Poisson arrivals, 0–2 per minute, 0.3–1.2 s long.
    let gap_rate = if rng.uniform() < 0.35 { 0.0 } else { rng.range(0.1, 2.0) / 60.0 };
    let mut gaps = vec![];
    if gap_rate > 0.0 {
        let mut t = 0.0;
        loop {
            t += -libm::log(rng.uniform().max(1e-12)) / gap_rate;
            if t >= duration {
                break;
            }
            let len = rng.range(0.3, 1.2);
            gaps.push([t, t + len]);
            t += len;
        }
    }
    GpsDraw {
        rate,
        family,
        sigma_h,
        sigma_v,
        tau,
        gm_share,
        vel_sigma_h,
        vel_sigma_v,
        eph_scale,
        sats,
        drop_prob,
        gaps,
        phase: rng.range(0.0, 1.0 / rate),
        reports_sacc: false,
    }
}

fn draw_imu(rng: &mut Rng) -> ImuDraw {
    let rate = pick(rng, &[50.0, 100.0, 200.0, 400.0]);
    let grade = pick(rng, &[ImuGrade::Consumer, ImuGrade::Industrial, ImuGrade::Tactical]);
    // (accel density µg/√Hz, bias m/s², gyro density °/s/√Hz, tilt °, wander °, heading °)
    let (dens, bias, gyro, tilt, wander, heading) = match grade {
        ImuGrade::Consumer => ((150.0, 400.0), (0.05, 0.3), (0.005, 0.015), (0.3, 1.0), (0.2, 0.6), (1.0, 3.0)),
        ImuGrade::Industrial => ((60.0, 150.0), (0.01, 0.05), (0.002, 0.005), (0.1, 0.3), (0.05, 0.2), (0.5, 1.0)),
        ImuGrade::Tactical => ((20.0, 60.0), (0.002, 0.01), (0.0005, 0.002), (0.02, 0.08), (0.01, 0.05), (0.1, 0.3)),
    };
    let b = rng.range(bias.0, bias.1);
    ImuDraw {
        rate,
        grade,
        accel_density: rng.range(dens.0, dens.1) * 1e-6 * G,
        accel_bias: [b * rng.normal().clamp(-2.0, 2.0), b * rng.normal().clamp(-2.0, 2.0), b * rng.normal().clamp(-2.0, 2.0)],
        gyro_density: rng.range(gyro.0, gyro.1).to_radians(),
        tilt_sigma_deg: rng.range(tilt.0, tilt.1),
        wander_sigma_deg: rng.range(wander.0, wander.1),
        heading_sigma_deg: rng.range(heading.0, heading.1),
        vibration: log_uniform(rng, 0.2, 6.0),
        vibration_hz: rng.range(60.0, 220.0),
    }
}

/// Faults of a flight: none (20%), one (60%) or two (20%) that do not
/// overlap and are at least 30 s apart; a quarter start 5–20 s into the log.
fn draw_faults(f: &Flight, rng: &mut Rng) -> Vec<Fault> {
    let u = rng.uniform();
    let n = if u < 0.2 { 0 } else if u < 0.8 { 1 } else { 2 };
    let mut out = Flight { faults: vec![], ..f.clone() };
    let path = Path::build(f);
    for _ in 0..n {
        let kind = pick(rng, &FaultKind::ALL);
        let axis = if kind.has_axis() && rng.uniform() < 0.4 { Axis::Vertical } else { Axis::Horizontal };
        let (lo, hi) = kind.magnitude_range();
        let magnitude = rng.range(lo, hi);
        let direction = match axis {
            Axis::Horizontal => rng.range(0.0, 2.0 * PI),
            Axis::Vertical => {
                if rng.uniform() < 0.5 {
                    -1.0
                } else {
                    1.0
                }
            }
        };
        let length = log_uniform(rng, 3.0, 120.0);
        let early = rng.uniform() < 0.25;
        // Try a few starts; keep the first that fits (and, for a stuck baro,
        // spans a height change of at least 3 m, else it is unobservable).
        for _ in 0..20 {
            let latest = (f.path.duration - length - 5.0).max(0.0);
            // Early starts leave 5 s of fault-free data: a fault present from
            // the first fix has no reference to be judged against.
            let start = if early { rng.range(5.0f64.min(latest), 20.0f64.min(latest)) } else { rng.range(20.0f64.min(latest), latest) };
            let end = start + length;
            let clear = out.faults.iter().all(|g| end + 30.0 <= g.start || start >= g.end + 30.0);
            let observable = kind != FaultKind::BaroStuck || path.height_range(start, end) >= 3.0;
            if clear && observable && end <= f.path.duration {
                out.add_fault(kind, axis, magnitude, direction, start, length);
                break;
            }
        }
    }
    out.faults.sort_by(|a, b| a.start.total_cmp(&b.start));
    out.faults
}

// ---------------------------------------------------------------------------
// Trajectory

/// One half-cosine transition of a channel: from its previous value to `to`
/// over `[t0, t0 + dur]`, then held.
#[derive(Clone, Copy, Debug)]
struct Knot {
    t0: f64,
    dur: f64,
    from: f64,
    to: f64,
    /// ∫ of the channel over [0, t0].
    area: f64,
}

/// A piecewise half-cosine signal with closed-form value and integral.
#[derive(Clone, Debug, Default)]
struct Channel {
    v0: f64,
    knots: Vec<Knot>,
}

impl Channel {
    fn new(v0: f64) -> Self {
        Channel { v0, knots: vec![] }
    }
    fn end(&self) -> f64 {
        self.knots.last().map_or(0.0, |k| k.t0 + k.dur)
    }
    fn last(&self) -> f64 {
        self.knots.last().map_or(self.v0, |k| k.to)
    }
    /// Move to `to` over `[t0, t0 + dur]`; `t0` is pushed past the previous knot.
    fn to(&mut self, t0: f64, dur: f64, to: f64) -> f64 {
        let t0 = t0.max(self.end());
        let area = self.integral(t0);
        let from = self.last();
        self.knots.push(Knot { t0, dur: dur.max(1e-3), from, to, area });
        t0 + dur.max(1e-3)
    }
    fn knot(&self, t: f64) -> Option<&Knot> {
        let i = self.knots.partition_point(|k| k.t0 <= t);
        if i == 0 {
            None
        } else {
            self.knots.get(i - 1)
        }
    }
    fn value(&self, t: f64) -> f64 {
        match self.knot(t) {
            None => self.v0,
            Some(k) if t < k.t0 + k.dur => k.from + (k.to - k.from) * smooth(t, k.t0, k.t0 + k.dur),
            Some(k) => k.to,
        }
    }
    /// ∫ of the channel over [0, t].
    fn integral(&self, t: f64) -> f64 {
        match self.knot(t) {
            None => self.v0 * t,
            Some(k) if t < k.t0 + k.dur => {
                // ∫₀ˣ (½ − ½cos πu) du = x/2 − sin(πx)/(2π)
                let x = (t - k.t0) / k.dur;
                k.area + k.dur * (k.from * x + (k.to - k.from) * (0.5 * x - libm::sin(PI * x) / (2.0 * PI)))
            }
            Some(k) => k.area + 0.5 * k.dur * (k.from + k.to) + k.to * (t - k.t0 - k.dur),
        }
    }
}

/// Horizontal-position grid step, s (fixed: independent of sensor rates).
const GRID_DT: f64 = 0.02;

/// A built trajectory: truth position, velocity, acceleration and attitude
/// as functions of true time.
#[derive(Clone, Debug)]
pub struct Path {
    speed: Channel,
    heading: Channel,
    climb: Channel,
    /// Position-hold wander (amplitude m/s, frequency Hz, phase) north and east.
    wobble: [Vec<(f64, f64, f64)>; 2],
    wind: Vector3<f64>,
    drag: (f64, f64),
    /// Lift-off and touch-down, true s.
    pub liftoff: f64,
    /// Touch-down, true s.
    pub touchdown: f64,
    /// North–east position at grid points, m.
    grid: Vec<[f64; 2]>,
}

/// Finite-difference step for accelerations and rates, s.
const FD: f64 = 1e-3;

impl Path {
    /// Build the trajectory of a flight from its seed and path draws.
    pub fn build(f: &Flight) -> Path {
        let mut rng = Rng::new(f.seed ^ SALT_PATH);
        let d = &f.path;
        let mut b = Builder::new(d.kind, rng.range(0.0, 2.0 * PI));
        b.plan(d.kind, d.duration, &mut rng);
        let wob = |rng: &mut Rng| -> Vec<(f64, f64, f64)> {
            let amp = if d.kind == PathKind::Hover { 0.4 } else { 0.0 };
            (0..2).map(|_| (amp * rng.range(0.3, 1.0), rng.range(0.02, 0.1), rng.range(0.0, 2.0 * PI))).collect()
        };
        let wobble = [wob(&mut rng), wob(&mut rng)];
        let mut p = Path {
            speed: b.speed,
            heading: b.heading,
            climb: b.climb,
            wobble,
            wind: Vector3::new(d.wind[0], d.wind[1], 0.0),
            drag: (d.drag_linear, d.drag_quadratic),
            liftoff: b.liftoff,
            touchdown: b.touchdown,
            grid: vec![],
        };
        let n = libm::ceil(d.duration / GRID_DT) as usize + 2;
        let mut grid = Vec::with_capacity(n);
        let mut pos = [0.0, 0.0];
        for k in 0..n {
            grid.push(pos);
            let a = k as f64 * GRID_DT;
            let s = p.simpson_ne(a, a + GRID_DT);
            pos = [pos[0] + s[0], pos[1] + s[1]];
        }
        p.grid = grid;
        p
    }

    /// Airborne envelope: 0 on the ground, 1 in flight (2 s blends).
    fn airborne(&self, t: f64) -> f64 {
        smooth(t, self.liftoff, self.liftoff + 2.0) * (1.0 - smooth(t, self.touchdown - 2.0, self.touchdown))
    }

    fn wobble_at(&self, t: f64) -> [f64; 2] {
        let env = smooth(t, self.liftoff + 5.0, self.liftoff + 10.0) * (1.0 - smooth(t, self.touchdown - 25.0, self.touchdown - 20.0));
        let sum = |c: &[(f64, f64, f64)]| c.iter().map(|(a, fr, ph)| a * libm::sin(2.0 * PI * fr * t + ph)).sum::<f64>();
        [env * sum(&self.wobble[0]), env * sum(&self.wobble[1])]
    }

    /// Truth velocity NED, m/s.
    pub fn velocity(&self, t: f64) -> Vector3<f64> {
        let s = self.speed.value(t);
        let h = self.heading.value(t);
        let w = self.wobble_at(t);
        Vector3::new(s * libm::cos(h) + w[0], s * libm::sin(h) + w[1], -self.climb.value(t))
    }

    fn simpson_ne(&self, a: f64, b: f64) -> [f64; 2] {
        let (va, vm, vb) = (self.velocity(a), self.velocity(0.5 * (a + b)), self.velocity(b));
        let k = (b - a) / 6.0;
        [k * (va[0] + 4.0 * vm[0] + vb[0]), k * (va[1] + 4.0 * vm[1] + vb[1])]
    }

    /// Truth position NED from the take-off point, m.
    pub fn position(&self, t: f64) -> Vector3<f64> {
        let t = t.max(0.0);
        let k = libm::floor(t / GRID_DT) as usize;
        let (base, t0) = match self.grid.get(k) {
            Some(p) => (*p, k as f64 * GRID_DT),
            None => (self.grid.last().copied().unwrap_or([0.0, 0.0]), (self.grid.len().saturating_sub(1)) as f64 * GRID_DT),
        };
        let s = self.simpson_ne(t0, t);
        // Height is closed form; clamp the last ulps at touch-down to the ground.
        Vector3::new(base[0] + s[0], base[1] + s[1], (-self.climb.integral(t)).min(0.0))
    }

    /// Height above the take-off point, m.
    pub fn height(&self, t: f64) -> f64 {
        self.climb.integral(t).max(0.0)
    }

    /// Truth acceleration NED, m/s² (central difference).
    pub fn acceleration(&self, t: f64) -> Vector3<f64> {
        (self.velocity(t + FD) - self.velocity(t - FD)) / (2.0 * FD)
    }

    /// Air-relative horizontal velocity, m/s.
    fn air_velocity(&self, t: f64) -> Vector3<f64> {
        let v = self.velocity(t);
        Vector3::new(v[0], v[1], 0.0) - self.wind * self.airborne(t)
    }

    /// Truth attitude: body z along minus the thrust (specific force minus
    /// rotor drag for a multirotor), nose along the heading; level on the ground.
    pub fn attitude(&self, t: f64) -> UnitQuaternion<f64> {
        let f = self.acceleration(t) - Vector3::new(0.0, 0.0, G);
        let env = self.airborne(t);
        let va = self.air_velocity(t);
        let drag = -va * (self.drag.0 + self.drag.1 * va.norm()) * env;
        let thrust = f - drag;
        let att = Vector3::new(thrust[0] * env, thrust[1] * env, thrust[2]);
        thrust_attitude(&att, self.heading.value(t))
    }

    /// Max over [a, b] of height minus min of height, m (1 s steps).
    fn height_range(&self, a: f64, b: f64) -> f64 {
        let n = libm::ceil(b - a).max(1.0) as usize;
        let hs: Vec<f64> = (0..=n).map(|i| self.height(a + (b - a) * i as f64 / n as f64)).collect();
        hs.iter().cloned().fold(f64::MIN, f64::max) - hs.iter().cloned().fold(f64::MAX, f64::min)
    }

    /// (max height m, max speed m/s, max tilt deg, max horizontal accel m/s²), 0.1 s steps.
    fn extremes(&self, d: &PathDraw) -> (f64, f64, f64, f64) {
        let mut out = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        let n = (d.duration * 10.0) as usize;
        for i in 0..n {
            let t = i as f64 * 0.1;
            let v = self.velocity(t);
            let a = self.acceleration(t);
            let q = self.attitude(t);
            let z = q.transform_vector(&Vector3::new(0.0, 0.0, 1.0));
            let tilt = libm::acos(z[2].clamp(-1.0, 1.0)).to_degrees();
            out.0 = out.0.max(self.height(t));
            out.1 = out.1.max(libm::hypot(v[0], v[1]));
            out.2 = out.2.max(tilt);
            out.3 = out.3.max(libm::hypot(a[0], a[1]));
        }
        out
    }
}

/// Plans a flight into speed, heading and climb channels.
struct Builder {
    speed: Channel,
    heading: Channel,
    climb: Channel,
    t: f64,
    liftoff: f64,
    touchdown: f64,
}

impl Builder {
    fn new(_kind: PathKind, heading0: f64) -> Self {
        Builder { speed: Channel::new(0.0), heading: Channel::new(heading0), climb: Channel::new(0.0), t: 0.0, liftoff: 0.0, touchdown: 0.0 }
    }

    fn height(&self, t: f64) -> f64 {
        self.climb.integral(t)
    }

    /// Climb (or sink) `dh` m at `rate` m/s from time `t` with `ramp` s
    /// transitions; returns the end time. Height change is exact.
    fn climb_by(&mut self, t: f64, dh: f64, rate: f64, ramp: f64) -> f64 {
        let rate = rate.abs().max(0.1) * dh.signum();
        let flat = (dh / rate - ramp).max(0.0);
        // With a shorter flat part than needed, shrink the rate to keep Δh exact.
        let rate = if dh / rate < ramp { dh / ramp } else { rate };
        let t1 = self.climb.to(t, ramp, rate);
        self.climb.to(t1 + flat, ramp, 0.0)
    }

    /// Time a landing from `h` m takes (descent plus roll-out), s.
    fn landing_time(kind: PathKind, h: f64, rate: f64) -> f64 {
        let ramp = 1.5;
        let descent = (h / rate).max(ramp) + ramp;
        if kind.multirotor() {
            descent + 3.0
        } else {
            descent + 10.0
        }
    }

    fn plan(&mut self, kind: PathKind, duration: f64, rng: &mut Rng) {
        let takeoff = rng.range(3.0, 12.0);
        // Fixed-wing: 8 s roll-out after touch-down, then at least 2 s at rest.
        let idle_after = if kind.multirotor() { rng.range(3.0, 10.0) } else { rng.range(10.0, 16.0) };
        let (cruise, up, down) = match kind {
            PathKind::Hover => (rng.range(8.0, 30.0), rng.range(1.0, 2.5), rng.range(0.7, 1.5)),
            PathKind::Survey => (rng.range(30.0, 80.0), rng.range(1.5, 3.0), rng.range(1.0, 2.0)),
            PathKind::Aggressive => (rng.range(20.0, 60.0), rng.range(3.0, 5.0), rng.range(1.5, 3.0)),
            PathKind::FixedWing => (rng.range(50.0, 120.0), rng.range(2.0, 4.0), rng.range(1.5, 3.0)),
        };
        let v_air = rng.range(12.0, 22.0);
        // Take-off.
        if kind.multirotor() {
            self.liftoff = takeoff;
            self.t = self.climb_by(takeoff, cruise, up, 1.5);
        } else {
            let roll = rng.range(5.0, 8.0);
            let t1 = self.speed.to(takeoff, roll, v_air);
            self.liftoff = t1 - 1.0;
            self.t = self.climb_by(t1 - 1.0, cruise, up, 2.0);
        }
        // Mission until the landing has to begin.
        let mut leg_dir = 1.0;
        loop {
            let h = self.height(self.t);
            let reserve = Self::landing_time(kind, h + 40.0, down) + idle_after + 45.0;
            if self.t + reserve > duration {
                break;
            }
            match kind {
                PathKind::Hover => self.hover_segment(rng, h),
                PathKind::Survey => {
                    self.survey_leg(rng, leg_dir);
                    leg_dir = -leg_dir;
                }
                PathKind::Aggressive => self.aggressive_segment(rng, h),
                PathKind::FixedWing => self.fixed_wing_segment(rng, h, v_air),
            }
        }
        // Stop, then land so that touch-down comes `idle_after` s before the end.
        if kind.multirotor() {
            let s = self.speed.last();
            self.t = self.speed.to(self.t, (s / 1.5).max(2.0), 0.0);
            self.t = self.t.max(self.climb.end());
            let h = self.height(self.t);
            let start = (duration - idle_after - Self::landing_time(kind, h, down) + 3.0).max(self.t);
            self.touchdown = self.climb_by(start, -h, down, 1.5);
        } else {
            self.t = self.t.max(self.climb.end()).max(self.heading.end());
            let h = self.height(self.t);
            let start = (duration - idle_after - Self::landing_time(kind, h, down) + 10.0).max(self.t);
            // Slow down before the descent starts, so the two do not overlap.
            self.speed.to(start, 4.0, 0.75 * v_air);
            self.touchdown = self.climb_by(start, -h, down, 1.5);
            self.speed.to(self.touchdown, 8.0, 0.0);
        }
    }

    fn hover_segment(&mut self, rng: &mut Rng, h: f64) {
        let t = self.t + rng.range(5.0, 25.0);
        let u = rng.uniform();
        if u < 0.4 {
            // Yaw to a new heading, fly a short hop, stop.
            let hd = self.heading.last() + rng.range(-PI, PI);
            let t1 = self.heading.to(t, rng.range(2.0, 5.0), hd);
            let s = rng.range(1.0, 4.0);
            let t2 = self.speed.to(t1, 2.0, s);
            self.t = self.speed.to(t2 + rng.range(3.0, 12.0), 2.0, 0.0);
        } else if u < 0.7 {
            let target = (h + rng.range(-10.0, 10.0)).clamp(8.0, 40.0);
            self.t = self.climb_by(t, target - h, rng.range(0.5, 1.5), 1.0);
        } else {
            self.t = t;
        }
    }

    fn survey_leg(&mut self, rng: &mut Rng, dir: f64) {
        let s = self.speed.last();
        let v = if s > 0.0 { s } else { rng.range(5.0, 12.0) };
        let t1 = if s > 0.0 { self.t } else { self.speed.to(self.t, 5.0, v) };
        let leg = rng.range(60.0, 250.0) / v;
        let t2 = t1 + leg;
        if rng.uniform() < 0.5 {
            // Banked U-turn at speed: peak lateral acceleration ≤ 3 m/s².
            let dur = (v * PI * PI / (2.0 * 3.0)).max(4.0);
            self.t = self.heading.to(t2, dur, self.heading.last() + dir * PI);
        } else {
            // Stop, yaw round, go.
            let t3 = self.speed.to(t2, 5.0, 0.0);
            let t4 = self.heading.to(t3, 4.0, self.heading.last() + dir * PI);
            self.t = self.speed.to(t4, 5.0, v);
        }
    }

    fn aggressive_segment(&mut self, rng: &mut Rng, h: f64) {
        let a = rng.range(4.0, 6.0);
        let s = self.speed.last();
        let t = self.t + rng.range(0.5, 4.0);
        match (rng.uniform() * 4.0) as u32 {
            0 => {
                // Sprint to 10–16 m/s: a half-cosine of peak a takes πΔv/(2a).
                let v = rng.range(10.0, 16.0);
                self.t = self.speed.to(t, (PI * (v - s).abs() / (2.0 * a)).max(0.5), v);
            }
            1 => {
                // Hard stop.
                self.t = self.speed.to(t, (PI * s / (2.0 * a)).max(0.5), 0.0);
            }
            2 => {
                // Hard turn: peak lateral acceleration a at speed s.
                let dh = rng.range(PI / 3.0, PI) * if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
                let dur = (PI * dh.abs() * s.max(1.0) / (2.0 * a)).max(1.0);
                self.t = self.heading.to(t, dur, self.heading.last() + dh);
            }
            _ => {
                // Climbs and drops at 2–4 m/s with 2 s transitions (peak
                // vertical acceleration ≤ 3.2 m/s², so thrust never nears zero).
                let target = (h + rng.range(-20.0, 20.0)).clamp(15.0, 80.0);
                self.t = self.climb_by(t, target - h, rng.range(2.0, 4.0), 2.0);
            }
        }
    }

    fn fixed_wing_segment(&mut self, rng: &mut Rng, h: f64, v: f64) {
        let t = self.t + rng.range(10.0, 40.0);
        if rng.uniform() < 0.7 {
            // Banked turn 20–35°: peak turn rate g·tan(bank)/v.
            let bank = rng.range(20.0f64, 35.0).to_radians();
            let w = G * libm::tan(bank) / v;
            let dh = rng.range(PI / 2.0, 1.5 * PI) * if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
            self.t = self.heading.to(t, PI * dh.abs() / (2.0 * w), self.heading.last() + dh);
        } else {
            let target = (h + rng.range(-30.0, 30.0)).clamp(40.0, 150.0);
            self.t = self.climb_by(t, target - h, rng.range(1.0, 3.0), 2.0);
        }
    }
}

// ---------------------------------------------------------------------------
// Sensors

/// Slow IMU error processes on a fixed 10 Hz grid (linearly interpolated),
/// so every IMU rate sees the same attitude error.
struct Slow {
    /// Attitude error (roll, pitch, yaw) rad at 10 Hz.
    att: Vec<[f64; 3]>,
}

const SLOW_DT: f64 = 0.1;

impl Slow {
    fn new(f: &Flight) -> Slow {
        let mut rng = Rng::new(f.seed ^ SALT_SLOW);
        let d = &f.imu;
        let tilt0 = [d.tilt_sigma_deg.to_radians() * rng.normal(), d.tilt_sigma_deg.to_radians() * rng.normal(), d.heading_sigma_deg.to_radians() * rng.normal()];
        let tau = rng.range(20.0, 60.0);
        let mut gm = [GaussMarkov::new(d.wander_sigma_deg.to_radians(), tau, &mut rng), GaussMarkov::new(d.wander_sigma_deg.to_radians(), tau, &mut rng)];
        let n = libm::ceil(f.path.duration / SLOW_DT) as usize + 2;
        let att = (0..n)
            .map(|_| {
                let e1 = gm[0].step(SLOW_DT, &mut rng);
                let e2 = gm[1].step(SLOW_DT, &mut rng);
                [tilt0[0] + e1, tilt0[1] + e2, tilt0[2]]
            })
            .collect();
        Slow { att }
    }
    fn att_error(&self, t: f64) -> [f64; 3] {
        let x = (t / SLOW_DT).max(0.0);
        let k = libm::floor(x) as usize;
        let w = x - k as f64;
        match (self.att.get(k), self.att.get(k + 1)) {
            (Some(a), Some(b)) => [a[0] + w * (b[0] - a[0]), a[1] + w * (b[1] - a[1]), a[2] + w * (b[2] - a[2])],
            (Some(a), None) => *a,
            _ => [0.0; 3],
        }
    }
}

fn imu_rows(f: &Flight, path: &Path) -> Vec<Sample> {
    let d = &f.imu;
    let mut rng = Rng::new(f.seed ^ SALT_IMU);
    let slow = Slow::new(f);
    // Vibration: blade-pass tone and its harmonic with per-axis phases.
    let mut vib_rng = Rng::new(f.seed ^ SALT_IMU ^ 0x5151);
    let phases: Vec<f64> = (0..6).map(|_| vib_rng.range(0.0, 2.0 * PI)).collect();
    let detune = vib_rng.range(1.9, 2.1);
    let bias = Vector3::new(d.accel_bias[0], d.accel_bias[1], d.accel_bias[2]);
    let sigma_a = d.accel_density * libm::sqrt(0.5 * d.rate);
    let sigma_g = d.gyro_density * libm::sqrt(0.5 * d.rate);
    let n = libm::floor(f.path.duration * d.rate) as usize;
    let mut out = Vec::with_capacity(n);
    for j in 0..n {
        let t = j as f64 / d.rate;
        let q = path.attitude(t);
        let q_next = path.attitude(t + FD);
        let w = (q.inverse() * q_next).scaled_axis() / FD;
        let fned = path.acceleration(t) - Vector3::new(0.0, 0.0, G);
        let mut fb = q.inverse_transform_vector(&fned) + bias;
        // Throttle: idle on the ground (armed), full in flight.
        let thr = 0.3 + 0.7 * path.airborne(t);
        let amp = d.vibration * thr * core::f64::consts::SQRT_2 * 0.8;
        let mut vib = [0.0; 3];
        for (i, v) in vib.iter_mut().enumerate() {
            let ax = if i == 2 { 1.5 } else { 1.0 };
            let w1 = 2.0 * PI * d.vibration_hz * t;
            *v = ax * amp * (libm::sin(w1 + phases[i]) + 0.5 * libm::sin(detune * w1 + phases[i + 3]));
        }
        for ft in f.faults.iter().filter(|ft| ft.kind == FaultKind::AccelBias && ft.active(t)) {
            let dir = match ft.axis {
                Axis::Horizontal => Vector3::new(libm::cos(ft.direction), libm::sin(ft.direction), 0.0),
                Axis::Vertical => Vector3::new(0.0, 0.0, ft.direction.signum()),
            };
            fb += dir * ft.magnitude;
        }
        let broad = 0.3 * d.vibration * thr;
        let e = slow.att_error(t);
        let qm = q * UnitQuaternion::from_scaled_axis(Vector3::new(e[0], e[1], e[2]));
        let mut s = Sample::at(f.log_time(t));
        s.ax = fb[0] + vib[0] + (sigma_a + broad) * rng.normal();
        s.ay = fb[1] + vib[1] + (sigma_a + broad) * rng.normal();
        s.az = fb[2] + vib[2] + (sigma_a + 1.5 * broad) * rng.normal();
        let gv = 0.01 * d.vibration * thr;
        s.gx = w[0] + (sigma_g + gv) * rng.normal();
        s.gy = w[1] + (sigma_g + gv) * rng.normal();
        s.gz = w[2] + (sigma_g + gv) * rng.normal();
        let c = qm.into_inner();
        s.qw = c.w;
        s.qx = c.i;
        s.qy = c.j;
        s.qz = c.k;
        out.push(s);
    }
    out
}

/// GPS records (one per epoch not dropped), labelled.
fn gps_rows(f: &Flight, path: &Path) -> Vec<Sample> {
    let d = &f.gps;
    let mut rng = Rng::new(f.seed ^ SALT_GPS);
    let anchor = Anchor::at(ORIGIN.0, ORIGIN.1, ORIGIN.2);
    let gm_h = d.sigma_h * libm::sqrt(d.gm_share);
    let gm_v = d.sigma_v * libm::sqrt(d.gm_share);
    let wh = d.sigma_h * libm::sqrt(1.0 - d.gm_share);
    let wv = d.sigma_v * libm::sqrt(1.0 - d.gm_share);
    let mut gm = [GaussMarkov::new(gm_h, d.tau, &mut rng), GaussMarkov::new(gm_h, d.tau, &mut rng), GaussMarkov::new(gm_v, d.tau, &mut rng)];
    let dt = 1.0 / d.rate;
    let mut sats = d.sats;
    // Per fault: the onset's (position, velocity, eph, sats).
    type Held = Option<(Vector3<f64>, Vector3<f64>, f64, f64)>;
    let mut frozen: Vec<Held> = vec![None; f.faults.len()];
    let mut walk = Vector3::zeros();
    let n = libm::floor((f.path.duration - d.phase) * d.rate) as usize;
    let mut out = Vec::with_capacity(n);
    for k in 0..n {
        let t = d.phase + k as f64 * dt;
        // Every random draw happens whatever the epoch's fate, so a drop
        // or a fault never shifts the noise of later epochs.
        let err = Vector3::new(gm[0].step(dt, &mut rng) + wh * rng.normal(), gm[1].step(dt, &mut rng) + wh * rng.normal(), gm[2].step(dt, &mut rng) + wv * rng.normal());
        let vnoise = Vector3::new(d.vel_sigma_h * rng.normal(), d.vel_sigma_h * rng.normal(), d.vel_sigma_v * rng.normal());
        let u_sats = rng.uniform();
        let u_drop = rng.uniform();
        let deg_noise = Vector3::new(rng.normal(), rng.normal(), rng.normal());
        if u_sats < 0.02 * dt {
            sats = (sats + if rng.uniform() < 0.5 { -1.0 } else { 1.0 }).clamp(d.sats - 3.0, d.sats + 3.0).max(5.0);
        }
        let truth_p = path.position(t);
        let truth_v = path.velocity(t);
        let mut pm = truth_p + err;
        let mut vm = truth_v + vnoise;
        let sat_factor = libm::sqrt(d.sats / sats);
        let mut eph = d.eph_scale * d.sigma_h * sat_factor;
        let mut epv = d.eph_scale * d.sigma_v * sat_factor;
        let mut sacc = d.eph_scale * d.vel_sigma_h * sat_factor;
        let mut nsat = sats;
        let mut fix = 3.0;
        let mut any_degraded = false;
        for (i, ft) in f.faults.iter().enumerate() {
            if !ft.active(t) {
                continue;
            }
            let dir = ft.ned_dir();
            let x = t - ft.start;
            match ft.kind {
                FaultKind::Step => pm += dir * ft.magnitude,
                FaultKind::Ramp => pm += dir * (ft.magnitude * x),
                FaultKind::DragOff => {
                    // Velocity offset builds up over `onset` s; position is its integral.
                    let on = ft.onset.max(1e-3);
                    let xi = (x / on).min(1.0);
                    let area = if x < on { on * (0.5 * xi - libm::sin(PI * xi) / (2.0 * PI)) } else { 0.5 * on + (x - on) };
                    pm += dir * (ft.magnitude * area);
                    vm += dir * (ft.magnitude * smooth(x, 0.0, on));
                }
                FaultKind::Frozen => {
                    let fz = frozen.get_mut(i).map(|z| *z.get_or_insert((pm, vm, eph, nsat)));
                    if let Some((p0, v0, e0, n0)) = fz {
                        pm = p0;
                        vm = v0;
                        sacc *= e0 / eph;
                        eph = e0;
                        epv = e0 * d.sigma_v / d.sigma_h;
                        nsat = n0;
                    }
                }
                FaultKind::Outage => fix = 0.0,
                FaultKind::Degraded => {
                    any_degraded = true;
                    walk += Vector3::new(deg_noise[0], deg_noise[1], 0.5 * deg_noise[2]) * (0.8 * libm::sqrt(dt));
                    let off = dir * ft.magnitude + Vector3::new(0.0, 0.0, 0.5 * ft.magnitude * libm::cos(ft.direction));
                    pm = truth_p + off + walk + err * 2.0;
                    vm = truth_v + vnoise * 5.0 + Vector3::new(0.3 * libm::cos(ft.direction), 0.3 * libm::sin(ft.direction), 0.0);
                    nsat = 4.0 + libm::floor(2.0 * u_sats);
                    sacc *= 5.0 * (5.0 + 5.0 * u_sats) / eph;
                    eph = 5.0 + 5.0 * u_sats;
                    epv = 1.6 * eph;
                    fix = if u_sats < 0.3 { 2.0 } else { 3.0 };
                }
                _ => {}
            }
        }
        if !any_degraded {
            walk = Vector3::zeros();
        }
        let in_gap = d.gaps.iter().any(|[a, b]| t >= *a && t < *b);
        if in_gap || u_drop < d.drop_prob {
            continue;
        }
        let mut s = Sample::at(f.log_time(t));
        s.fix = fix;
        s.gps_time = f.gps_time(t);
        if fix >= 2.0 {
            let (lat, lon, alt) = anchor.ned_to_lla(&pm).unwrap_or((f64::NAN, f64::NAN, f64::NAN));
            s.lat = lat;
            s.lon = lon;
            s.alt = alt;
            s.vn = vm[0];
            s.ve = vm[1];
            s.vd = vm[2];
            s.sats = nsat;
            s.eph = eph;
            s.epv = epv;
            if d.reports_sacc {
                s.sacc = sacc;
            }
        } else {
            s.sats = libm::floor(4.0 * u_sats);
        }
        s.label = if f.faulty_at(t) { 1.0 } else { 0.0 };
        out.push(s);
    }
    out
}

fn baro_rows(f: &Flight, path: &Path) -> Vec<Sample> {
    let d = &f.baro;
    let mut rng = Rng::new(f.seed ^ SALT_BARO);
    let mut gm = GaussMarkov::new(d.gm_sigma, d.gm_tau, &mut rng);
    let dt = 1.0 / d.rate;
    let mut hold: Vec<Option<f64>> = vec![None; f.faults.len()];
    let n = libm::floor((f.path.duration - d.phase) * d.rate) as usize;
    let mut out = Vec::with_capacity(n);
    for k in 0..n {
        let t = d.phase + k as f64 * dt;
        let h = path.height(t);
        let va = path.air_velocity(t);
        let climb = -path.velocity(t)[2];
        // Ground effect: motors are armed for the whole log.
        let ge = if h < d.ground_height { d.ground_effect * (1.0 - h / d.ground_height) } else { 0.0 };
        let mut b = ORIGIN.2 + h + d.offset + gm.step(dt, &mut rng) + d.white * rng.normal() + d.k_dynamic * va.norm_squared() + d.k_climb * climb + ge;
        for (i, ft) in f.faults.iter().enumerate() {
            if !ft.active(t) {
                continue;
            }
            match ft.kind {
                FaultKind::BaroStep => b += ft.direction.signum() * ft.magnitude,
                FaultKind::BaroDrift => b += ft.direction.signum() * ft.magnitude * (t - ft.start),
                FaultKind::BaroStuck => {
                    if let Some(slot) = hold.get_mut(i) {
                        b = *slot.get_or_insert(b);
                    }
                }
                _ => {}
            }
        }
        let mut s = Sample::at(f.log_time(t));
        s.baro = b;
        out.push(s);
    }
    out
}

/// Simulate a flight: IMU, GPS and baro records merged in time order (each
/// sensor on its own rows, as a logger writes them), `t` on the boot clock.
pub fn simulate(f: &Flight) -> Vec<Sample> {
    let path = Path::build(f);
    let imu = imu_rows(f, &path);
    let gps = gps_rows(f, &path);
    let baro = baro_rows(f, &path);
    merge3(imu, gps, baro)
}

/// Merge three time-sorted row lists; ties keep IMU, then GPS, then baro.
fn merge3(a: Vec<Sample>, b: Vec<Sample>, c: Vec<Sample>) -> Vec<Sample> {
    let mut out = Vec::with_capacity(a.len() + b.len() + c.len());
    let (mut i, mut j, mut k) = (0, 0, 0);
    loop {
        let ta = a.get(i).map_or(f64::INFINITY, |s| s.t);
        let tb = b.get(j).map_or(f64::INFINITY, |s| s.t);
        let tc = c.get(k).map_or(f64::INFINITY, |s| s.t);
        if ta == f64::INFINITY && tb == f64::INFINITY && tc == f64::INFINITY {
            break;
        }
        let next = if ta <= tb && ta <= tc {
            i += 1;
            a.get(i - 1)
        } else if tb <= tc {
            j += 1;
            b.get(j - 1)
        } else {
            k += 1;
            c.get(k - 1)
        };
        out.extend(next.copied());
    }
    out
}

/// Navlog CSV with the flight's draws as a `# battery:` JSON comment.
pub fn to_csv(f: &Flight, rows: &[Sample]) -> String {
    let mut out = String::with_capacity(rows.len() * 120);
    out.push_str(&format!("# navguard battery flight {} #{} (seed {})\n", f.split.name(), f.index, f.seed));
    if let Ok(j) = serde_json::to_string(f) {
        out.push_str("# battery: ");
        out.push_str(&j);
        out.push('\n');
    }
    crate::sim::write_rows(&mut out, rows);
    out
}

// ---------------------------------------------------------------------------
// Harness

/// One evaluated GPS epoch (a row with a `label`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Epoch {
    /// Log time, s.
    pub t: f64,
    /// Truth: 1 inside a fault's `[start, end)`, else 0.
    pub label: f64,
    /// Detector status: 0 normal, 1 fault.
    pub status: u8,
    /// The whole-flight reconciled verdict ([`crate::audit::RetroSpans`]):
    /// `status`, or 1 inside a span the detector dated once the fault
    /// ended.
    pub reconciled: u8,
}

/// How the detector did on one fault interval (an "event").
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct EventResult {
    /// The injected fault.
    pub fault: Fault,
    /// GPS epochs inside the fault, and how many were flagged.
    pub epochs: u64,
    /// GPS epochs inside the fault that were flagged.
    pub flagged: u64,
    /// flagged / epochs (0 when the fault has no epoch).
    pub share: f64,
    /// True time from fault start to the first flagged epoch inside it, s (NaN if none).
    pub delay: f64,
    /// Flagged time in the 20 s (true) after the fault end, s (flagged epochs / GPS rate).
    pub after_flagged_s: f64,
    /// Whether a new flagged run starts in those 20 s (a 0 → 1 edge).
    pub after_new_interval: bool,
}

impl EventResult {
    /// Whether at least one epoch inside the fault was flagged.
    pub fn detected(&self) -> bool {
        self.flagged > 0
    }
}

/// One flight through the detector.
#[derive(Clone, Debug, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct FlightResult {
    /// The flight's draws.
    pub flight: Flight,
    /// Every evaluated GPS epoch, in log order.
    pub epochs: Vec<Epoch>,
    /// One per fault, in the flight's fault order.
    pub events: Vec<EventResult>,
    /// Rows pushed (all sensors).
    pub rows: u64,
}

impl FlightResult {
    /// Whether the flight has no fault (counts in the clean-flight figures).
    pub fn is_clean(&self) -> bool {
        self.flight.faults.is_empty()
    }
    /// Share of GPS epochs flagged, %.
    pub fn flagged_pct(&self) -> f64 {
        let n = self.epochs.len().max(1) as f64;
        100.0 * self.epochs.iter().filter(|e| e.status != 0).count() as f64 / n
    }
    /// The same flight scored on its reconciled verdicts (what a whole-log
    /// audit reports) instead of the causal ones.
    pub fn reconciled(&self) -> FlightResult {
        let epochs: Vec<Epoch> = self.epochs.iter().map(|e| Epoch { status: e.reconciled, ..*e }).collect();
        let f = &self.flight;
        let events = f.faults.iter().map(|ft| event_result(f, ft, &epochs)).collect();
        FlightResult { flight: f.clone(), epochs, events, rows: self.rows }
    }
}

/// Length of the post-fault window watched for a new interval, true s.
pub const AFTER_WINDOW: f64 = 20.0;

/// Run `cfg`'s detector over a flight's rows.
pub fn run_rows(f: &Flight, rows: &[Sample], cfg: &Config) -> Result<FlightResult, String> {
    let mut det = Detector::new(cfg.clone())?;
    let mut epochs: Vec<Epoch> = Vec::with_capacity(rows.len() / 10);
    let mut spans = RetroSpans::default();
    for s in rows {
        let o = det.push(s).map_err(|e| format!("flight {} ({}): {e}", f.index, f.seed))?;
        spans.note(&det, s.t);
        if !s.label.is_nan() {
            epochs.push(Epoch { t: s.t, label: s.label, status: o.status, reconciled: o.status });
        }
    }
    for e in &mut epochs {
        e.reconciled |= spans.covers(e.t) as u8;
    }
    let events = f.faults.iter().map(|ft| event_result(f, ft, &epochs)).collect();
    Ok(FlightResult { flight: f.clone(), epochs, events, rows: rows.len() as u64 })
}

/// Simulate and run one flight.
pub fn run(f: &Flight, cfg: &Config) -> Result<FlightResult, String> {
    run_rows(f, &simulate(f), cfg)
}

fn event_result(f: &Flight, ft: &Fault, epochs: &[Epoch]) -> EventResult {
    let inside: Vec<&Epoch> = epochs.iter().filter(|e| e.t >= ft.start_log && e.t < ft.end_log).collect();
    let flagged = inside.iter().filter(|e| e.status != 0).count() as u64;
    let delay = inside.iter().find(|e| e.status != 0).map_or(f64::NAN, |e| (e.t - ft.start_log) / f.clock.rate);
    let win_end = ft.end_log + AFTER_WINDOW * f.clock.rate;
    let mut prev = epochs.iter().rev().find(|e| e.t < ft.end_log).map_or(0, |e| e.status);
    let mut after = 0u64;
    let mut new_interval = false;
    for e in epochs.iter().filter(|e| e.t >= ft.end_log && e.t < win_end) {
        if e.status != 0 {
            after += 1;
            new_interval |= prev == 0;
        }
        prev = e.status;
    }
    EventResult {
        fault: *ft,
        epochs: inside.len() as u64,
        flagged,
        share: if inside.is_empty() { 0.0 } else { flagged as f64 / inside.len() as f64 },
        delay,
        after_flagged_s: after as f64 / f.gps.rate,
        after_new_interval: new_interval,
    }
}

/// One row of a condition table.
#[derive(Clone, Debug, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct GroupRow {
    /// Condition value the row pools (e.g. `10 Hz`, `ramp-h`).
    pub key: String,
    /// Flights in the group.
    pub flights: u64,
    /// Pooled over the GPS epochs of the group's flights.
    pub metrics: Metrics,
    /// Events counted (those `keep` accepts).
    pub events: u64,
    /// Of those, events with at least one flagged epoch.
    pub events_flagged: u64,
    /// Mean over the group's events of the share of the event flagged.
    pub mean_event_share: f64,
    /// Median delay over the detected events, true s (NaN if none).
    pub median_delay: f64,
    /// Fault-free flights in the group.
    pub clean_flights: u64,
    /// GPS epochs of those clean flights.
    pub clean_epochs: u64,
    /// Of those, epochs flagged (false alarms).
    pub clean_flagged: u64,
}

impl GroupRow {
    /// Clean flights' share of GPS epochs flagged, %.
    pub fn clean_pct(&self) -> f64 {
        if self.clean_epochs == 0 {
            f64::NAN
        } else {
            100.0 * self.clean_flagged as f64 / self.clean_epochs as f64
        }
    }
}

/// Pool flights into one row; only events for which `keep` holds count in
/// the event columns.
pub fn group_row(key: &str, flights: &[&FlightResult], keep: &dyn Fn(&EventResult) -> bool) -> GroupRow {
    let mut acc = Accumulator::default();
    let mut row = GroupRow {
        key: key.into(),
        flights: flights.len() as u64,
        metrics: Metrics::default(),
        events: 0,
        events_flagged: 0,
        mean_event_share: f64::NAN,
        median_delay: f64::NAN,
        clean_flights: 0,
        clean_epochs: 0,
        clean_flagged: 0,
    };
    let mut shares = 0.0;
    let mut delays = vec![];
    for r in flights {
        for e in &r.epochs {
            acc.push(e.t, e.label, e.status);
        }
        for ev in r.events.iter().filter(|ev| keep(ev)) {
            row.events += 1;
            shares += ev.share;
            if ev.detected() {
                row.events_flagged += 1;
                delays.push(ev.delay);
            }
        }
        if r.is_clean() {
            row.clean_flights += 1;
            row.clean_epochs += r.epochs.len() as u64;
            row.clean_flagged += r.epochs.iter().filter(|e| e.status != 0).count() as u64;
        }
    }
    row.metrics = acc.metrics();
    if row.events > 0 {
        row.mean_event_share = shares / row.events as f64;
    }
    row.median_delay = median(&mut delays);
    row
}

fn median(xs: &mut [f64]) -> f64 {
    xs.sort_by(|a, b| a.total_cmp(b));
    match xs.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => xs[n / 2],
        n => 0.5 * (xs[n / 2 - 1] + xs[n / 2]),
    }
}

/// A table cut by one condition.
#[derive(Clone, Debug, Serialize)]
pub struct Table {
    /// Condition the table is cut by (e.g. `GPS rate`).
    pub name: &'static str,
    /// One row per condition value; fault tables end with a `clean (no fault)` row.
    pub rows: Vec<GroupRow>,
}

fn bucket(x: f64, edges: &[(f64, &'static str)], last: &'static str) -> &'static str {
    edges.iter().find(|(e, _)| x < *e).map_or(last, |(_, n)| n)
}

/// Fault kind as reported: vertical variants get a `-v` suffix.
pub fn kind_key(ft: &Fault) -> String {
    match (ft.kind.has_axis(), ft.axis) {
        (true, Axis::Vertical) => format!("{}-v", ft.kind.name()),
        (true, Axis::Horizontal) => format!("{}-h", ft.kind.name()),
        _ => ft.kind.name().into(),
    }
}

/// Fault-duration bucket of the duration table (`3-10 s` … `60-120 s`).
pub fn duration_key(ft: &Fault) -> &'static str {
    bucket(ft.duration(), &[(10.0, "3-10 s"), (30.0, "10-30 s"), (60.0, "30-60 s")], "60-120 s")
}

fn start_key(ft: &Fault) -> &'static str {
    if ft.start < 20.0 {
        "first 20 s"
    } else {
        "later"
    }
}

/// Flight-level condition keys: (table name, key).
fn flight_keys(f: &Flight) -> Vec<(&'static str, String)> {
    let fam = match f.gps.family {
        NoiseFamily::White => "white",
        NoiseFamily::GaussMarkov => "gauss-markov",
        NoiseFamily::Mixed => "mixed (eval only)",
    };
    let grade = match f.imu.grade {
        ImuGrade::Consumer => "consumer",
        ImuGrade::Industrial => "industrial",
        ImuGrade::Tactical => "tactical",
    };
    let rate = if f.gps.rate >= 20.0 { "20 Hz (eval only)".to_string() } else { format!("{} Hz", f.gps.rate) };
    let drops = if f.gps.gaps.is_empty() && f.gps.drop_prob == 0.0 { "none" } else { "gaps/drops" };
    vec![
        ("GPS noise family", fam.into()),
        ("GPS σ horizontal", bucket(f.gps.sigma_h, &[(0.7, "0.3-0.7 m"), (1.5, "0.7-1.5 m")], "1.5-3 m").into()),
        ("GPS rate", rate),
        ("GPS logger drops", drops.into()),
        ("IMU rate", format!("{} Hz", f.imu.rate)),
        ("IMU grade", grade.into()),
        ("Vibration RMS", bucket(f.imu.vibration, &[(1.0, "< 1 m/s²"), (3.0, "1-3 m/s²")], "3-6 m/s²").into()),
        ("Trajectory", f.path.kind.name().into()),
        ("Boot clock", if f.clock.rate == 1.0 { "true rate".into() } else { bucket(f.clock.rate, &[(0.96, "0.92-0.96x")], "0.96-1x").into() }),
    ]
}

/// Sort keys by their leading number when they have one ("2 Hz" < "10 Hz"), else by text.
fn sort_keys(keys: &mut Vec<String>) {
    let lead = |k: &str| k.split(|c: char| !(c.is_ascii_digit() || c == '.')).next().and_then(|x| x.parse::<f64>().ok());
    keys.sort_by(|a, b| match (lead(a), lead(b)) {
        (Some(x), Some(y)) => x.total_cmp(&y).then_with(|| a.cmp(b)),
        _ => a.cmp(b),
    });
    keys.dedup();
}

/// Every condition table over the results.
pub fn tables(results: &[FlightResult]) -> Vec<Table> {
    let mut out: Vec<Table> = vec![];
    let all: Vec<&FlightResult> = results.iter().collect();
    let Some(first) = results.first() else { return out };
    for (ti, (name, _)) in flight_keys(&first.flight).into_iter().enumerate() {
        let mut keys: Vec<String> = all.iter().filter_map(|r| flight_keys(&r.flight).into_iter().nth(ti).map(|k| k.1)).collect();
        sort_keys(&mut keys);
        let rows = keys
            .iter()
            .map(|k| {
                let fl: Vec<&FlightResult> = all.iter().copied().filter(|r| flight_keys(&r.flight).into_iter().nth(ti).is_some_and(|x| &x.1 == k)).collect();
                group_row(k, &fl, &|_| true)
            })
            .collect();
        out.push(Table { name, rows });
    }
    type EvKey = fn(&Fault) -> String;
    let ev_dims: [(&'static str, EvKey); 3] =
        [("Fault kind", kind_key), ("Fault duration", |f| duration_key(f).into()), ("Fault start", |f| start_key(f).into())];
    for (name, key) in ev_dims {
        let mut keys: Vec<String> = all.iter().flat_map(|r| r.flight.faults.iter().map(key)).collect();
        sort_keys(&mut keys);
        let mut rows: Vec<GroupRow> = keys
            .iter()
            .map(|k| {
                let fl: Vec<&FlightResult> = all.iter().copied().filter(|r| r.flight.faults.iter().any(|f| &key(f) == k)).collect();
                group_row(k, &fl, &|ev| &key(&ev.fault) == k)
            })
            .collect();
        let clean: Vec<&FlightResult> = all.iter().copied().filter(|r| r.is_clean()).collect();
        if !clean.is_empty() {
            rows.push(group_row("clean (no fault)", &clean, &|_| true));
        }
        out.push(Table { name, rows });
    }
    out
}

// ---------------------------------------------------------------------------
// The specific checks

/// A specific check of issue 14's acceptance list.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct CheckSpec {
    /// Label printed in the checks table.
    pub name: &'static str,
    /// Fault kind injected.
    pub kind: FaultKind,
    /// `None`: alternate horizontal and vertical by instance.
    pub axis: Option<Axis>,
    /// Fault magnitude (units as in [`Fault`]).
    pub magnitude: f64,
    /// Fault length, true s.
    pub length: f64,
    /// Needs a moving vehicle (frozen GPS during hover is invisible).
    pub moving: bool,
    /// The pass criterion as printed (applied by [`CheckSpec::passes`]).
    pub criterion: &'static str,
}

/// The checks, in the order.
pub const CHECKS: [CheckSpec; 6] = [
    CheckSpec { name: "step 10 m, 60 s", kind: FaultKind::Step, axis: Some(Axis::Horizontal), magnitude: 10.0, length: 60.0, moving: false, criterion: "share >= 90% and no new run, <= 2 s flagged in 20 s after end" },
    CheckSpec { name: "frozen GPS, 60 s", kind: FaultKind::Frozen, axis: Some(Axis::Horizontal), magnitude: 0.0, length: 60.0, moving: true, criterion: "share >= 90% and no new run, <= 2 s flagged in 20 s after end" },
    CheckSpec { name: "ramp 0.3 m/s (position only), 60 s", kind: FaultKind::Ramp, axis: Some(Axis::Horizontal), magnitude: 0.3, length: 60.0, moving: false, criterion: "first flag <= 10 s and share >= 80%" },
    CheckSpec { name: "drag-off 0.5 m/s (h and v), 80 s", kind: FaultKind::DragOff, axis: None, magnitude: 0.5, length: 80.0, moving: false, criterion: "first flag <= 15 s" },
    CheckSpec { name: "step 5 m horizontal, 30 s", kind: FaultKind::Step, axis: Some(Axis::Horizontal), magnitude: 5.0, length: 30.0, moving: false, criterion: "flagged" },
    CheckSpec { name: "step 6 m vertical, 30 s", kind: FaultKind::Step, axis: Some(Axis::Vertical), magnitude: 6.0, length: 30.0, moving: false, criterion: "flagged" },
];

impl CheckSpec {
    /// Instance `i` of this check (check number `c`): an eval-split flight
    /// (index `CHECK_BASE + 1000 c + i`) with this one fault 60–90 s in.
    pub fn flight(&self, c: usize, i: u64) -> Flight {
        let index = CHECK_BASE + 1000 * c as u64 + i;
        let mut rng = Rng::new(Split::Eval.seed(index) ^ SALT_DRAW ^ 0xC4);
        let start = rng.range(60.0, 90.0);
        let path = if self.moving { Some(pick(&mut rng, &[PathKind::Survey, PathKind::Aggressive, PathKind::FixedWing])) } else { None };
        let ov = Overrides { path, min_duration: Some(start + self.length + 60.0) };
        let mut f = Flight::conditions(Split::Eval, index, ov);
        let axis = self.axis.unwrap_or(if i.is_multiple_of(2) { Axis::Horizontal } else { Axis::Vertical });
        let direction = match axis {
            Axis::Horizontal => rng.range(0.0, 2.0 * PI),
            Axis::Vertical => {
                if i % 4 < 2 {
                    1.0
                } else {
                    -1.0
                }
            }
        };
        f.add_fault(self.kind, axis, self.magnitude, direction, start, self.length);
        f
    }

    /// Whether an event meets the criterion.
    pub fn passes(&self, ev: &EventResult) -> bool {
        let after_ok = !ev.after_new_interval && ev.after_flagged_s <= 2.0;
        match (self.kind, self.length) {
            (FaultKind::Step | FaultKind::Frozen, l) if l >= 60.0 => ev.share >= 0.9 && after_ok,
            (FaultKind::Ramp, _) => ev.delay <= 10.0 && ev.share >= 0.8,
            (FaultKind::DragOff, _) => ev.delay <= 15.0,
            _ => ev.detected(),
        }
    }
}

/// The flights of the IMU-rate invariance check: eval flight
/// `CHECK_BASE + 10_000 + i` at each of [`IMU_RATES`].
pub const IMU_RATES: [f64; 4] = [50.0, 100.0, 200.0, 400.0];

/// Instance `i` of the IMU-rate check: the same eval flight at each of [`IMU_RATES`].
pub fn imu_rate_flights(i: u64) -> Vec<Flight> {
    let base = Flight::draw(Split::Eval, CHECK_BASE + 10_000 + i);
    IMU_RATES.iter().map(|r| base.with_imu_rate(*r)).collect()
}

/// Flagged-share spread (max − min, percentage points) over variants.
pub fn spread(pcts: &[f64]) -> f64 {
    let hi = pcts.iter().cloned().fold(f64::MIN, f64::max);
    let lo = pcts.iter().cloned().fold(f64::MAX, f64::min);
    if pcts.is_empty() {
        0.0
    } else {
        hi - lo
    }
}
