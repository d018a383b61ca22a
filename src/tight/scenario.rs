//! Simulator and evaluation loop: a UAV flight with a MEMS IMU, receiver
//! clock and per-satellite pseudo-ranges; the observation environments of
//! Table 3 and the fault types of Table 4 of Shen et al. 2022.
//!
//! Pseudo-range model (m): `ρ_i = |s_i − p| + t_u + τ_i + m_i + ε_i + f_i(t)`
//! with `t_u` the receiver clock bias (random-walk drift), `τ_i` the residual
//! of a standard troposphere correction (a fixed fraction, per satellite, of
//! `2.4 m / sin(el)`), `m_i` first-order Gauss–Markov multipath, `ε_i` white
//! noise and `f_i` an injected fault.

use nalgebra::{UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

use super::constellation::{dop, los_vectors, Constellation, Site};
use super::gan_fdsr::{default_model, GanDetectorModel};
use super::fdi::{rdpop, Action, FdsrConfig, FilterPredictor, Reconfigurator, Strategy};
use super::tc_ekf::{quat_exp, EkfConfig, ImuNoise, NavState, PrMeas, TcEkf, Vec17, GRAVITY, N};
use super::rows::{EpochRow, InitialState, PrObs};
use super::TightError;
use crate::rng::Rng;

/// Fault types of Table 4.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FaultType {
    /// Type 1: 20 m step.
    Step20,
    /// Type 2: 10 m step.
    Step10,
    /// Type 3: 1 m/s ramp.
    Ramp1,
    /// Type 4: 0.5 m/s ramp.
    Ramp05,
    /// Type 5: 0.3 m/s ramp.
    Ramp03,
}

impl FaultType {
    /// The five fault types of Table 4.
    pub const ALL: [FaultType; 5] = [FaultType::Step20, FaultType::Step10, FaultType::Ramp1, FaultType::Ramp05, FaultType::Ramp03];

    /// Fault on the pseudo-range (m), `dt` seconds after onset.
    pub fn bias(self, dt: f64) -> f64 {
        match self {
            FaultType::Step20 => 20.0,
            FaultType::Step10 => 10.0,
            FaultType::Ramp1 => 1.0 * dt,
            FaultType::Ramp05 => 0.5 * dt,
            FaultType::Ramp03 => 0.3 * dt,
        }
    }

    /// Name in reports.
    pub fn name(self) -> &'static str {
        match self {
            FaultType::Step20 => "Type 1 (step 20 m)",
            FaultType::Step10 => "Type 2 (step 10 m)",
            FaultType::Ramp1 => "Type 3 (ramp 1 m/s)",
            FaultType::Ramp05 => "Type 4 (ramp 0.5 m/s)",
            FaultType::Ramp03 => "Type 5 (ramp 0.3 m/s)",
        }
    }
}

/// An injected fault on one satellite during `[start, end)` (s).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FaultSpec {
    /// The faulty satellite.
    pub prn: u8,
    /// Step or ramp, and its size.
    pub kind: FaultType,
    /// Onset, s.
    pub start: f64,
    /// End (exclusive), s.
    pub end: f64,
}

impl FaultSpec {
    /// The pseudo-range error added to satellite `prn` at time `t` (s), m.
    pub fn bias(&self, prn: u8, t: f64) -> f64 {
        if prn == self.prn && t >= self.start && t < self.end {
            self.kind.bias(t - self.start)
        } else {
            0.0
        }
    }
}

/// Simulation settings.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SimConfig {
    /// Satellites in the constellation (24..=31).
    pub n_sats: usize,
    /// Site latitude, longitude (deg), height (m): origin of NED.
    pub site: (f64, f64, f64),
    /// Run length, s.
    pub duration: f64,
    /// IMU rate, Hz.
    pub imu_rate: f64,
    /// GNSS epoch rate, Hz.
    pub gnss_rate: f64,
    /// Elevation mask, deg.
    pub mask_deg: f64,
    /// White pseudo-range noise, m.
    pub sigma_white: f64,
    /// Multipath standard deviation, m.
    pub multipath_sigma: f64,
    /// Multipath correlation time, s.
    pub multipath_tau: f64,
    /// Troposphere residual as a fraction of the 2.4 m zenith delay, drawn
    /// per satellite in `[−x, x]`.
    pub tropo_residual: f64,
    /// True IMU noise (the filter's model is `ekf.imu`).
    pub imu: ImuNoise,
    /// Filter settings.
    pub ekf: EkfConfig,
}

impl Default for SimConfig {
    fn default() -> Self {
        SimConfig {
            n_sats: 31,
            site: crate::sim::ORIGIN,
            duration: 420.0,
            imu_rate: 20.0,
            gnss_rate: 1.0,
            mask_deg: 10.0,
            sigma_white: 2.5,
            multipath_sigma: 1.0,
            multipath_tau: 20.0,
            tropo_residual: 0.1,
            imu: ImuNoise::default(),
            ekf: EkfConfig::default(),
        }
    }
}

impl SimConfig {
    /// White noise only, matched to the filter's R: the setting where the
    /// EKF must be statistically consistent (NEES test).
    pub fn white_noise_only() -> Self {
        let mut c = SimConfig::default();
        c.multipath_sigma = 0.0;
        c.tropo_residual = 0.0;
        c.sigma_white = c.ekf.sigma_pr;
        c
    }
}

/// Constellation, site and the constellation time at which runs start.
#[derive(Clone, Debug)]
pub struct World {
    /// The satellites' orbits.
    pub constellation: Constellation,
    /// Where the receiver flies.
    pub site: Site,
    /// Constellation time of run time 0, s.
    pub t0: f64,
}

impl World {
    /// Picks the first start time (10-min grid over a day) with the most
    /// satellites above 15° for the whole run.
    pub fn new(cfg: &SimConfig) -> Result<Self, TightError> {
        let constellation = Constellation::gps_like(cfg.n_sats)?;
        let site = Site::new(cfg.site.0, cfg.site.1, cfg.site.2)?;
        let mut best = (0usize, 0.0);
        for k in 0..144 {
            let t0 = k as f64 * 600.0;
            let n = Self::stable(&constellation, &site, t0, cfg.duration, 15.0).len();
            if n > best.0 {
                best = (n, t0);
            }
        }
        Ok(World { constellation, site, t0: best.1 })
    }

    /// PRNs above `mask_deg` at both the start and the end of the run, with
    /// their positions at the start, highest first.
    fn stable(c: &Constellation, site: &Site, t0: f64, duration: f64, mask_deg: f64) -> Vec<(u8, Vector3<f64>)> {
        let p = Vector3::zeros();
        let m = mask_deg.to_radians();
        let a = c.visible(site, &p, t0, m);
        let b = c.visible(site, &p, t0 + duration, m);
        a.into_iter().filter(|s| b.iter().any(|x| x.prn == s.prn)).map(|s| (s.prn, s.pos_ned)).collect()
    }

    /// PDOP of a set of PRNs at run time `t` seen from the site.
    pub fn pdop(&self, prns: &[u8], t: f64) -> Option<f64> {
        let sats: Vec<_> = prns
            .iter()
            .filter_map(|&p| self.constellation.orbit(p).map(|o| self.site.ecef_to_ned(&o.position_ecef(self.t0 + t))))
            .collect();
        dop(&los_vectors(&Vector3::zeros(), &sats)).map(|d| d.pdop)
    }
}

/// Env 5 takes the worst PDOP without the faulty satellite below this bound
/// (a finite, if poor, 5-satellite fix). A milder bound (8) was tried: the
/// faulty satellite then matters less for the step faults but the gradual
/// faults are still absorbed by the filter, with larger errors.
pub const ENV5_MAX_PDOP: f64 = 100.0;

/// An observation environment (Table 3).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Environment {
    /// Environment number: 1–4 as in Table 3, 5 the six-satellite case of Sec. 4.2.
    pub id: u8,
    /// Short name.
    pub name: String,
    /// How the satellite set was chosen.
    pub description: String,
    /// Satellites the receiver tracks.
    pub prns: Vec<u8>,
    /// The satellite the fault is injected on.
    pub faulty_prn: u8,
    /// Start of the fault section, s.
    pub fault_start: f64,
    /// End of the fault section, s.
    pub fault_end: f64,
    /// PDOP with all tracked satellites.
    pub pdop: f64,
    /// PDOP without the faulty satellite.
    pub pdop_without_faulty: f64,
}

fn subsets(items: &[u8], k: usize) -> Vec<Vec<u8>> {
    fn rec(items: &[u8], k: usize, start: usize, cur: &mut Vec<u8>, out: &mut Vec<Vec<u8>>) {
        if cur.len() == k {
            out.push(cur.clone());
            return;
        }
        for i in start..items.len() {
            cur.push(items[i]);
            rec(items, k, i + 1, cur, out);
            cur.pop();
        }
    }
    let mut out = Vec::new();
    rec(items, k, 0, &mut Vec::new(), &mut out);
    out
}

/// The environments of Table 3 (Env 1–4) plus the Section 4.2 environment
/// (Env 5) used for the fault types of Table 4. Satellite sets are chosen
/// from the satellites above 15° during the whole run, emulating blockage:
///
/// * Env 1: the 9 highest satellites; Env 2: the 5 highest of those (urban
///   canyon). The faulty satellite is the one of Env 2 whose loss degrades
///   PDOP most; it is in both (like the paper's G6). Fault 199–219 s.
/// * Env 3 / Env 4: 5 satellites with the same faulty satellite (like G11);
///   configuration 1 keeps a good PDOP without it, configuration 2 the worst
///   (both have PDOP ≤ 6 with all five). Fault 256–276 s.
/// * Env 5: 6 satellites where the faulty satellite matters most (like G7 in
///   Sec. 4.2); fault 300–360 s.
pub fn environments(world: &World, cfg: &SimConfig) -> Result<Vec<Environment>, TightError> {
    let cands: Vec<u8> = World::stable(&world.constellation, &world.site, world.t0, cfg.duration, 15.0)
        .into_iter()
        .map(|(p, _)| p)
        .collect();
    if cands.len() < 7 {
        return Err(TightError::new("n_sats", format!("only {} satellites above 15° for the run; need 7", cands.len())));
    }
    let pd = |s: &[u8], t: f64| world.pdop(s, t).unwrap_or(f64::INFINITY);
    let mut envs = Vec::new();

    // Env 1 and 2.
    let e1: Vec<u8> = cands.iter().copied().take(9).collect();
    let e2: Vec<u8> = e1.iter().copied().take(5).collect();
    let t12 = 199.0;
    let without = |s: &[u8], f: u8| -> Vec<u8> { s.iter().copied().filter(|&p| p != f).collect() };
    let f12 = e2
        .iter()
        .copied()
        .filter(|&f| pd(&without(&e2, f), t12).is_finite())
        .max_by(|&a, &b| pd(&without(&e2, a), t12).total_cmp(&pd(&without(&e2, b), t12)))
        .ok_or_else(|| TightError::new("environment", "Env 2 has no usable faulty satellite"))?;
    for (id, set, desc) in [
        (1u8, &e1, "9 highest satellites above 15°"),
        (2u8, &e2, "the 5 highest of Env 1 (urban canyon)"),
    ] {
        envs.push(Environment {
            id,
            name: format!("Env {id}"),
            description: desc.to_string(),
            prns: set.clone(),
            faulty_prn: f12,
            fault_start: t12,
            fault_end: 219.0,
            pdop: pd(set, t12),
            pdop_without_faulty: pd(&without(set, f12), t12),
        });
    }

    // Env 3 and 4: same faulty satellite, good vs poor configuration.
    let t34 = 256.0;
    let mut best: Option<(f64, u8, Vec<u8>, Vec<u8>)> = None;
    for &g in &cands {
        let others: Vec<u8> = cands.iter().copied().filter(|&p| p != g).collect();
        let mut good: Option<(f64, Vec<u8>)> = None;
        let mut poor: Option<(f64, Vec<u8>)> = None;
        for s in subsets(&others, 4) {
            let mut all = s.clone();
            all.push(g);
            if pd(&all, t34) > 6.0 {
                continue;
            }
            let w = pd(&s, t34);
            if !w.is_finite() || w > 200.0 {
                continue;
            }
            if good.as_ref().is_none_or(|(b, _)| w < *b) {
                good = Some((w, all.clone()));
            }
            if poor.as_ref().is_none_or(|(b, _)| w > *b) {
                poor = Some((w, all));
            }
        }
        if let (Some((gw, gs)), Some((pw, ps))) = (good, poor) {
            let ratio = pw / gw;
            if best.as_ref().is_none_or(|(r, ..)| ratio > *r) {
                best = Some((ratio, g, gs, ps));
            }
        }
    }
    let (_, g, good, poor) = best.ok_or_else(|| TightError::new("environment", "no 5-satellite configuration for Env 3/4"))?;
    for (id, set, desc) in [
        (3u8, good, "5 satellites, configuration 1 (good geometry without the faulty one)"),
        (4u8, poor, "5 satellites, configuration 2 (poor geometry without the faulty one)"),
    ] {
        envs.push(Environment {
            id,
            name: format!("Env {id}"),
            description: desc.to_string(),
            pdop: pd(&set, t34),
            pdop_without_faulty: pd(&without(&set, g), t34),
            prns: set,
            faulty_prn: g,
            fault_start: t34,
            fault_end: 276.0,
        });
    }

    // Env 5 (Sec. 4.2).
    let t5 = 300.0;
    let mut best5: Option<(f64, u8, Vec<u8>)> = None;
    for &g in &cands {
        let others: Vec<u8> = cands.iter().copied().filter(|&p| p != g).collect();
        for s in subsets(&others, 5) {
            let mut all = s.clone();
            all.push(g);
            if pd(&all, t5) > 4.0 {
                continue;
            }
            let w = pd(&s, t5);
            if !w.is_finite() || w > ENV5_MAX_PDOP {
                continue;
            }
            if best5.as_ref().is_none_or(|(b, ..)| w > *b) {
                best5 = Some((w, g, all));
            }
        }
    }
    let (_, g5, s5) = best5.ok_or_else(|| TightError::new("environment", "no 6-satellite configuration for Env 5"))?;
    envs.push(Environment {
        id: 5,
        name: "Env 5".to_string(),
        description: "6 satellites, the faulty one critical (Sec. 4.2)".to_string(),
        pdop: pd(&s5, t5),
        pdop_without_faulty: pd(&without(&s5, g5), t5),
        prns: s5,
        faulty_prn: g5,
        fault_start: t5,
        fault_end: 360.0,
    });
    Ok(envs)
}

/// The UAV flight profile: yaw rate (rad/s), forward and downward
/// acceleration (m/s²) at time `t`. A 100 s pattern: straight, a 90° turn
/// (alternating left/right), straight; speed and height changes.
pub fn profile(t: f64) -> (f64, f64, f64) {
    let k = libm::floor(t / 100.0);
    let s = t - 100.0 * k;
    let sign = if (k as i64) % 2 == 0 { 1.0 } else { -1.0 };
    let r = if (40.0..70.0).contains(&s) { sign * 3f64.to_radians() } else { 0.0 };
    let a_fwd = if (10.0..14.0).contains(&s) {
        0.5
    } else if (80.0..84.0).contains(&s) {
        -0.5
    } else {
        0.0
    };
    let a_down = if (20.0..24.0).contains(&s) {
        -0.25
    } else if (24.0..28.0).contains(&s) {
        0.25
    } else {
        0.0
    };
    (r, a_fwd, a_down)
}

/// True angular rate and specific force (body) for the profile at `t`.
fn true_imu(x: &NavState, t: f64) -> (Vector3<f64>, Vector3<f64>) {
    let (r, a_fwd, a_down) = profile(t);
    let vh = Vector3::new(x.v[0], x.v[1], 0.0);
    let speed = vh.norm().max(1e-6);
    let a = vh * (a_fwd / speed) + Vector3::new(-x.v[1], x.v[0], 0.0) * r + Vector3::new(0.0, 0.0, a_down);
    let f = x.q.inverse() * (a - Vector3::new(0.0, 0.0, GRAVITY));
    (Vector3::new(0.0, 0.0, r), f)
}

/// Per-run results, one entry per GNSS epoch.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct RunRecord {
    /// Epoch time, s.
    pub t: Vec<f64>,
    /// 3-D position error |p̂ − p|, m.
    pub pos_err: Vec<f64>,
    /// RDPOP of the environment's faulty satellite (NaN if untracked).
    pub rdpop_faulty: Vec<f64>,
    /// λ of the environment's faulty satellite (NaN if untracked).
    pub lambda_faulty: Vec<f64>,
    /// Flagged satellite per epoch (0 = none).
    pub flagged_prn: Vec<u8>,
    /// What the reconfigurator did per epoch.
    pub action: Vec<Action>,
    /// NEES of the full 17-dim error state.
    pub nees: Vec<f64>,
    /// Per epoch, every tracked satellite's (prn, measured pseudo-range,
    /// filter-predicted pseudo-range) before the update, m: the GNSS and INS
    /// pseudo-ranges ρ_G and ρ_I of the paper's eq. 10.
    #[serde(default)]
    pub ranges: Vec<Vec<(u8, f64, f64)>>,
    /// Per epoch, the normalised innovation λ (eq. A2) of each satellite of
    /// `ranges`, in the same order.
    #[serde(default)]
    pub lambdas: Vec<Vec<f64>>,
}

impl RunRecord {
    fn window(&self, a: f64, b: f64) -> impl Iterator<Item = usize> + '_ {
        self.t.iter().enumerate().filter(move |(_, &t)| t >= a && t < b).map(|(i, _)| i)
    }
    /// RMS position error in `[a, b)`, m.
    pub fn rms(&self, a: f64, b: f64) -> f64 {
        let (s, n) = self.window(a, b).fold((0.0, 0usize), |(s, n), i| (s + self.pos_err[i] * self.pos_err[i], n + 1));
        if n == 0 {
            f64::NAN
        } else {
            libm::sqrt(s / n as f64)
        }
    }
    /// Maximum position error in `[a, b)`, m.
    pub fn max(&self, a: f64, b: f64) -> f64 {
        self.window(a, b).map(|i| self.pos_err[i]).fold(f64::NAN, f64::max)
    }
    /// Mean of a series in `[a, b)` ignoring NaN.
    pub fn mean_of(&self, series: &[f64], a: f64, b: f64) -> f64 {
        let (s, n) = self
            .window(a, b)
            .filter(|&i| series[i].is_finite())
            .fold((0.0, 0usize), |(s, n), i| (s + series[i], n + 1));
        if n == 0 {
            f64::NAN
        } else {
            s / n as f64
        }
    }
    /// First epoch in `[a, b)` flagging `prn`, as a delay after `a` (s).
    pub fn detection_delay(&self, prn: u8, a: f64, b: f64) -> Option<f64> {
        self.window(a, b).find(|&i| self.flagged_prn[i] == prn).map(|i| self.t[i] - a)
    }
    /// Epochs in `[a, b)` flagging a satellite other than `prn`.
    pub fn wrong_flags(&self, prn: u8, a: f64, b: f64) -> usize {
        self.window(a, b).filter(|&i| self.flagged_prn[i] != 0 && self.flagged_prn[i] != prn).count()
    }
    /// Fraction of epochs in `[a, b)` flagging `prn`.
    pub fn flag_rate(&self, prn: u8, a: f64, b: f64) -> f64 {
        let (k, n) = self.window(a, b).fold((0, 0), |(k, n), i| (k + usize::from(self.flagged_prn[i] == prn), n + 1));
        if n == 0 {
            f64::NAN
        } else {
            k as f64 / n as f64
        }
    }
}

/// One run.
#[derive(Clone, Debug)]
pub struct RunSpec<'a> {
    /// Constellation and site.
    pub world: &'a World,
    /// Sensor and noise settings.
    pub cfg: &'a SimConfig,
    /// Tracked satellites.
    pub prns: &'a [u8],
    /// Satellite whose RDPOP and λ are recorded.
    pub watch_prn: u8,
    /// The injected fault, if any.
    pub fault: Option<FaultSpec>,
    /// Detection strategy and thresholds.
    pub fdsr: FdsrConfig,
    /// Seed of every random draw.
    pub seed: u64,
    /// GAN-FDSR model for [`Strategy::Gan`]; `None`: the embedded default.
    pub gan: Option<&'a GanDetectorModel>,
}

/// Simulate a flight and run the filter with detection/reconfiguration.
/// Noise draws do not depend on the strategy, so runs with the same seed
/// share every noise realisation.
pub fn run(spec: &RunSpec) -> Result<RunRecord, TightError> {
    run_inner(spec, None)
}

/// [`run`] that also returns the simulated raw rows (one per IMU sample, in
/// the [`EpochRow`] format of the streaming API) and the true initial state.
pub fn run_with_rows(spec: &RunSpec) -> Result<(RunRecord, Vec<EpochRow>, InitialState), TightError> {
    let mut rows = Vec::new();
    let rec = run_inner(spec, Some(&mut rows))?;
    let init = InitialState {
        t: 0.0,
        position_ned: [0.0, 0.0, -100.0],
        velocity_ned: [15.0, 0.0, 0.0],
        roll_pitch_yaw_deg: [0.0; 3],
        clock_bias_m: 1500.0,
        clock_drift_mps: 0.3,
    };
    Ok((rec, rows, init))
}

fn run_inner(spec: &RunSpec, mut rows: Option<&mut Vec<EpochRow>>) -> Result<RunRecord, TightError> {
    let cfg = spec.cfg;
    for (f, v) in [("imu_rate", cfg.imu_rate), ("gnss_rate", cfg.gnss_rate), ("duration", cfg.duration)] {
        if !(v.is_finite() && v > 0.0) {
            return Err(TightError::new(f, format!("must be finite and > 0, got {v}")));
        }
    }
    let dt = 1.0 / cfg.imu_rate;
    let steps_per_epoch = libm::round(cfg.imu_rate / cfg.gnss_rate).max(1.0) as usize;
    let n_steps = libm::round(cfg.duration * cfg.imu_rate) as usize;
    let mut rng_imu = Rng::new(spec.seed.wrapping_mul(0x1000_0001).wrapping_add(1));
    let mut rng_gnss = Rng::new(spec.seed.wrapping_mul(0x1000_0001).wrapping_add(2));
    let mut rng_clk = Rng::new(spec.seed.wrapping_mul(0x1000_0001).wrapping_add(3));
    let mut rng_init = Rng::new(spec.seed.wrapping_mul(0x1000_0001).wrapping_add(4));

    // Truth: biases are drawn from the filter's initial uncertainty.
    let is = cfg.ekf.init_sigma;
    let mut truth = NavState {
        q: UnitQuaternion::identity(),
        v: Vector3::new(15.0, 0.0, 0.0),
        p: Vector3::new(0.0, 0.0, -100.0),
        bg: Vector3::new(rng_init.normal(), rng_init.normal(), rng_init.normal()) * is.gyro_bias,
        ba: Vector3::new(rng_init.normal(), rng_init.normal(), rng_init.normal()) * is.accel_bias,
        clk: 1500.0,
        drift: 0.3,
    };
    // Estimate = truth − e, e ~ N(0, P0) (diagonal P0).
    let sig = is.as_vector();
    let e = Vec17::from_fn(|i, _| sig[i] * rng_init.normal());
    let mut x0 = truth.clone();
    x0.q = quat_exp(&(-Vector3::new(e[0], e[1], e[2]))) * truth.q;
    x0.v -= Vector3::new(e[3], e[4], e[5]);
    x0.p -= Vector3::new(e[6], e[7], e[8]);
    x0.bg = Vector3::zeros();
    x0.ba = Vector3::zeros();
    x0.clk -= e[15];
    x0.drift -= e[16];
    let mut ekf = TcEkf::new(x0, cfg.ekf)?;
    let mut fdsr = match (spec.fdsr.strategy, spec.gan) {
        (Strategy::Gan, Some(m)) => Reconfigurator::with_gan(spec.fdsr, m.clone())?,
        (strategy, _) => {
            let gan = if strategy == Strategy::Gan { Some(default_model()?) } else { None };
            Reconfigurator::new(spec.fdsr, Box::new(FilterPredictor::new(cfg.ekf.sigma_pr * cfg.ekf.sigma_pr)), gan)?
        }
    };

    // Per-satellite error states.
    let mut tropo = [0.0f64; 256];
    for v in tropo.iter_mut() {
        *v = rng_gnss.range(-cfg.tropo_residual, cfg.tropo_residual);
    }
    let mut mp = [0.0f64; 256];
    for v in mp.iter_mut() {
        *v = cfg.multipath_sigma * rng_gnss.normal();
    }
    let gnss_dt = steps_per_epoch as f64 * dt;
    let phi_mp = libm::exp(-gnss_dt / cfg.multipath_tau.max(1e-9));
    let mask = cfg.mask_deg.to_radians();
    // Clock noise: Cholesky of the 2×2 discrete covariance.
    let q = ekf.q_discrete(dt);
    let (qbb, qbd, qdd) = (q[(15, 15)], q[(15, 16)], q[(16, 16)]);
    let l11 = libm::sqrt(qbb);
    let l21 = qbd / l11;
    let l22 = libm::sqrt((qdd - l21 * l21).max(0.0));
    let n = &cfg.imu;

    let mut rec = RunRecord::default();
    for k in 0..n_steps {
        let t = k as f64 * dt;
        let (w, f) = true_imu(&truth, t);
        // IMU readings: truth + bias + white noise; biases random-walk.
        let sq = libm::sqrt(dt);
        let gyro = w + truth.bg + Vector3::new(rng_imu.normal(), rng_imu.normal(), rng_imu.normal()) * (n.gyro_arw / sq);
        let acc = f + truth.ba + Vector3::new(rng_imu.normal(), rng_imu.normal(), rng_imu.normal()) * (n.accel_vrw / sq);
        truth.mechanize(&w, &f, dt);
        truth.bg += Vector3::new(rng_imu.normal(), rng_imu.normal(), rng_imu.normal()) * (n.gyro_bias_rw * sq);
        truth.ba += Vector3::new(rng_imu.normal(), rng_imu.normal(), rng_imu.normal()) * (n.accel_bias_rw * sq);
        let (z1, z2) = (rng_clk.normal(), rng_clk.normal());
        truth.clk += l11 * z1;
        truth.drift += l21 * z1 + l22 * z2;
        ekf.propagate(&gyro, &acc, dt);
        if let Some(r) = rows.as_deref_mut() {
            r.push(EpochRow { t: (k + 1) as f64 * dt, gyro: [gyro[0], gyro[1], gyro[2]], accel: [acc[0], acc[1], acc[2]], pr: Vec::new() });
        }

        if (k + 1) % steps_per_epoch != 0 {
            continue;
        }
        let te = (k + 1) as f64 * dt;
        let sats = spec.world.constellation.positions_ned(&spec.world.site, spec.world.t0 + te);
        let mut meas = Vec::new();
        for (prn, s) in sats {
            let i = prn as usize;
            mp[i] = phi_mp * mp[i] + libm::sqrt(1.0 - phi_mp * phi_mp) * cfg.multipath_sigma * rng_gnss.normal();
            let white = cfg.sigma_white * rng_gnss.normal();
            if !spec.prns.contains(&prn) {
                continue;
            }
            let (el, _) = super::constellation::elevation_azimuth(&truth.p, &s);
            if el < mask {
                continue;
            }
            let fault = spec.fault.map_or(0.0, |fs| fs.bias(prn, te));
            let pr = (s - truth.p).norm() + truth.clk + tropo[i] * 2.4 / libm::sin(el) + mp[i] + white + fault;
            meas.push(PrMeas { prn, pr, sat: s });
        }
        if let Some(last) = rows.as_deref_mut().and_then(|r| r.last_mut()) {
            last.pr = meas.iter().map(|m| PrObs { prn: m.prn, pr: m.pr }).collect();
        }
        let lin = ekf.linearize(&meas);
        rec.ranges.push(lin.prns.iter().zip(&lin.predicted).zip(lin.v.iter()).map(|((&p, &pred), &v)| (p, pred + v, pred)).collect());
        let watch = lin.index_of(spec.watch_prn);
        let rd = watch.and_then(|i| rdpop(&ekf.p, &lin, i)).unwrap_or(f64::NAN);
        let d = fdsr.epoch(&mut ekf, &meas, te);
        let lam = d.lambdas.iter().find(|(p, _)| *p == spec.watch_prn).map_or(f64::NAN, |x| x.1);
        rec.lambdas.push(lin.prns.iter().map(|p| d.lambdas.iter().find(|x| x.0 == *p).map_or(f64::NAN, |x| x.1)).collect());
        rec.t.push(te);
        rec.pos_err.push((ekf.x.p - truth.p).norm());
        rec.rdpop_faulty.push(rd);
        rec.lambda_faulty.push(lam);
        rec.flagged_prn.push(d.detection.map_or(0, |x| x.prn));
        rec.action.push(d.action);
        rec.nees.push(ekf.nees(&truth, 0..N).unwrap_or(f64::NAN));
    }
    Ok(rec)
}

/// Results of one environment (Figure 8) or fault type (Figure 11).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CaseResult {
    /// Case label (environment or fault type).
    pub label: String,
    /// The environment it ran in.
    pub env: Environment,
    /// The injected fault.
    pub fault: FaultSpec,
    /// (strategy label, record): "FF" (fault-free, no detection), "FDI" (FI),
    /// "FDA" (FA), "RDPOP-switch".
    pub runs: Vec<(String, RunRecord)>,
}

impl CaseResult {
    /// The run of strategy `label` ("FF", "FDI", ...).
    pub fn record(&self, label: &str) -> Option<&RunRecord> {
        self.runs.iter().find(|(l, _)| l == label).map(|(_, r)| r)
    }
}

/// Runs FF, FDI, FDA and the RDPOP switch for one environment and fault.
pub fn run_case(world: &World, cfg: &SimConfig, env: &Environment, kind: FaultType, eta: f64, seed: u64, label: &str) -> Result<CaseResult, TightError> {
    let fault = FaultSpec { prn: env.faulty_prn, kind, start: env.fault_start, end: env.fault_end };
    let mut runs = Vec::new();
    for (name, strategy, faulty) in [
        ("FF", Strategy::None, false),
        ("FDI", Strategy::Fdi, true),
        ("FDA", Strategy::Fda, true),
        ("RDPOP-switch", Strategy::Switch, true),
    ] {
        let spec = RunSpec {
            world,
            cfg,
            prns: &env.prns,
            watch_prn: env.faulty_prn,
            fault: faulty.then_some(fault),
            fdsr: FdsrConfig { strategy, alpha: 0.001, eta },
            seed,
            gan: None,
        };
        runs.push((name.to_string(), run(&spec)?));
    }
    Ok(CaseResult { label: label.to_string(), env: env.clone(), fault, runs })
}

#[cfg(all(test, not(target_arch = "wasm32")))]
mod tests {
    use super::*;
    use crate::tight::stats::chi2_quantile;

    #[test]
    fn fault_types_table4() {
        assert_eq!(FaultType::Step20.bias(0.0), 20.0);
        assert_eq!(FaultType::Step10.bias(30.0), 10.0);
        assert!((FaultType::Ramp1.bias(18.0) - 18.0).abs() < 1e-12);
        assert!((FaultType::Ramp05.bias(34.0) - 17.0).abs() < 1e-12);
        assert!((FaultType::Ramp03.bias(60.0) - 18.0).abs() < 1e-12);
        let f = FaultSpec { prn: 7, kind: FaultType::Ramp1, start: 300.0, end: 360.0 };
        assert_eq!(f.bias(7, 299.0), 0.0);
        assert_eq!(f.bias(7, 310.0), 10.0);
        assert_eq!(f.bias(8, 310.0), 0.0);
        assert_eq!(f.bias(7, 360.0), 0.0);
    }

    #[test]
    fn environments_match_table3() {
        let cfg = SimConfig::default();
        let world = World::new(&cfg).unwrap();
        let envs = environments(&world, &cfg).unwrap();
        let n: Vec<usize> = envs.iter().map(|e| e.prns.len()).collect();
        assert_eq!(n, vec![9, 5, 5, 5, 6]);
        // Same faulty satellite in Env 1/2 and in Env 3/4, tracked in each.
        assert_eq!(envs[0].faulty_prn, envs[1].faulty_prn);
        assert_eq!(envs[2].faulty_prn, envs[3].faulty_prn);
        assert!(envs.iter().all(|e| e.prns.contains(&e.faulty_prn)));
        // Configuration 2 loses far more geometry than configuration 1.
        assert!(envs[3].pdop_without_faulty > 5.0 * envs[2].pdop_without_faulty, "{envs:?}");
        assert!(envs[1].pdop_without_faulty > 3.0 * envs[0].pdop_without_faulty);
        assert_eq!((envs[0].fault_start, envs[2].fault_start, envs[4].fault_start), (199.0, 256.0, 300.0));
    }

    /// EKF consistency: averaged NEES of the 17-dim error state over Monte
    /// Carlo runs stays inside the two-sided 99 % chi-square band.
    #[test]
    fn nees_within_chi_square_bounds() {
        let mut cfg = SimConfig::white_noise_only();
        cfg.duration = 240.0;
        let world = World::new(&cfg).unwrap();
        let envs = environments(&world, &cfg).unwrap();
        let m = 12usize;
        let mut sum: Vec<f64> = Vec::new();
        for seed in 0..m as u64 {
            let spec = RunSpec {
                world: &world,
                cfg: &cfg,
                prns: &envs[0].prns,
                watch_prn: envs[0].faulty_prn,
                fault: None,
                fdsr: FdsrConfig { strategy: Strategy::None, alpha: 0.001, eta: 0.1 },
                seed: 100 + seed,
                gan: None,
            };
            let r = run(&spec).unwrap();
            if sum.is_empty() {
                sum = vec![0.0; r.nees.len()];
            }
            for (s, v) in sum.iter_mut().zip(&r.nees) {
                assert!(v.is_finite());
                *s += v;
            }
        }
        let dof = (N * m) as f64;
        let lo = chi2_quantile(0.005, dof).unwrap() / m as f64;
        let hi = chi2_quantile(0.995, dof).unwrap() / m as f64;
        let anees: Vec<f64> = sum.iter().map(|s| s / m as f64).collect();
        let inside = anees.iter().filter(|a| **a >= lo && **a <= hi).count() as f64 / anees.len() as f64;
        let mean = anees.iter().sum::<f64>() / anees.len() as f64;
        eprintln!("ANEES mean {mean:.2} (dof {N}), band [{lo:.2}, {hi:.2}], inside {inside:.3}");
        assert!(inside >= 0.9, "only {inside} of epochs inside [{lo}, {hi}]");
        assert!((0.85 * N as f64..=1.15 * N as f64).contains(&mean), "mean ANEES {mean}");
    }
}
