//! Tightly coupled GNSS/INS error-state EKF (paper eqs. 1–9).
//!
//! Error state (17): `[φ (3, rad), δv (3, m/s), δp (3, m), δb_g (3, rad/s),
//! δb_a (3, m/s²), δt_u (m), δt_ru (m/s)]`, the paper's eq. 2 with the clock
//! terms expressed in metres. The attitude error φ is in the navigation frame:
//! `C_true = (I + [φ×]) Ĉ`. All other errors are `true − estimate`.
//!
//! Mechanization in the local NED frame with constant gravity; Earth rate and
//! transport rate are neglected (a UAV flight of minutes within a few km of
//! the site, and the simulator uses the same model, so this is not a source of
//! model error here). Closed loop: after every update the error estimate is
//! fed back into the navigation state and reset to zero.
//!
//! Measurements: pseudo-ranges `ρ_i = |s_i − p| + t_u + ε_i`, linearised as
//! `δρ_i = −u_iᵀ δp + δt_u` with `u_i` the unit line of sight to satellite i.

use nalgebra::{DMatrix, DVector, Matrix3, Quaternion, SMatrix, SVector, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

use super::TightError;

/// Error-state dimension.
pub const N: usize = 17;
/// Offset of the attitude error (3) in the error state.
pub const ATT: usize = 0;
/// Offset of the velocity error (3).
pub const VEL: usize = 3;
/// Offset of the position error (3).
pub const POS: usize = 6;
/// Offset of the gyro bias (3).
pub const BG: usize = 9;
/// Offset of the accelerometer bias (3).
pub const BA: usize = 12;
/// Offset of the receiver clock bias.
pub const CLK: usize = 15;
/// Offset of the receiver clock drift.
pub const DRIFT: usize = 16;

/// Standard gravity, m/s² (NED: +down).
pub const GRAVITY: f64 = 9.806_65;

/// A 17×17 error-state matrix.
pub type Mat17 = SMatrix<f64, N, N>;
/// A 17-element error-state vector.
pub type Vec17 = SVector<f64, N>;

/// Skew-symmetric (cross-product) matrix.
pub fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v[2], v[1], v[2], 0.0, -v[0], -v[1], v[0], 0.0)
}

/// Rotation vector -> unit quaternion (libm trigonometry: bit-identical on
/// native and wasm).
pub fn quat_exp(w: &Vector3<f64>) -> UnitQuaternion<f64> {
    let th = w.norm();
    let q = if th < 1e-12 {
        Quaternion::new(1.0, 0.5 * w[0], 0.5 * w[1], 0.5 * w[2])
    } else {
        let s = libm::sin(0.5 * th) / th;
        Quaternion::new(libm::cos(0.5 * th), s * w[0], s * w[1], s * w[2])
    };
    UnitQuaternion::new_normalize(q)
}

/// Small-angle vector φ with `a ≈ (I + [φ×]) b` (rotation matrices).
pub fn attitude_error(a: &Matrix3<f64>, b: &Matrix3<f64>) -> Vector3<f64> {
    let m = a * b.transpose();
    Vector3::new(0.5 * (m[(2, 1)] - m[(1, 2)]), 0.5 * (m[(0, 2)] - m[(2, 0)]), 0.5 * (m[(1, 0)] - m[(0, 1)]))
}

/// Kinematic navigation state plus sensor and clock states.
#[derive(Clone, Debug, PartialEq)]
pub struct NavState {
    /// Body-to-NED attitude.
    pub q: UnitQuaternion<f64>,
    /// Velocity, NED, m/s.
    pub v: Vector3<f64>,
    /// Position, NED, m.
    pub p: Vector3<f64>,
    /// Gyro bias, rad/s.
    pub bg: Vector3<f64>,
    /// Accelerometer bias, m/s².
    pub ba: Vector3<f64>,
    /// Receiver clock bias, m (c·δt).
    pub clk: f64,
    /// Receiver clock drift, m/s.
    pub drift: f64,
}

impl NavState {
    /// Strapdown step over `dt` (s) with bias-corrected angular rate `w`
    /// (rad/s, body) and specific force `f` (m/s², body). The same function
    /// drives the simulator's truth, so a perfect IMU reproduces the truth.
    pub fn mechanize(&mut self, w: &Vector3<f64>, f: &Vector3<f64>, dt: f64) {
        let a = self.q * f + Vector3::new(0.0, 0.0, GRAVITY);
        self.p += self.v * dt + a * (0.5 * dt * dt);
        self.v += a * dt;
        self.q *= quat_exp(&(w * dt));
        self.clk += self.drift * dt;
    }
}

/// IMU noise model (continuous-time densities).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ImuNoise {
    /// Angle random walk, rad/√s.
    pub gyro_arw: f64,
    /// Velocity random walk, m/s/√s.
    pub accel_vrw: f64,
    /// Gyro bias random walk, rad/s/√s.
    pub gyro_bias_rw: f64,
    /// Accelerometer bias random walk, m/s²/√s.
    pub accel_bias_rw: f64,
}

impl Default for ImuNoise {
    /// A small-UAV MEMS IMU including airframe vibration, which dominates
    /// the datasheet noise: 0.2°/√s (12°/√h) and 0.05 m/s/√s (3 m/s/√h).
    fn default() -> Self {
        ImuNoise {
            gyro_arw: 0.2f64.to_radians(),
            accel_vrw: 0.05,
            gyro_bias_rw: 1.0e-6,
            accel_bias_rw: 1.0e-4,
        }
    }
}

/// Filter configuration.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct EkfConfig {
    /// IMU noise densities.
    pub imu: ImuNoise,
    /// Clock bias white-frequency density S_f, m²/s.
    pub clock_sf: f64,
    /// Clock drift random-walk density S_g, m²/s³.
    pub clock_sg: f64,
    /// Pseudo-range standard deviation used in R, m.
    pub sigma_pr: f64,
    /// Initial 1σ: roll/pitch, yaw (rad), velocity (m/s), position (m),
    /// gyro bias (rad/s), accel bias (m/s²), clock bias (m), drift (m/s).
    pub init_sigma: InitSigma,
}

/// Initial standard deviations of the error state.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct InitSigma {
    /// Roll and pitch, rad.
    pub roll_pitch: f64,
    /// Yaw, rad.
    pub yaw: f64,
    /// Velocity, m/s.
    pub vel: f64,
    /// Position, m.
    pub pos: f64,
    /// Gyro bias, rad/s.
    pub gyro_bias: f64,
    /// Accelerometer bias, m/s².
    pub accel_bias: f64,
    /// Clock bias, m.
    pub clk: f64,
    /// Clock drift, m/s.
    pub drift: f64,
}

impl Default for InitSigma {
    fn default() -> Self {
        InitSigma {
            roll_pitch: 0.5f64.to_radians(),
            yaw: 2.0f64.to_radians(),
            vel: 0.3,
            pos: 3.0,
            gyro_bias: 10f64.to_radians() / 3600.0,
            accel_bias: 0.03,
            clk: 10.0,
            drift: 0.5,
        }
    }
}

impl InitSigma {
    /// The 1σ of every error-state element, in state order.
    pub fn as_vector(&self) -> Vec17 {
        let mut s = Vec17::zeros();
        s[0] = self.roll_pitch;
        s[1] = self.roll_pitch;
        s[2] = self.yaw;
        for i in 0..3 {
            s[VEL + i] = self.vel;
            s[POS + i] = self.pos;
            s[BG + i] = self.gyro_bias;
            s[BA + i] = self.accel_bias;
        }
        s[CLK] = self.clk;
        s[DRIFT] = self.drift;
        s
    }
}

impl Default for EkfConfig {
    fn default() -> Self {
        EkfConfig {
            imu: ImuNoise::default(),
            // TCXO: h0 ≈ 2e-19, h-2 ≈ 2e-20 -> S_f = c²h0/2, S_g = 2π²c²h-2.
            clock_sf: 0.009,
            clock_sg: 0.036,
            sigma_pr: 3.0,
            init_sigma: InitSigma::default(),
        }
    }
}

impl EkfConfig {
    /// Every density and σ finite and positive; the error names it.
    pub fn check(&self) -> Result<(), TightError> {
        let pos = |f: &str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(TightError::new(f, format!("must be finite and > 0, got {v}")))
            }
        };
        pos("imu.gyro_arw", self.imu.gyro_arw)?;
        pos("imu.accel_vrw", self.imu.accel_vrw)?;
        pos("imu.gyro_bias_rw", self.imu.gyro_bias_rw)?;
        pos("imu.accel_bias_rw", self.imu.accel_bias_rw)?;
        pos("clock_sf", self.clock_sf)?;
        pos("clock_sg", self.clock_sg)?;
        pos("sigma_pr", self.sigma_pr)?;
        let s = self.init_sigma;
        pos("init_sigma.roll_pitch", s.roll_pitch)?;
        pos("init_sigma.yaw", s.yaw)?;
        pos("init_sigma.vel", s.vel)?;
        pos("init_sigma.pos", s.pos)?;
        pos("init_sigma.gyro_bias", s.gyro_bias)?;
        pos("init_sigma.accel_bias", s.accel_bias)?;
        pos("init_sigma.clk", s.clk)?;
        pos("init_sigma.drift", s.drift)
    }
}

/// One pseudo-range with the satellite position it refers to.
#[derive(Clone, Debug, PartialEq)]
pub struct PrMeas {
    /// Satellite id.
    pub prn: u8,
    /// Pseudo-range, m.
    pub pr: f64,
    /// Satellite position in the site NED frame, m.
    pub sat: Vector3<f64>,
}

/// A linearised pseudo-range measurement set (the paper's Z, H, R, v).
#[derive(Clone, Debug, PartialEq)]
pub struct Linearized {
    /// Satellite of each row.
    pub prns: Vec<u8>,
    /// Innovations `v = Z − h(X̄)`, m (eq. 9).
    pub v: DVector<f64>,
    /// Measurement matrix, n×17.
    pub h: DMatrix<f64>,
    /// Measurement noise covariance, n×n, m².
    pub r: DMatrix<f64>,
    /// Predicted pseudo-ranges `h(X̄)` (INS position + clock), m.
    pub predicted: Vec<f64>,
}

impl Linearized {
    /// Number of measurements.
    pub fn len(&self) -> usize {
        self.prns.len()
    }
    /// No measurement.
    pub fn is_empty(&self) -> bool {
        self.prns.is_empty()
    }
    /// Row of satellite `prn`, if present.
    pub fn index_of(&self, prn: u8) -> Option<usize> {
        self.prns.iter().position(|&p| p == prn)
    }
    /// The set without row `i` (Appendix B, eq. A5).
    pub fn without(&self, i: usize) -> Linearized {
        let keep: Vec<usize> = (0..self.len()).filter(|&k| k != i).collect();
        self.select(&keep)
    }
    /// The rows `keep`, in order.
    pub fn select(&self, keep: &[usize]) -> Linearized {
        let n = keep.len();
        let mut v = DVector::zeros(n);
        let mut h = DMatrix::zeros(n, N);
        let mut r = DMatrix::zeros(n, n);
        for (a, &i) in keep.iter().enumerate() {
            v[a] = self.v[i];
            h.row_mut(a).copy_from(&self.h.row(i));
            for (b, &j) in keep.iter().enumerate() {
                r[(a, b)] = self.r[(i, j)];
            }
        }
        Linearized {
            prns: keep.iter().map(|&i| self.prns[i]).collect(),
            v,
            h,
            r,
            predicted: keep.iter().map(|&i| self.predicted[i]).collect(),
        }
    }
}

/// The filter.
#[derive(Clone, Debug)]
pub struct TcEkf {
    /// The navigation state estimate.
    pub x: NavState,
    /// Error-state covariance, 17×17.
    pub p: Mat17,
    /// Noise and initial uncertainty.
    pub cfg: EkfConfig,
}

impl TcEkf {
    /// Start from `x0` with the configured initial covariance.
    pub fn new(x0: NavState, cfg: EkfConfig) -> Result<Self, TightError> {
        cfg.check()?;
        let s = cfg.init_sigma.as_vector();
        Ok(TcEkf { x: x0, p: Mat17::from_diagonal(&s.component_mul(&s)), cfg })
    }

    /// Continuous-time error dynamics F (eq. 1) at the current estimate, for
    /// bias-corrected specific force `f` (body, m/s²).
    pub fn f_matrix(&self, f: &Vector3<f64>) -> Mat17 {
        let c = self.x.q.to_rotation_matrix().into_inner();
        let mut fm = Mat17::zeros();
        // φ̇ = −C δb_g
        fm.fixed_view_mut::<3, 3>(ATT, BG).copy_from(&(-c));
        // δv̇ = −[(C f)×] φ − C δb_a
        fm.fixed_view_mut::<3, 3>(VEL, ATT).copy_from(&(-skew(&(c * f))));
        fm.fixed_view_mut::<3, 3>(VEL, BA).copy_from(&(-c));
        // δṗ = δv
        fm.fixed_view_mut::<3, 3>(POS, VEL).copy_from(&Matrix3::identity());
        // δṫ_u = δt_ru
        fm[(CLK, DRIFT)] = 1.0;
        fm
    }

    /// Discrete process noise Γ Q Γᵀ over `dt` (eq. 7).
    pub fn q_discrete(&self, dt: f64) -> Mat17 {
        let n = &self.cfg.imu;
        let mut q = Mat17::zeros();
        for i in 0..3 {
            // White gyro/accel noise are isotropic, so C Q Cᵀ = Q.
            q[(ATT + i, ATT + i)] = n.gyro_arw * n.gyro_arw * dt;
            q[(VEL + i, VEL + i)] = n.accel_vrw * n.accel_vrw * dt;
            q[(BG + i, BG + i)] = n.gyro_bias_rw * n.gyro_bias_rw * dt;
            q[(BA + i, BA + i)] = n.accel_bias_rw * n.accel_bias_rw * dt;
        }
        let (sf, sg) = (self.cfg.clock_sf, self.cfg.clock_sg);
        q[(CLK, CLK)] = sf * dt + sg * dt * dt * dt / 3.0;
        q[(CLK, DRIFT)] = sg * dt * dt / 2.0;
        q[(DRIFT, CLK)] = sg * dt * dt / 2.0;
        q[(DRIFT, DRIFT)] = sg * dt;
        q
    }

    /// Time update over `dt` (s) with raw gyro (rad/s) and accelerometer
    /// (m/s²) readings: mechanization plus eqs. 6–7 with Φ ≈ I + F dt + F²dt²/2.
    pub fn propagate(&mut self, gyro: &Vector3<f64>, accel: &Vector3<f64>, dt: f64) {
        if dt.is_nan() || dt <= 0.0 {
            return;
        }
        let w = gyro - self.x.bg;
        let f = accel - self.x.ba;
        let fm = self.f_matrix(&f) * dt;
        let phi = Mat17::identity() + fm + fm * fm * 0.5;
        self.p = phi * self.p * phi.transpose() + self.q_discrete(dt);
        self.symmetrize();
        self.x.mechanize(&w, &f, dt);
    }

    fn symmetrize(&mut self) {
        self.p = (self.p + self.p.transpose()) * 0.5;
    }

    /// Predicted pseudo-ranges, innovations and H for `meas` (eq. 9).
    pub fn linearize(&self, meas: &[PrMeas]) -> Linearized {
        let n = meas.len();
        let mut v = DVector::zeros(n);
        let mut h = DMatrix::zeros(n, N);
        let mut predicted = Vec::with_capacity(n);
        for (i, m) in meas.iter().enumerate() {
            let d = m.sat - self.x.p;
            let range = d.norm();
            let u = d / range;
            let pred = range + self.x.clk;
            predicted.push(pred);
            v[i] = m.pr - pred;
            for k in 0..3 {
                h[(i, POS + k)] = -u[k];
            }
            h[(i, CLK)] = 1.0;
        }
        let s2 = self.cfg.sigma_pr * self.cfg.sigma_pr;
        Linearized {
            prns: meas.iter().map(|m| m.prn).collect(),
            v,
            h,
            r: DMatrix::from_diagonal_element(n, n, s2),
            predicted,
        }
    }

    /// Innovation covariance `P_v = H P Hᵀ + R` (eq. A1).
    pub fn innovation_cov(&self, lin: &Linearized) -> DMatrix<f64> {
        let p = DMatrix::from_column_slice(N, N, self.p.as_slice());
        &lin.h * p * lin.h.transpose() + &lin.r
    }

    /// Measurement update with `lin` (eqs. 8–9), Joseph form
    /// `P = (I−KH) P (I−KH)ᵀ + K R Kᵀ`, then closed-loop feedback. Returns the
    /// applied error-state correction, or `None` (nothing changed) when `lin`
    /// is empty or `P_v` is not positive definite.
    pub fn update(&mut self, lin: &Linearized) -> Option<Vec17> {
        if lin.is_empty() {
            return None;
        }
        let p = DMatrix::from_column_slice(N, N, self.p.as_slice());
        let pht = &p * lin.h.transpose();
        let s = &lin.h * &pht + &lin.r;
        let s_inv = s.cholesky()?.inverse();
        let k = pht * s_inv;
        let dx = &k * &lin.v;
        let ikh = DMatrix::identity(N, N) - &k * &lin.h;
        let pj = &ikh * p * ikh.transpose() + &k * &lin.r * k.transpose();
        if pj.iter().any(|x| !x.is_finite()) || dx.iter().any(|x| !x.is_finite()) {
            return None;
        }
        self.p = Mat17::from_column_slice(pj.as_slice());
        self.symmetrize();
        let dx = Vec17::from_column_slice(dx.as_slice());
        self.inject(&dx);
        Some(dx)
    }

    /// Feed an error-state estimate back into the navigation state.
    pub fn inject(&mut self, dx: &Vec17) {
        let phi = Vector3::new(dx[ATT], dx[ATT + 1], dx[ATT + 2]);
        self.x.q = quat_exp(&phi) * self.x.q;
        self.x.v += Vector3::new(dx[VEL], dx[VEL + 1], dx[VEL + 2]);
        self.x.p += Vector3::new(dx[POS], dx[POS + 1], dx[POS + 2]);
        self.x.bg += Vector3::new(dx[BG], dx[BG + 1], dx[BG + 2]);
        self.x.ba += Vector3::new(dx[BA], dx[BA + 1], dx[BA + 2]);
        self.x.clk += dx[CLK];
        self.x.drift += dx[DRIFT];
    }

    /// Error `truth − estimate` in the error-state convention (for NEES).
    pub fn error_from(&self, truth: &NavState) -> Vec17 {
        let mut e = Vec17::zeros();
        let phi = attitude_error(
            &truth.q.to_rotation_matrix().into_inner(),
            &self.x.q.to_rotation_matrix().into_inner(),
        );
        let dv = truth.v - self.x.v;
        let dp = truth.p - self.x.p;
        let dbg = truth.bg - self.x.bg;
        let dba = truth.ba - self.x.ba;
        for i in 0..3 {
            e[ATT + i] = phi[i];
            e[VEL + i] = dv[i];
            e[POS + i] = dp[i];
            e[BG + i] = dbg[i];
            e[BA + i] = dba[i];
        }
        e[CLK] = truth.clk - self.x.clk;
        e[DRIFT] = truth.drift - self.x.drift;
        e
    }

    /// Normalized estimation error squared `eᵀ P⁻¹ e` over the index range
    /// `dims` of the error state; `None` if that block is singular.
    pub fn nees(&self, truth: &NavState, dims: core::ops::Range<usize>) -> Option<f64> {
        let e = self.error_from(truth);
        let n = dims.len();
        let sub = DMatrix::from_fn(n, n, |i, j| self.p[(dims.start + i, dims.start + j)]);
        let es = DVector::from_fn(n, |i, _| e[dims.start + i]);
        let chol = sub.cholesky()?;
        let y = chol.solve(&es);
        Some(es.dot(&y))
    }
}

#[cfg(all(test, not(target_arch = "wasm32")))]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn state() -> NavState {
        NavState {
            q: UnitQuaternion::identity(),
            v: Vector3::new(15.0, 0.0, 0.0),
            p: Vector3::new(0.0, 0.0, -100.0),
            bg: Vector3::zeros(),
            ba: Vector3::zeros(),
            clk: 50.0,
            drift: 0.2,
        }
    }

    #[test]
    fn mechanization_level_flight() {
        let mut x = state();
        // Level, unaccelerated: accelerometer reads −g on the z axis.
        let f = Vector3::new(0.0, 0.0, -GRAVITY);
        for _ in 0..100 {
            x.mechanize(&Vector3::zeros(), &f, 0.1);
        }
        assert_relative_eq!(x.p, Vector3::new(150.0, 0.0, -100.0), epsilon = 1e-9);
        assert_relative_eq!(x.clk, 52.0, epsilon = 1e-9);
        // Yaw rate 0.1 rad/s for 10 s turns the body by 1 rad.
        let mut y = state();
        for _ in 0..1000 {
            y.mechanize(&Vector3::new(0.0, 0.0, 0.1), &f, 0.01);
        }
        assert_relative_eq!(y.q.euler_angles().2, 1.0, epsilon = 1e-9);
    }

    #[test]
    fn attitude_error_inverts_quat_exp() {
        let phi = Vector3::new(0.01, -0.02, 0.005);
        let b = quat_exp(&Vector3::new(0.3, 0.1, -1.0)).to_rotation_matrix().into_inner();
        let a = quat_exp(&phi).to_rotation_matrix().into_inner() * b;
        assert_relative_eq!(attitude_error(&a, &b), phi, epsilon = 1e-5);
    }

    #[test]
    fn linearize_matches_finite_difference() {
        let ekf = TcEkf::new(state(), EkfConfig::default()).unwrap();
        let sat = Vector3::new(1.0e7, 2.0e7, -1.5e7);
        let m = [PrMeas { prn: 3, pr: 3.0e7, sat }];
        let lin = ekf.linearize(&m);
        assert_relative_eq!(lin.predicted[0], (sat - ekf.x.p).norm() + 50.0, epsilon = 1e-6);
        assert_relative_eq!(lin.v[0], 3.0e7 - lin.predicted[0], epsilon = 1e-6);
        // δρ ≈ H δx for δp = (1, 2, −3) m, δt_u = 4 m.
        let mut e2 = ekf.clone();
        let mut dx = Vec17::zeros();
        dx[POS] = 1.0;
        dx[POS + 1] = 2.0;
        dx[POS + 2] = -3.0;
        dx[CLK] = 4.0;
        e2.inject(&dx);
        let lin2 = e2.linearize(&m);
        let hdx: f64 = (0..N).map(|k| lin.h[(0, k)] * dx[k]).sum();
        assert_relative_eq!(lin2.predicted[0] - lin.predicted[0], hdx, epsilon = 1e-5);
    }

    #[test]
    fn scalar_update_hand_case() {
        // One satellite straight up (u = (0,0,−1)): H = [.. 0 0 1 (pos z) .. 1 (clk) 0].
        // With P_zz = 9, P_clk = 100, R = 9: S = 9 + 100 + 9 = 118, and
        // an innovation of 11.8 m gives δz = 9·11.8/118 = 0.9 m, δt_u = 10 m.
        let mut ekf = TcEkf::new(state(), EkfConfig::default()).unwrap();
        let sat = Vector3::new(0.0, 0.0, -2.0e7);
        let pred = (sat - ekf.x.p).norm() + ekf.x.clk;
        let m = [PrMeas { prn: 1, pr: pred + 11.8, sat }];
        let lin = ekf.linearize(&m);
        assert_relative_eq!(lin.h[(0, POS + 2)], 1.0, epsilon = 1e-12);
        let dx = ekf.update(&lin).unwrap();
        assert_relative_eq!(dx[POS + 2], 0.9, epsilon = 1e-9);
        assert_relative_eq!(dx[CLK], 10.0, epsilon = 1e-9);
        // Posterior: P_zz = 9 − 81/118, P_clk = 100 − 10000/118.
        assert_relative_eq!(ekf.p[(POS + 2, POS + 2)], 9.0 - 81.0 / 118.0, epsilon = 1e-9);
        assert_relative_eq!(ekf.p[(CLK, CLK)], 100.0 - 10000.0 / 118.0, epsilon = 1e-9);
        assert_relative_eq!(ekf.p[(POS + 2, CLK)], -900.0 / 118.0, epsilon = 1e-9);
    }
}

#[cfg(all(test, not(target_arch = "wasm32")))]
mod prop {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]
        /// Any sequence of time updates and pseudo-range updates keeps P
        /// symmetric and positive semi-definite (Joseph form + symmetrize).
        #[test]
        fn covariance_stays_symmetric_psd(
            steps in proptest::collection::vec((0.001f64..0.5, -2.0f64..2.0, -0.5f64..0.5), 1..40),
            sats in proptest::collection::vec((-1.0f64..1.0, -1.0f64..1.0, -1.0f64..-0.05, -50.0f64..50.0), 1..8),
            sigma in 0.3f64..20.0,
        ) {
            let cfg = EkfConfig { sigma_pr: sigma, ..EkfConfig::default() };
            let x0 = NavState {
                q: UnitQuaternion::identity(),
                v: Vector3::new(10.0, 0.0, 0.0),
                p: Vector3::zeros(),
                bg: Vector3::zeros(),
                ba: Vector3::zeros(),
                clk: 0.0,
                drift: 0.0,
            };
            let mut ekf = TcEkf::new(x0, cfg).unwrap();
            for (k, (dt, a, w)) in steps.iter().enumerate() {
                ekf.propagate(&Vector3::new(0.0, 0.0, *w), &Vector3::new(*a, 0.0, -GRAVITY), *dt);
                if k % 3 == 0 {
                    let meas: Vec<PrMeas> = sats.iter().enumerate().map(|(i, (x, y, z, err))| {
                        let dir = Vector3::new(*x, *y, *z).normalize();
                        let sat = dir * 2.2e7;
                        PrMeas { prn: i as u8 + 1, pr: (sat - ekf.x.p).norm() + ekf.x.clk + err, sat }
                    }).collect();
                    let lin = ekf.linearize(&meas);
                    let _ = ekf.update(&lin);
                }
                let asym = (ekf.p - ekf.p.transpose()).abs().max();
                prop_assert!(asym <= 1e-9 * ekf.p.abs().max().max(1.0), "asymmetry {asym}");
                let eig = ekf.p.symmetric_eigenvalues();
                let scale = ekf.p.abs().max();
                prop_assert!(eig.min() >= -1e-9 * scale, "negative eigenvalue {} (scale {scale})", eig.min());
            }
        }
    }
}
