//! The residual-evaluation methods behind `config.method`, besides the
//! default ANFIS. Every method sees the same loosely coupled filter, the same
//! outage logic and the same sensor gating (a fault withholds what departed);
//! only the per-GPS-epoch decision differs. Each reports a score `f` that is
//! its test statistic divided by its threshold, so `f ≥ 1` is a fault.
//!
//! - `chi2`: the per-measurement normalised-innovation test of Shen et al.
//!   2022, Appendix A: `γ_i = |ν_i| / √S_i` for every scalar GPS channel
//!   (position N/E/D, velocity N/E/D), fault when any `γ_i > N_{α/2}`,
//!   α = 0.001 (`N_{α/2}` = 3.29). Score `max γ_i / N_{α/2}`.
//! - `nis`: the whole-vector chi-square test: `q = νᵀ S⁻¹ ν` with the full
//!   innovation covariance `S = H P⁻ Hᵀ + R` over the epoch's channels
//!   (m = 3 or 6), gate at the χ²_m percentile 1 − α, α = 0.001. Score `q / gate`.
//! - `gate`: what PX4 EKF2 and ArduPilot EKF3 do: a 5-sigma innovation gate
//!   per channel, test ratio `ν_i² / (5² S_i)`, fault when any ratio > 1.
//!   Score: the largest test ratio.
//! - `mahalanobis`: in the style of Lin et al. and Khalastchi et al. (cited by
//!   Sun et al.): the Mahalanobis distance of this epoch's residual increment
//!   Δr (eq. 11), per group (position, velocity; 3 axes each), from the mean
//!   and covariance of the last [`MAHA_WINDOW`] normal epochs. The threshold
//!   on d² comes from normal data: the 99.9th percentile over clean
//!   simulated flights ([`MAHA_D2`], reproduced by a test). Score
//!   `max_group d² / MAHA_D2`.
//! - `rms`, `knee`, `adaptive`: the thresholds of Baek & Jo 2018 (see
//!   [`crate::thresholds`]) on the epoch's largest normalised innovation
//!   `max γ_i`, one threshold per operating mode (speed band).

use crate::MinMax;
use nalgebra::{Matrix3, SMatrix, SVector, Vector3};
use serde::{Deserialize, Serialize};

use crate::error::ConfigError;
use crate::thresholds::{Evaluator, SpeedBands, Verdict};

/// Detection method (`config.method`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// The online KF–ANFIS of Sun et al. 2017 (default).
    #[default]
    Anfis,
    /// Per-measurement normalised-innovation test (Shen et al. Appendix A).
    Chi2,
    /// Whole-vector chi-square test on the NIS.
    Nis,
    /// 5-σ innovation gate per channel (PX4 EKF2, ArduPilot EKF3).
    Gate,
    /// Mahalanobis distance of the residual increment (Lin, Khalastchi).
    Mahalanobis,
    /// Baek & Jo RMS threshold (RT).
    Rms,
    /// Baek & Jo knee threshold (KT).
    Knee,
    /// Baek & Jo adaptive threshold (AT).
    Adaptive,
}

impl Method {
    /// Every method, the default first.
    pub const ALL: [Method; 8] =
        [Method::Anfis, Method::Chi2, Method::Nis, Method::Gate, Method::Mahalanobis, Method::Rms, Method::Knee, Method::Adaptive];

    /// The name users give in `config.method`.
    pub fn name(self) -> &'static str {
        match self {
            Method::Anfis => "anfis",
            Method::Chi2 => "chi2",
            Method::Nis => "nis",
            Method::Gate => "gate",
            Method::Mahalanobis => "mahalanobis",
            Method::Rms => "rms",
            Method::Knee => "knee",
            Method::Adaptive => "adaptive",
        }
    }

    /// The method named `s` (as in `config.method`); the error lists them.
    /// `#[inline]`: cold, as [`crate::model::Model::check`].
    #[inline]
    pub fn parse(s: &str) -> Result<Method, ConfigError> {
        Method::ALL.iter().copied().find(|m| m.name() == s).ok_or_else(|| {
            let names: Vec<String> = Method::ALL.iter().map(|m| format!("\"{}\"", m.name())).collect();
            ConfigError::new("method", format!("unknown method \"{s}\" (available: {})", names.join(", ")))
        })
    }
}

/// `N_{α/2}` for α = 0.001: the two-sided standard normal quantile.
pub const N_ALPHA_HALF: f64 = 3.290_526_731_491_926;
/// χ²_m(1 − α) for α = 0.001, m = 1..=6.
pub const CHI2_999: [f64; 6] = [10.827_566, 13.815_511, 16.266_236, 18.466_827, 20.515_006, 22.457_744];
/// χ²₇(1 − α), α = 0.001 (six GPS channels and the baro).
pub const CHI2_999_7: f64 = 24.321_886;
/// The innovation gate of PX4 EKF2 (`EKF2_GPS_P_GATE`, `EKF2_GPS_V_GATE`)
/// and ArduPilot EKF3 (`EK3_POSNE_M_NSE` gates default to 5 σ), in σ.
pub const GATE_SIGMA: f64 = 5.0;

/// One GPS epoch's innovations: position N/E/D then velocity N/E/D, with the
/// prior innovation covariance. Velocity channels are absent (`m = 3`) when
/// the receiver gives no velocity.
#[derive(Clone, Copy, Debug)]
pub struct EpochInnovations {
    /// Innovations ν: position N/E/D (m), velocity N/E/D (m/s).
    pub nu: [f64; 6],
    /// Full `S = H P⁻ Hᵀ + R` (top-left m×m block used).
    pub s: SMatrix<f64, 6, 6>,
    /// Number of GPS channels present (3 or 6).
    pub m: usize,
    /// The barometer's largest normalised innovation since the last GPS
    /// epoch, as (ν m, S m²), if a baro sample was checked.
    pub baro: Option<(f64, f64)>,
}

impl EpochInnovations {
    /// Normalised innovations `γ_i = |ν_i| / √S_i` with each channel's
    /// group (0 position, 1 velocity, 2 baro).
    pub fn gamma(&self) -> impl Iterator<Item = (usize, f64)> + '_ {
        let gps = (0..self.m).map(move |i| (i / 3, self.nu[i].abs() / self.s[(i, i)].fmax(1e-12).sqrt()));
        gps.chain(self.baro.map(|(nu, s)| (2, nu.abs() / s.fmax(1e-12).sqrt())))
    }

    /// Largest `γ_i` (0 when there are no channels).
    pub fn max_gamma(&self) -> f64 {
        self.gamma().fold(0.0, |m, (_, g)| m.fmax(g))
    }
}

/// A method's verdict for one epoch: score (≥ 1 is a fault) and, per group
/// (position, velocity), whether that group failed its own test.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Decision {
    /// Test statistic over its threshold: ≥ 1 is a fault.
    pub score: f64,
    /// Per group (position, velocity, baro): failed its own test.
    pub failed: [bool; 3],
}

/// Shen et al. Appendix A, per measurement.
pub fn chi2(inn: &EpochInnovations) -> Decision {
    let mut failed = [false; 3];
    let mut worst: f64 = 0.0;
    for (grp, g) in inn.gamma() {
        worst = worst.fmax(g);
        failed[grp] |= g > N_ALPHA_HALF;
    }
    Decision { score: worst / N_ALPHA_HALF, failed }
}

/// Whole-vector chi-square test (normalised innovation squared). Built for
/// size in the core module: the default ANFIS never calls it, and its bytes
/// pay for the track departure's (issue 15's budget).
#[cfg_attr(navguard_cold_size, optimize(size))]
pub fn nis(inn: &EpochInnovations) -> Decision {
    let m = inn.m;
    let q = if m == 6 {
        quad::<6>(&inn.s, &inn.nu)
    } else {
        let s3: Matrix3<f64> = inn.s.fixed_view::<3, 3>(0, 0).into_owned();
        quad::<3>(&s3, &inn.nu[..3])
    };
    // The baro is a separate sensor: its own χ²₁ term and one more degree of freedom.
    let (q, m_all) = match inn.baro {
        Some((nu, s)) => (q + nu * nu / s.fmax(1e-12), m + 1),
        None => (q, m),
    };
    let gate = if m_all <= 6 { CHI2_999[m_all.clamp(1, 6) - 1] } else { CHI2_999_7 };
    let score = q / gate;
    // The vector test cannot say which group; per-group χ²₃ tests do.
    let group = |g: usize| {
        if g * 3 >= m {
            return false;
        }
        let s3: Matrix3<f64> = inn.s.fixed_view::<3, 3>(3 * g, 3 * g).into_owned();
        quad::<3>(&s3, &[inn.nu[3 * g], inn.nu[3 * g + 1], inn.nu[3 * g + 2]]) > CHI2_999[2]
    };
    let baro = inn.baro.is_some_and(|(nu, s)| nu * nu / s.fmax(1e-12) > CHI2_999[0]);
    Decision { score, failed: [score >= 1.0 && group(0), score >= 1.0 && group(1), score >= 1.0 && baro] }
}

/// `νᵀ S⁻¹ ν` by Cholesky; a non-positive-definite `S` gives +∞ (the epoch
/// cannot be trusted, so it fails the test rather than passing it).
fn quad<const N: usize>(s: &SMatrix<f64, N, N>, nu: &[f64]) -> f64 {
    let v = SVector::<f64, N>::from_iterator(nu.iter().copied());
    match s.cholesky() {
        Some(ch) => v.dot(&ch.solve(&v)),
        None => f64::INFINITY,
    }
}

/// PX4 EKF2 / ArduPilot EKF3 innovation gate: test ratios `ν²/(g² S)`.
pub fn gate(inn: &EpochInnovations) -> Decision {
    let mut failed = [false; 3];
    let mut worst: f64 = 0.0;
    for (grp, g) in inn.gamma() {
        let ratio = g * g / (GATE_SIGMA * GATE_SIGMA);
        worst = worst.fmax(ratio);
        failed[grp] |= ratio > 1.0;
    }
    Decision { score: worst, failed }
}

/// Normal epochs in the Mahalanobis reference window.
pub const MAHA_WINDOW: usize = 50;
/// Fewest normal epochs before the Mahalanobis test decides.
const MAHA_MIN: usize = 20;
/// Threshold on d² (per group): the 99.9th percentile over clean simulated
/// flights; `tests::mahalanobis_threshold_is_reproducible` recomputes it.
pub const MAHA_D2: f64 = 21.21;

/// Sliding-window mean and covariance of one group's Δr (3 axes), with the
/// Mahalanobis distance of a new Δr from them. Fixed capacity; running sums
/// re-summed once per window to shed rounding.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct MahaWindow {
    ring: Vec<[f64; 3]>,
    head: usize,
    len: usize,
    sum: [f64; 3],
    /// Σ x xᵀ, upper triangle (xx, xy, xz, yy, yz, zz).
    sq: [f64; 6],
    since_resum: usize,
}

impl Default for MahaWindow {
    fn default() -> Self {
        MahaWindow { ring: vec![[0.0; 3]; MAHA_WINDOW], head: 0, len: 0, sum: [0.0; 3], sq: [0.0; 6], since_resum: 0 }
    }
}

fn outer(x: &[f64; 3]) -> [f64; 6] {
    [x[0] * x[0], x[0] * x[1], x[0] * x[2], x[1] * x[1], x[1] * x[2], x[2] * x[2]]
}

impl MahaWindow {
    /// Empty the window (a new reference after an episode or a reset).
    pub fn clear(&mut self) {
        self.head = 0;
        self.len = 0;
        self.sum = [0.0; 3];
        self.sq = [0.0; 6];
        self.since_resum = 0;
    }

    /// Ring capacity and indices in range (a restored snapshot may be forged).
    #[cfg_attr(navguard_cold_size, optimize(size))]
    pub fn check_shape(&self) -> Result<(), String> {
        let cap = self.ring.len();
        if cap != MAHA_WINDOW || self.head >= cap || self.len > cap {
            return Err(format!("mahalanobis window: capacity {cap} / head {} / len {}", self.head, self.len));
        }
        Ok(())
    }

    /// Add (`sign` 1) or remove (−1) one Δr from the running sums.
    fn accumulate(&mut self, x: &[f64; 3], sign: f64) {
        for (s, v) in self.sum.iter_mut().zip(x) {
            *s += sign * v;
        }
        for (s, v) in self.sq.iter_mut().zip(outer(x)) {
            *s += sign * v;
        }
    }

    /// Add a normal epoch's Δr. Built for size in the core module, as the
    /// other methods' per-epoch work is: the default ANFIS never calls it.
    #[cfg_attr(navguard_cold_size, optimize(size))]
    pub fn push(&mut self, x: [f64; 3]) {
        if !x.iter().all(|v| v.is_finite()) {
            return;
        }
        let cap = self.ring.len();
        if self.len == cap {
            let old = self.ring[self.head];
            self.accumulate(&old, -1.0);
        } else {
            self.len += 1;
        }
        self.ring[self.head] = x;
        self.head = (self.head + 1) % cap;
        self.accumulate(&x, 1.0);
        self.since_resum += 1;
        if self.since_resum >= cap {
            // Re-sum exactly once per window to shed rounding.
            self.since_resum = 0;
            self.sum = [0.0; 3];
            self.sq = [0.0; 6];
            for i in 0..self.len {
                let r = self.ring[i];
                self.accumulate(&r, 1.0);
            }
        }
    }

    /// d² of `x` from the window's mean and covariance (NaN until the window
    /// holds `MAHA_MIN` epochs). A small ridge keeps a degenerate window
    /// (a receiver that quantises one axis) invertible. Built for size, like
    /// `push`.
    #[cfg_attr(navguard_cold_size, optimize(size))]
    pub fn d2(&self, x: [f64; 3]) -> f64 {
        if self.len < MAHA_MIN || !x.iter().all(|v| v.is_finite()) {
            return f64::NAN;
        }
        let n = self.len as f64;
        let mu = Vector3::new(self.sum[0] / n, self.sum[1] / n, self.sum[2] / n);
        let q = &self.sq;
        let e = |k: usize, i: usize, j: usize| (q[k] - n * mu[i] * mu[j]) / (n - 1.0);
        let mut c = Matrix3::new(e(0, 0, 0), e(1, 0, 1), e(2, 0, 2), e(1, 0, 1), e(3, 1, 1), e(4, 1, 2), e(2, 0, 2), e(4, 1, 2), e(5, 2, 2));
        let ridge = 1e-6 + 1e-3 * c.trace() / 3.0;
        for i in 0..3 {
            c[(i, i)] += ridge;
        }
        let v = Vector3::new(x[0], x[1], x[2]) - mu;
        match c.cholesky() {
            Some(ch) => v.dot(&ch.solve(&v)),
            None => f64::INFINITY,
        }
    }

    /// Epochs in the window.
    pub fn len(&self) -> usize {
        self.len
    }

    /// No epoch yet.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
}

/// Mahalanobis decision for one epoch's Δr (position, velocity groups).
pub fn mahalanobis(win: &[MahaWindow; 2], dr: [[f64; 3]; 2], has_vel: bool) -> Decision {
    let mut failed = [false; 3];
    let mut worst: f64 = 0.0;
    for g in 0..if has_vel { 2 } else { 1 } {
        let d2 = win[g].d2(dr[g]);
        if d2.is_finite() || d2 == f64::INFINITY {
            worst = worst.fmax(d2 / MAHA_D2);
            failed[g] = d2 > MAHA_D2;
        }
    }
    Decision { score: worst, failed }
}

/// A Baek & Jo threshold pool on the detector's residual (the epoch's
/// largest normalised innovation), one threshold per speed band.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PoolState {
    /// Operating modes by horizontal speed.
    pub bands: SpeedBands,
    /// The threshold pool and its streaming state.
    pub eval: Evaluator,
}

impl PoolState {
    /// Decide one epoch at horizontal speed `speed` (m/s). Built for size in
    /// the core module, like `nis`.
    #[cfg_attr(navguard_cold_size, optimize(size))]
    pub fn decide(&mut self, inn: &EpochInnovations, speed: f64) -> Decision {
        let (grp, g) = inn.gamma().fold((0, 0.0), |b, x| if x.1 > b.1 { x } else { b });
        let mode = self.bands.mode_of(speed).unwrap_or(0);
        let rt = self.eval.rms_threshold(mode);
        let mut failed = [false; 3];
        let score = match self.eval.push(g, mode) {
            Ok(v) if v.is_fault() => {
                failed[grp] = true;
                rt.map_or(1.0, |t| (g / t).fmax(1.0))
            }
            // RT has a continuous ratio; the two-stage methods only have
            // their stages: an anomaly (first stage) scores 0.5.
            Ok(Verdict::Anomaly) => 0.5,
            Ok(_) => rt.map_or(0.0, |t| (g / t).fmin(0.99)),
            Err(_) => 0.0,
        };
        Decision { score, failed }
    }
}

/// The pools of `rms`, `knee` and `adaptive` (in that order), as shipped in
/// `detector/src/default_pools.bin` ([`crate::codec`] bytes, postcard's, so every
/// f64 is bit-exact). They were
/// fitted on clean simulated flights by `navguard::calibrate::fit_pools` (the lab) over
/// seeds [`POOL_SEEDS`]; a test refits them and compares the bytes.
pub const EMBEDDED_POOLS: &[u8] = include_bytes!("default_pools.bin");

/// What the crate embeds and reads: [`EMBEDDED_POOLS`] packed by
/// [`crate::codec::pack`] (8 KB instead of 21 KB in the core wasm module),
/// unpacked at first use. A test holds it to `default_pools.bin`, byte for
/// byte; `NAVGUARD_WRITE_POOLS=1 cargo test --release -p navguard-detector
/// --lib packed_pools` rewrites it from that file.
pub const EMBEDDED_POOLS_PACKED: &[u8] = include_bytes!("default_pools.lz");

/// The simulator seeds the embedded pools were fitted on.
pub const POOL_SEEDS: core::ops::Range<u64> = 1000..1006;

/// The pool for `method` (rms, knee or adaptive): the embedded pools, decoded
/// once per process and cloned. Speed bands split the training epochs into
/// quartiles.
#[inline]
pub fn default_pool(method: Method) -> Result<PoolState, String> {
    use std::sync::OnceLock;
    static POOLS: OnceLock<Result<[PoolState; 3], String>> = OnceLock::new();
    let k = match method {
        Method::Rms => 0,
        Method::Knee => 1,
        Method::Adaptive => 2,
        m => return Err(format!("method \"{}\" has no threshold pool", m.name())),
    };
    let pools = POOLS
        .get_or_init(|| {
            crate::codec::unpack(EMBEDDED_POOLS_PACKED)
                .and_then(|b| crate::codec::from_bytes(&b))
                .map_err(|e| format!("embedded threshold pools: {e}"))
        })
        .as_ref()
        .map_err(|e| e.clone())?;
    Ok(pools[k].clone())
}

#[cfg(all(test, not(target_arch = "wasm32")))]
mod tests {
    /// The packed pools unpack to `default_pools.bin` exactly.
    #[test]
    fn packed_pools_are_the_bin_exactly() {
        if std::env::var_os("NAVGUARD_WRITE_POOLS").is_some() {
            std::fs::write(concat!(env!("CARGO_MANIFEST_DIR"), "/src/default_pools.lz"), crate::codec::pack(super::EMBEDDED_POOLS)).unwrap();
        }
        assert!(crate::codec::unpack(super::EMBEDDED_POOLS_PACKED).unwrap() == super::EMBEDDED_POOLS, "default_pools.lz does not unpack to default_pools.bin");
    }
    use super::*;
    use approx::assert_relative_eq;

    fn diag(nu: [f64; 6], s: [f64; 6], m: usize) -> EpochInnovations {
        let mut sm = SMatrix::<f64, 6, 6>::zeros();
        for i in 0..6 {
            sm[(i, i)] = s[i];
        }
        EpochInnovations { nu, s: sm, m, baro: None }
    }

    #[test]
    fn chi2_hand_case() {
        // γ = |ν|/√S: position E has 3.3/1 > 3.29, the rest are small.
        let inn = diag([0.5, 3.3, -1.0, 0.1, 0.2, 0.3], [1.0, 1.0, 4.0, 0.01, 0.01, 0.01], 6);
        let d = chi2(&inn);
        assert_relative_eq!(d.score, 3.3 / N_ALPHA_HALF, epsilon = 1e-12);
        assert_eq!(d.failed, [true, false, false]);
        // Velocity N: 0.4/√0.01 = 4 fails; position passes.
        let inn = diag([0.5, 1.0, -1.0, 0.4, 0.2, 0.3], [1.0, 1.0, 4.0, 0.01, 0.01, 0.01], 6);
        let d = chi2(&inn);
        assert_relative_eq!(d.score, 4.0 / N_ALPHA_HALF, epsilon = 1e-12);
        assert_eq!(d.failed, [false, true, false]);
        // N_{α/2} for α = 0.001: Φ⁻¹(0.9995).
        assert_relative_eq!(N_ALPHA_HALF, 3.2905267, epsilon = 1e-6);
    }

    #[test]
    fn nis_hand_case_with_correlation() {
        // S = [[2,1,0],[1,2,0],[0,0,1]], ν = (1,1,0): S⁻¹ν = (1/3,1/3,0), q = 2/3.
        let mut inn = diag([1.0, 1.0, 0.0, 0.0, 0.0, 0.0], [2.0, 2.0, 1.0, 1.0, 1.0, 1.0], 3);
        inn.s[(0, 1)] = 1.0;
        inn.s[(1, 0)] = 1.0;
        let d = nis(&inn);
        assert_relative_eq!(d.score, (2.0 / 3.0) / CHI2_999[2], epsilon = 1e-12);
        assert_eq!(d.failed, [false, false, false]);
        // Diagonal, m = 6: q = Σ ν²/S = 16 + 9 = 25 > 22.46.
        let inn = diag([4.0, 0.0, 0.0, 0.3, 0.0, 0.0], [1.0, 1.0, 1.0, 0.01, 0.01, 0.01], 6);
        let d = nis(&inn);
        assert_relative_eq!(d.score, 25.0 / CHI2_999[5], epsilon = 1e-9);
        // Per group: position 16 < 16.27 passes, velocity 9 passes: the
        // vector fails without naming a group.
        assert_eq!(d.failed, [false, false, false]);
        // Not positive definite: fails.
        let inn = diag([0.1; 6], [-1.0, 1.0, 1.0, 1.0, 1.0, 1.0], 6);
        assert!(nis(&inn).score.is_infinite());
    }

    #[test]
    fn gate_hand_case() {
        // Test ratio ν²/(25 S): 6²/25 = 1.44 fails, 4²/25 = 0.64 passes.
        let inn = diag([6.0, 0.0, 0.0, 0.0, 0.0, 0.0], [1.0; 6], 3);
        let d = gate(&inn);
        assert_relative_eq!(d.score, 1.44, epsilon = 1e-12);
        assert_eq!(d.failed, [true, false, false]);
        let mut inn = diag([4.0, 0.0, 0.0, 0.0, 0.0, 0.0], [1.0; 6], 3);
        assert_relative_eq!(gate(&inn).score, 0.64, epsilon = 1e-12);
        // A baro innovation of 3 m with S = 0.25 m²: γ = 6, ratio 1.44, baro group fails.
        inn.baro = Some((3.0, 0.25));
        let d = gate(&inn);
        assert_relative_eq!(d.score, 1.44, epsilon = 1e-12);
        assert_eq!(d.failed, [false, false, true]);
        // ... and in the vector test: q = 16 + 36 = 52 over χ²₄ = 18.47.
        let d = nis(&inn);
        assert_relative_eq!(d.score, 52.0 / CHI2_999[3], epsilon = 1e-9);
        assert_eq!(d.failed, [false, false, true]);
    }

    #[test]
    fn mahalanobis_window_matches_direct_formula() {
        let mut w = MahaWindow::default();
        let mut xs = vec![];
        let mut s = 12345u64;
        let mut rnd = || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        for _ in 0..130 {
            let x = [rnd(), 0.5 * rnd() + 0.2, rnd() * 2.0];
            xs.push(x);
            w.push(x);
        }
        // Direct: the last 50 samples.
        let last = &xs[xs.len() - MAHA_WINDOW..];
        let n = last.len() as f64;
        let mu: Vec<f64> = (0..3).map(|a| last.iter().map(|x| x[a]).sum::<f64>() / n).collect();
        let mut c = Matrix3::zeros();
        for x in last {
            for i in 0..3 {
                for j in 0..3 {
                    c[(i, j)] += (x[i] - mu[i]) * (x[j] - mu[j]) / (n - 1.0);
                }
            }
        }
        let ridge = 1e-6 + 1e-3 * c.trace() / 3.0;
        for i in 0..3 {
            c[(i, i)] += ridge;
        }
        let q = [0.7, -0.1, 1.3];
        let v = Vector3::new(q[0] - mu[0], q[1] - mu[1], q[2] - mu[2]);
        let want = v.dot(&(c.try_inverse().unwrap() * v));
        assert_relative_eq!(w.d2(q), want, max_relative = 1e-9);
        assert_eq!(w.len(), MAHA_WINDOW);
    }

    #[test]
    fn method_names_round_trip_and_unknown_is_named() {
        for m in Method::ALL {
            assert_eq!(Method::parse(m.name()).unwrap(), m);
        }
        let e = Method::parse("magic").unwrap_err().to_string();
        assert!(e.contains("config.method") && e.contains("magic") && e.contains("\"knee\""), "{e}");
    }
}

/// The snapshot codec of this file's state types ([`crate::codec`]): each
/// struct's fields in declaration order (a field left out does not compile;
/// `skip`: not saved, rebuilt on restore).
mod codec_impls {
    use super::*;
    use crate::codec::{impl_codec, impl_codec_enum};

    impl_codec_enum!(Method { Anfis = 0, Chi2 = 1, Nis = 2, Gate = 3, Mahalanobis = 4, Rms = 5, Knee = 6, Adaptive = 7 });
    impl_codec!(MahaWindow { ring, head, len, sum, sq, since_resum });
    impl_codec!(PoolState { bands, eval });
}
