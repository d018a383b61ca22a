//! Seeded, deterministic flight and sensor simulator (Sun et al. 2017 §3).
//!
//! A multirotor flies a trajectory defined by smooth speed, heading and climb
//! profiles. The accelerometer sees pure thrust (`f_body = (0, 0, −‖a − g‖)`)
//! and the attitude tilts the thrust along the needed acceleration, so IMU,
//! attitude and GPS are mutually consistent. Sensor errors:
//! - GPS position: first-order Gauss–Markov (σ 0.8 m horizontal, 1.5 m
//!   vertical, τ 120 s) plus white noise (0.08 m / 0.15 m); velocity white
//!   noise 0.05 m/s horizontal, 0.08 m/s vertical;
//! - accelerometer: constant bias (±0.05 m/s² per axis) plus white noise
//!   0.05 m/s²; attitude: a constant tilt error (σ 0.2°) plus Gauss–Markov
//!   wander (σ 0.15°, τ 30 s);
//! - barometer: datum offset, Gauss–Markov drift (σ 0.3 m, τ 60 s), white
//!   noise 0.1 m.
//!
//! Rows: one per IMU sample; GPS columns on GPS ticks, baro on its own ticks
//! (offset from GPS so the streams interleave). `label` is written on GPS
//! ticks only: those are the evaluated epochs (2,500 for the paper flight).

use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

use crate::frames::Anchor;
use crate::sample::Sample;

pub use crate::rng::Rng;

/// Trajectory shapes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Trajectory {
    /// The paper's 250 s flight: climb, level flight with turns, descent.
    Paper,
    /// Fault-free stress: hard turns, sprints, fast climbs and drops.
    Aggressive,
    /// Lawn-mower survey legs with 180° turns at 6 m/s.
    Survey,
}

/// GPS outage behaviour.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum OutageMode {
    /// No GPS rows at all during the outage.
    Silent,
    /// The receiver keeps reporting a fix from a few satellites: wrong,
    /// wandering positions.
    Degraded,
}

/// Injectable fault kinds (item 7 of the core issue).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FaultKind {
    /// GPS position step, magnitude in m.
    Step,
    /// GPS position ramp, magnitude in m/s.
    Ramp,
    /// GPS noise burst, magnitude = added σ in m.
    Noise,
    /// GPS output frozen (position and velocity) while moving.
    Frozen,
    /// GPS velocity reported as zero in flight (contextual fault).
    ZeroVelocity,
    /// Barometer stuck (collective fault; place it in a climb).
    BaroStuck,
    /// Accelerometer bias on body x and y, magnitude in m/s².
    AccelBias,
}

impl FaultKind {
    /// Every fault kind.
    pub const ALL: [FaultKind; 7] = [
        FaultKind::Step,
        FaultKind::Ramp,
        FaultKind::Noise,
        FaultKind::Frozen,
        FaultKind::ZeroVelocity,
        FaultKind::BaroStuck,
        FaultKind::AccelBias,
    ];

    /// The kind's name in presets and reports (kebab-case).
    pub fn name(self) -> &'static str {
        match self {
            FaultKind::Step => "step",
            FaultKind::Ramp => "ramp",
            FaultKind::Noise => "noise",
            FaultKind::Frozen => "frozen",
            FaultKind::ZeroVelocity => "zero-velocity",
            FaultKind::BaroStuck => "baro-stuck",
            FaultKind::AccelBias => "accel-bias",
        }
    }
}

/// One injected fault over `[start, end)` s.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Fault {
    /// What fails.
    pub kind: FaultKind,
    /// Onset, s.
    pub start: f64,
    /// End (exclusive), s.
    pub end: f64,
    /// Units per kind (see [`FaultKind`]); ignored for frozen / zero-velocity / baro-stuck.
    #[serde(default)]
    pub magnitude: f64,
}

/// A scenario: everything the simulator needs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "camelCase")]
pub struct Scenario {
    /// Scenario name (a preset's or free text).
    pub name: String,
    /// Seed of every random draw.
    pub seed: u64,
    /// Flight length, s.
    pub duration: f64,
    /// The flight's shape.
    pub trajectory: Trajectory,
    /// Rates, Hz. `imu_rate` 0 = GPS-only stream; `baro_rate` 0 = no baro.
    pub imu_rate: f64,
    /// GPS rate, Hz.
    pub gps_rate: f64,
    /// Barometer rate, Hz (0: no baro).
    pub baro_rate: f64,
    /// Write GPS velocity columns.
    pub gps_velocity: bool,
    /// Outage intervals `[start, end)` s (labelled fault) and their mode.
    pub outages: Vec<[f64; 2]>,
    /// How the receiver reports an outage.
    pub outage_mode: OutageMode,
    /// Injected sensor faults.
    pub faults: Vec<Fault>,
}

impl Scenario {
    /// The paper's 250 s scenario with outages at 30–40, 100–110, 220–230 s.
    pub fn paper(mode: OutageMode, seed: u64) -> Self {
        Scenario {
            name: match mode {
                OutageMode::Degraded => "paper".into(),
                OutageMode::Silent => "paper-silent".into(),
            },
            seed,
            duration: 250.0,
            trajectory: Trajectory::Paper,
            imu_rate: 50.0,
            gps_rate: 10.0,
            baro_rate: 10.0,
            gps_velocity: true,
            outages: vec![[30.0, 40.0], [100.0, 110.0], [220.0, 230.0]],
            outage_mode: mode,
            faults: vec![],
        }
    }

    /// A fault-free flight.
    pub fn clean(trajectory: Trajectory, seed: u64, duration: f64) -> Self {
        Scenario {
            name: format!("clean-{}", traj_name(trajectory)),
            seed,
            duration,
            trajectory,
            imu_rate: 50.0,
            gps_rate: 10.0,
            baro_rate: 10.0,
            gps_velocity: true,
            outages: vec![],
            outage_mode: OutageMode::Silent,
            faults: vec![],
        }
    }

    /// The paper flight with one fault of `kind` and `magnitude` over
    /// `[start, start + length)`. Baro-stuck is moved into the climb.
    pub fn with_fault(kind: FaultKind, magnitude: f64, start: f64, length: f64, seed: u64) -> Self {
        let mut s = Scenario::clean(Trajectory::Paper, seed, 250.0);
        let start = if kind == FaultKind::BaroStuck { start.clamp(5.0, 55.0 - length.min(50.0)) } else { start };
        s.name = format!("{}-{}", kind.name(), magnitude);
        s.faults.push(Fault { kind, start, end: start + length, magnitude });
        s
    }

    /// Built-in scenarios by name: paper, paper-silent, clean-aggressive,
    /// clean-survey, clean-paper, gps-only, or a fault kind name.
    pub fn preset(name: &str, seed: u64) -> Result<Self, String> {
        Ok(match name {
            "paper" => Scenario::paper(OutageMode::Degraded, seed),
            "paper-silent" => Scenario::paper(OutageMode::Silent, seed),
            "clean-aggressive" => Scenario::clean(Trajectory::Aggressive, seed, 300.0),
            "clean-survey" => Scenario::clean(Trajectory::Survey, seed, 300.0),
            "clean-paper" => Scenario::clean(Trajectory::Paper, seed, 250.0),
            "gps-only" => {
                let mut s = Scenario::paper(OutageMode::Degraded, seed);
                s.name = "gps-only".into();
                s.imu_rate = 0.0;
                s
            }
            other => {
                let kind = FaultKind::ALL
                    .iter()
                    .find(|k| k.name() == other)
                    .ok_or_else(|| format!("unknown scenario \"{other}\" (try: {})", preset_names().join(", ")))?;
                Scenario::with_fault(*kind, default_magnitude(*kind), 120.0, 15.0, seed)
            }
        })
    }

    /// Rates, duration and intervals in range; the error names the field.
    pub fn check(&self) -> Result<(), String> {
        let bad = |f: &str, v: f64| Err(format!("scenario.{f}: bad value {v}"));
        if !(self.duration.is_finite() && self.duration > 0.0 && self.duration <= 86_400.0) {
            return bad("duration", self.duration);
        }
        if !(self.gps_rate.is_finite() && self.gps_rate > 0.0 && self.gps_rate <= 100.0) {
            return bad("gpsRate", self.gps_rate);
        }
        if !(self.imu_rate.is_finite() && (self.imu_rate == 0.0 || (self.imu_rate >= self.gps_rate && self.imu_rate <= 1000.0))) {
            return bad("imuRate", self.imu_rate);
        }
        if !(self.baro_rate.is_finite() && self.baro_rate >= 0.0 && self.baro_rate <= 200.0) {
            return bad("baroRate", self.baro_rate);
        }
        for f in &self.faults {
            if !(f.start.is_finite() && f.end.is_finite() && f.end > f.start && f.magnitude.is_finite()) {
                return Err(format!("scenario.faults: bad interval or magnitude {:?}", f));
            }
        }
        Ok(())
    }
}

/// Names accepted by [`Scenario::preset`].
pub fn preset_names() -> Vec<&'static str> {
    let mut v = vec!["paper", "paper-silent", "clean-aggressive", "clean-survey", "clean-paper", "gps-only"];
    v.extend(FaultKind::ALL.iter().map(|k| k.name()));
    v
}

/// A typical magnitude per kind, mid-range of the list.
pub fn default_magnitude(kind: FaultKind) -> f64 {
    match kind {
        FaultKind::Step => 10.0,
        FaultKind::Ramp => 0.5,
        FaultKind::Noise => 5.0,
        FaultKind::AccelBias => 0.5,
        _ => 0.0,
    }
}

fn traj_name(t: Trajectory) -> &'static str {
    match t {
        Trajectory::Paper => "paper",
        Trajectory::Aggressive => "aggressive",
        Trajectory::Survey => "survey",
    }
}

/// Smooth step from 0 to 1 over [a, b] (half a cosine).
pub(crate) fn smooth(t: f64, a: f64, b: f64) -> f64 {
    if t <= a {
        0.0
    } else if t >= b {
        1.0
    } else {
        let x = (t - a) / (b - a);
        0.5 - 0.5 * libm::cos(core::f64::consts::PI * x)
    }
}

/// Trajectory as (horizontal speed m/s, heading rad, climb rate m/s) at t.
#[derive(Clone, Debug)]
struct Profile {
    kind: Trajectory,
    /// Random sinusoid components for the aggressive flight: (amp, freq, phase).
    speed_c: Vec<(f64, f64, f64)>,
    turn_c: Vec<(f64, f64, f64)>,
    climb_c: Vec<(f64, f64, f64)>,
}

impl Profile {
    fn new(kind: Trajectory, rng: &mut Rng) -> Self {
        let mut comp = |n: usize, amp: f64, fmin: f64, fmax: f64| -> Vec<(f64, f64, f64)> {
            (0..n).map(|_| (amp * rng.range(0.5, 1.0), rng.range(fmin, fmax), rng.range(0.0, 6.283))).collect()
        };
        Profile {
            kind,
            speed_c: comp(3, 3.5, 0.02, 0.12),
            turn_c: comp(3, 0.35, 0.02, 0.15),
            climb_c: comp(2, 1.6, 0.03, 0.15),
        }
    }

    /// (speed, heading, climb) at time t.
    fn at(&self, t: f64) -> (f64, f64, f64) {
        let sum = |c: &[(f64, f64, f64)], t: f64| -> f64 {
            c.iter().map(|(a, f, p)| a * libm::sin(2.0 * core::f64::consts::PI * f * t + p)).sum()
        };
        match self.kind {
            Trajectory::Paper => {
                let speed = 3.0 + 7.0 * smooth(t, 0.0, 20.0);
                // Two coordinated turns in level flight, one during descent.
                let heading = 0.5 * core::f64::consts::PI * smooth(t, 80.0, 95.0)
                    - 0.75 * core::f64::consts::PI * smooth(t, 140.0, 165.0)
                    + 0.5 * core::f64::consts::PI * smooth(t, 205.0, 215.0);
                let climb = 1.0 * (smooth(t, 0.0, 3.0) - smooth(t, 57.0, 60.0))
                    - 0.9 * (smooth(t, 195.0, 198.0) - smooth(t, 247.0, 250.0));
                (speed, heading, climb)
            }
            Trajectory::Aggressive => {
                let speed = (8.0 + sum(&self.speed_c, t)).max(0.5);
                // Heading is the integral of a turn rate; integrate the sinusoids analytically.
                let heading: f64 = self
                    .turn_c
                    .iter()
                    .map(|(a, f, p)| {
                        let w = 2.0 * core::f64::consts::PI * f;
                        a / w * (libm::cos(*p) - libm::cos(w * t + p))
                    })
                    .sum::<f64>()
                    * 2.5;
                let climb = sum(&self.climb_c, t) * smooth(t, 0.0, 5.0) + 1.5 * (1.0 - smooth(t, 0.0, 20.0));
                (speed, heading, climb)
            }
            Trajectory::Survey => {
                // 40 s legs, 10 s 180° turns, alternating direction.
                let period = 50.0;
                let k = libm::floor(t / period);
                let tin = t - k * period;
                let base = k * core::f64::consts::PI;
                let heading = base + core::f64::consts::PI * smooth(tin, 40.0, 50.0);
                let climb = 1.5 * (smooth(t, 0.0, 2.0) - smooth(t, 18.0, 20.0));
                (6.0, heading, climb)
            }
        }
    }

    fn velocity(&self, t: f64) -> Vector3<f64> {
        let (s, h, c) = self.at(t);
        Vector3::new(s * libm::cos(h), s * libm::sin(h), -c)
    }
}

/// Attitude whose body z axis is along minus the specific force, nose along `yaw`.
pub(crate) fn thrust_attitude(f_ned: &Vector3<f64>, yaw: f64) -> UnitQuaternion<f64> {
    let n = f_ned.norm().max(1e-6);
    let zb = -f_ned / n;
    let xc = Vector3::new(libm::cos(yaw), libm::sin(yaw), 0.0);
    let yb = zb.cross(&xc);
    let yb = if yb.norm() < 1e-9 { Vector3::new(0.0, 1.0, 0.0) } else { yb.normalize() };
    let xb = yb.cross(&zb);
    let m = Matrix3::from_columns(&[xb, yb, zb]);
    UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(m))
}

/// First-order Gauss–Markov process.
#[derive(Clone, Copy, Debug)]
pub(crate) struct GaussMarkov {
    x: f64,
    sigma: f64,
    tau: f64,
}

impl GaussMarkov {
    pub(crate) fn new(sigma: f64, tau: f64, rng: &mut Rng) -> Self {
        GaussMarkov { x: sigma * rng.normal(), sigma, tau }
    }
    pub(crate) fn step(&mut self, dt: f64, rng: &mut Rng) -> f64 {
        let phi = libm::exp(-dt / self.tau);
        self.x = phi * self.x + self.sigma * libm::sqrt(1.0 - phi * phi) * rng.normal();
        self.x
    }
}

/// Origin of the simulated flights (deg, deg, m AMSL): Nanjing, where the paper flew.
pub const ORIGIN: (f64, f64, f64) = (31.9400, 118.7900, 20.0);

fn in_any(t: f64, iv: &[[f64; 2]]) -> bool {
    iv.iter().any(|[a, b]| t >= *a && t < *b)
}

/// Simulate a scenario into navlog rows.
pub fn simulate(sc: &Scenario) -> Result<Vec<Sample>, String> {
    sc.check()?;
    let mut rng = Rng::new(sc.seed);
    let prof = Profile::new(sc.trajectory, &mut rng);
    let anchor = Anchor::at(ORIGIN.0, ORIGIN.1, ORIGIN.2);
    let g = Vector3::new(0.0, 0.0, crate::filter::GRAVITY);

    // Sensor error states.
    let mut gps_gm: [GaussMarkov; 3] = [
        GaussMarkov::new(0.8, 120.0, &mut rng),
        GaussMarkov::new(0.8, 120.0, &mut rng),
        GaussMarkov::new(1.5, 120.0, &mut rng),
    ];
    let acc_bias = Vector3::new(rng.range(-0.05, 0.05), rng.range(-0.05, 0.05), rng.range(-0.05, 0.05));
    let tilt0 = Vector3::new(0.2f64.to_radians() * rng.normal(), 0.2f64.to_radians() * rng.normal(), 0.5f64.to_radians() * rng.normal());
    let mut att_gm = [GaussMarkov::new(0.15f64.to_radians(), 30.0, &mut rng), GaussMarkov::new(0.15f64.to_radians(), 30.0, &mut rng)];
    let baro_offset = rng.range(-30.0, 30.0);
    let mut baro_gm = GaussMarkov::new(0.3, 60.0, &mut rng);
    // Per-outage degraded-fix errors: offset direction/magnitude.
    let deg: Vec<(Vector3<f64>, Vector3<f64>)> = sc
        .outages
        .iter()
        .map(|_| {
            let ang = rng.range(0.0, 6.283);
            let mag = rng.range(5.0, 12.0);
            let vz = rng.range(3.0, 8.0) * if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
            let vang = rng.range(0.0, 6.283);
            (Vector3::new(mag * libm::cos(ang), mag * libm::sin(ang), vz), Vector3::new(0.6 * libm::cos(vang), 0.6 * libm::sin(vang), 0.0))
        })
        .collect();
    let mut deg_walk = Vector3::zeros();
    let fault_dirs: Vec<f64> = sc.faults.iter().map(|_| rng.range(0.0, 6.283)).collect();

    let gps_only = sc.imu_rate == 0.0;
    let row_rate = if gps_only { sc.gps_rate } else { sc.imu_rate };
    let n_rows = libm::floor(sc.duration * row_rate + 1e-9) as usize;
    let gps_every = if gps_only { 1 } else { ((sc.imu_rate / sc.gps_rate).round() as usize).max(1) };
    let baro_every = if sc.baro_rate > 0.0 { ((row_rate / sc.baro_rate).round() as usize).max(1) } else { 0 };
    let baro_offset_rows = if baro_every > 2 { 2 } else { 0 };
    let dt_row = 1.0 / row_rate;

    // Fine integration of position (RK-like trapezoid on the analytic velocity).
    let sub = 10usize;
    let mut p = Vector3::new(0.0, 0.0, 0.0);
    let mut rows = Vec::with_capacity(n_rows);
    let mut frozen: Vec<Option<(f64, f64, f64, Vector3<f64>)>> = vec![None; sc.faults.len()];
    let mut baro_hold: Vec<Option<f64>> = vec![None; sc.faults.len()];
    let mut t_prev = 0.0;
    let h = 1e-3;
    for k in 0..n_rows {
        let t = k as f64 * dt_row;
        if k > 0 {
            let ds = (t - t_prev) / sub as f64;
            for j in 0..sub {
                let ta = t_prev + j as f64 * ds;
                p += (prof.velocity(ta) + prof.velocity(ta + ds)) * (0.5 * ds);
            }
        }
        t_prev = t;
        let v = prof.velocity(t);
        let a = (prof.velocity(t + h) - prof.velocity((t - h).max(0.0))) / if t >= h { 2.0 * h } else { h };
        let f_ned = a - g;
        let (_, yaw, _) = prof.at(t);
        let q = thrust_attitude(&f_ned, yaw);
        let mut s = Sample::at((t * 1e6).round() / 1e6);

        // GPS error processes advance every GPS tick.
        let gps_tick = k % gps_every == 0;
        if !gps_only {
            let f_body = q.inverse_transform_vector(&f_ned);
            let f_next = (prof.velocity(t + 2.0 * h) - prof.velocity(t)) / (2.0 * h) - g;
            let q_next = thrust_attitude(&f_next, prof.at(t + h).1);
            let w = (q.inverse() * q_next).scaled_axis() / h;
            let mut fb = f_body + acc_bias + Vector3::new(rng.normal(), rng.normal(), rng.normal()) * 0.05;
            for (i, ft) in sc.faults.iter().enumerate() {
                if ft.kind == FaultKind::AccelBias && t >= ft.start && t < ft.end {
                    let d = fault_dirs[i];
                    fb += Vector3::new(libm::cos(d), libm::sin(d), 0.0) * ft.magnitude;
                }
            }
            let e1 = att_gm[0].step(dt_row, &mut rng);
            let e2 = att_gm[1].step(dt_row, &mut rng);
            let qerr = UnitQuaternion::from_scaled_axis(Vector3::new(tilt0[0] + e1, tilt0[1] + e2, tilt0[2]));
            let qm = q * qerr;
            s.ax = fb[0];
            s.ay = fb[1];
            s.az = fb[2];
            s.gx = w[0] + 0.003 * rng.normal();
            s.gy = w[1] + 0.003 * rng.normal();
            s.gz = w[2] + 0.003 * rng.normal();
            let c = qm.into_inner();
            s.qw = c.w;
            s.qx = c.i;
            s.qy = c.j;
            s.qz = c.k;
        }
        if gps_tick {
            let gdt = 1.0 / sc.gps_rate;
            let err = Vector3::new(
                gps_gm[0].step(gdt, &mut rng) + 0.08 * rng.normal(),
                gps_gm[1].step(gdt, &mut rng) + 0.08 * rng.normal(),
                gps_gm[2].step(gdt, &mut rng) + 0.15 * rng.normal(),
            );
            let mut pm = p + err;
            let mut vm = v + Vector3::new(0.05 * rng.normal(), 0.05 * rng.normal(), 0.08 * rng.normal());
            let mut label = 0.0;
            let mut sats = 12.0 + libm::floor(3.0 * rng.uniform());
            let mut eph = 0.8;
            let mut present = true;
            if let Some(oi) = sc.outages.iter().position(|[a, b]| t >= *a && t < *b) {
                label = 1.0;
                match sc.outage_mode {
                    OutageMode::Silent => present = false,
                    OutageMode::Degraded => {
                        let (off, vb) = deg[oi];
                        deg_walk += Vector3::new(rng.normal(), rng.normal(), 0.5 * rng.normal()) * (0.8 * libm::sqrt(gdt));
                        pm = p + off + deg_walk + Vector3::new(rng.normal(), rng.normal(), 2.0 * rng.normal()) * 1.5;
                        vm = v + vb + Vector3::new(rng.normal(), rng.normal(), rng.normal()) * 0.6;
                        sats = 4.0 + libm::floor(2.0 * rng.uniform());
                        eph = 6.0 + 4.0 * rng.uniform();
                    }
                }
            } else {
                deg_walk = Vector3::zeros();
            }
            for (i, ft) in sc.faults.iter().enumerate() {
                let active = t >= ft.start && t < ft.end;
                if !active {
                    continue;
                }
                label = 1.0;
                let d = Vector3::new(libm::cos(fault_dirs[i]), libm::sin(fault_dirs[i]), 0.0);
                match ft.kind {
                    FaultKind::Step => pm += d * ft.magnitude,
                    FaultKind::Ramp => pm += d * (ft.magnitude * (t - ft.start)),
                    FaultKind::Noise => {
                        pm += Vector3::new(rng.normal(), rng.normal(), rng.normal()) * ft.magnitude;
                        vm += Vector3::new(rng.normal(), rng.normal(), rng.normal()) * (0.25 * ft.magnitude);
                    }
                    FaultKind::Frozen => {
                        let fz = frozen[i].get_or_insert((pm[0], pm[1], pm[2], vm));
                        pm = Vector3::new(fz.0, fz.1, fz.2);
                        vm = fz.3;
                    }
                    FaultKind::ZeroVelocity => vm = Vector3::zeros(),
                    FaultKind::BaroStuck | FaultKind::AccelBias => {}
                }
            }
            if present {
                let (lat, lon, alt) = anchor.ned_to_lla(&pm).unwrap_or((f64::NAN, f64::NAN, f64::NAN));
                s.lat = lat;
                s.lon = lon;
                s.alt = alt;
                if sc.gps_velocity {
                    s.vn = vm[0];
                    s.ve = vm[1];
                    s.vd = vm[2];
                }
                s.fix = 3.0;
                s.sats = sats;
                s.eph = eph;
                s.epv = eph * 1.6;
            }
            s.label = label;
        }
        if baro_every > 0 && k % baro_every == baro_offset_rows {
            let mut b = -p[2] + ORIGIN.2 + baro_offset + baro_gm.step(1.0 / sc.baro_rate.max(1e-3), &mut rng) + 0.1 * rng.normal();
            for (i, ft) in sc.faults.iter().enumerate() {
                if ft.kind == FaultKind::BaroStuck && t >= ft.start && t < ft.end {
                    b = *baro_hold[i].get_or_insert(b);
                }
            }
            s.baro = b;
        }
        let _ = in_any(t, &sc.outages);
        rows.push(s);
    }
    Ok(rows)
}

/// Write rows as navlog CSV with `#` comment lines describing the scenario.
pub fn to_csv(sc: &Scenario, rows: &[Sample]) -> String {
    use core::fmt::Write;
    let mut out = String::with_capacity(rows.len() * 160);
    let _ = writeln!(out, "# navguard simulated scenario \"{}\" (seed {})", sc.name, sc.seed);
    if let Ok(j) = serde_json::to_string(sc) {
        let _ = writeln!(out, "# scenario: {j}");
    }
    write_rows(&mut out, rows);
    out
}

/// The header row and one line per row, at the simulator's precision
/// (decimals per column; an absent value is an empty cell).
pub fn write_rows(out: &mut String, rows: &[Sample]) {
    use core::fmt::Write;
    let cols: &[(&str, usize)] = &[
        ("t", 6), ("lat", 9), ("lon", 9), ("alt", 3), ("vn", 3), ("ve", 3), ("vd", 3), ("fix", 0),
        ("sats", 0), ("eph", 2), ("epv", 2), ("ax", 4), ("ay", 4), ("az", 4), ("gx", 5), ("gy", 5),
        ("gz", 5), ("qw", 7), ("qx", 7), ("qy", 7), ("qz", 7), ("baro", 3), ("label", 0),
        ("gps_time", 3),
    ];
    // The receiver-time column only when some row has it, so files without
    // it are byte for byte what they were before the column existed.
    let cols = if rows.iter().any(|s| !s.gps_time.is_nan()) { cols } else { &cols[..cols.len() - 1] };
    let header: Vec<&str> = cols.iter().map(|c| c.0).collect();
    let _ = writeln!(out, "{}", header.join(","));
    for s in rows {
        for (j, (name, dec)) in cols.iter().enumerate() {
            if j > 0 {
                out.push(',');
            }
            let idx = Sample::column_index(name).unwrap_or(0);
            let v = s.get(idx);
            if v.is_finite() {
                let _ = write!(out, "{:.*}", *dec, v);
            }
        }
        out.push('\n');
    }
}

#[cfg(all(test, not(target_arch = "wasm32")))]
mod tests {
    use super::*;
    use approx::assert_abs_diff_eq;

    #[test]
    fn paper_scenario_has_2500_labelled_epochs_300_faulty() {
        let rows = simulate(&Scenario::paper(OutageMode::Degraded, 1)).unwrap();
        let labelled: Vec<&Sample> = rows.iter().filter(|s| !s.label.is_nan()).collect();
        assert_eq!(labelled.len(), 2500);
        assert_eq!(labelled.iter().filter(|s| s.label == 1.0).count(), 300);
        assert_eq!(rows.len(), 12_500);
    }

    #[test]
    fn silent_outage_has_no_fixes() {
        let rows = simulate(&Scenario::paper(OutageMode::Silent, 2)).unwrap();
        assert!(rows.iter().filter(|s| s.t >= 30.0 && s.t < 40.0).all(|s| !s.has_fix()));
        assert!(rows.iter().filter(|s| s.t >= 40.0 && s.t < 41.0).any(|s| s.has_fix()));
    }

    #[test]
    fn deterministic_for_a_seed() {
        let a = simulate(&Scenario::paper(OutageMode::Degraded, 7)).unwrap();
        let b = simulate(&Scenario::paper(OutageMode::Degraded, 7)).unwrap();
        let c = simulate(&Scenario::paper(OutageMode::Degraded, 8)).unwrap();
        assert!(a.iter().zip(&b).all(|(x, y)| x.lat.to_bits() == y.lat.to_bits() || x.lat.is_nan()));
        assert!(a.iter().zip(&c).any(|(x, y)| x.ax != y.ax));
    }

    #[test]
    fn hover_accelerometer_reads_minus_g_and_paper_profile_climbs_60m() {
        let rows = simulate(&Scenario::paper(OutageMode::Silent, 3)).unwrap();
        let anchor = Anchor::at(ORIGIN.0, ORIGIN.1, ORIGIN.2);
        let at = |t: f64| rows.iter().find(|s| (s.t - t).abs() < 1e-9 && s.has_fix()).map(|s| anchor.lla_to_ned(s.lat, s.lon, s.alt)).unwrap();
        // Climb of 1 m/s for ~57 s: about 57 m up (GPS error is a few m).
        assert_abs_diff_eq!(-at(70.0)[2], 57.0, epsilon = 6.0);
        // Level flight at 10 m/s heading north before the first turn.
        let dn = at(75.0)[0] - at(65.0)[0];
        assert_abs_diff_eq!(dn, 100.0, epsilon = 3.0);
        // Specific force magnitude in steady level flight ≈ g.
        let s = rows.iter().find(|s| (s.t - 70.0).abs() < 1e-9).unwrap();
        let fm = (s.ax * s.ax + s.ay * s.ay + s.az * s.az).sqrt();
        assert_abs_diff_eq!(fm, 9.80665, epsilon = 0.3);
    }

    #[test]
    fn csv_round_trips_through_the_reader() {
        let sc = Scenario::with_fault(FaultKind::Step, 10.0, 120.0, 10.0, 4);
        let rows = simulate(&sc).unwrap();
        let text = to_csv(&sc, &rows);
        let back = crate::logs::csv::read_csv(text.as_bytes()).unwrap();
        assert_eq!(back.samples.len(), rows.len());
        for (a, b) in rows.iter().zip(&back.samples).step_by(97) {
            assert_eq!(a.lat.is_nan(), b.lat.is_nan());
            if a.lat.is_finite() {
                assert_abs_diff_eq!(a.lat, b.lat, epsilon = 1e-8);
            }
            assert_abs_diff_eq!(a.ax, b.ax, epsilon = 1e-3);
            assert_eq!(a.label.is_nan(), b.label.is_nan());
        }
    }
}
