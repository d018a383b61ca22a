//! Loosely coupled GPS/INS Kalman filter in local NED.
//!
//! State `x` (10): position NED (m), velocity NED (m/s), accelerometer bias in
//! the body frame (m/s²), barometer offset (m, baro altitude minus true
//! altitude). Prediction runs at IMU rate from the specific force rotated by
//! the attitude quaternion with gravity added; with no fresh IMU it falls back
//! to a constant-velocity model with a larger process noise, so GPS-only
//! streams work. Updates are sequential scalar updates in Joseph form, which
//! keeps `P` symmetric positive semi-definite in floating point.

#![allow(non_snake_case)] // textbook names: P, Q, F, K, C

use nalgebra::{Matrix3, Quaternion, SMatrix, SVector, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

/// State dimension.
pub const N: usize = 10;
/// The state `x`: position NED (m), velocity NED (m/s), accelerometer bias
/// (body, m/s²), barometer offset (m).
pub type StateVec = SVector<f64, N>;
/// An N×N matrix over the state (`P`, `Φ`, `Q`).
pub type StateMat = SMatrix<f64, N, N>;

/// Standard gravity, m/s², NED down positive.
pub const GRAVITY: f64 = 9.80665;

const IP: usize = 0; // position block start
const IV: usize = 3; // velocity block start
const IB: usize = 6; // accel-bias block start
const IBARO: usize = 9;

/// Noise settings of the filter (all 1-sigma).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FilterNoise {
    /// White accelerometer noise density used with IMU, m/s² (per sqrt(s) scaled by dt).
    pub accel: f64,
    /// Acceleration noise of the constant-velocity model (no IMU), m/s².
    pub cv_accel: f64,
    /// Accelerometer bias random walk, m/s² per sqrt(s).
    pub accel_bias_rw: f64,
    /// Barometer offset random walk, m per sqrt(s).
    pub baro_rw: f64,
    /// GPS horizontal position noise, m.
    pub gps_pos_h: f64,
    /// GPS vertical position noise, m.
    pub gps_pos_v: f64,
    /// GPS velocity noise, m/s.
    pub gps_vel: f64,
    /// Barometer noise, m.
    pub baro: f64,
}

impl Default for FilterNoise {
    fn default() -> Self {
        FilterNoise {
            accel: 0.2,
            cv_accel: 3.0,
            accel_bias_rw: 0.001,
            baro_rw: 0.05,
            gps_pos_h: 1.0,
            gps_pos_v: 1.5,
            gps_vel: 0.15,
            baro: 0.5,
        }
    }
}

/// Why the filter refused to go on.
#[derive(Clone, Debug, PartialEq)]
pub enum FilterError {
    /// `P` lost finiteness or positive diagonal; holds the offending index.
    CovarianceUnhealthy(usize),
    /// A non-finite input reached the filter.
    NonFinite(&'static str),
}

impl core::fmt::Display for FilterError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            FilterError::CovarianceUnhealthy(i) => {
                write!(f, "Kalman covariance unhealthy at state {i} (non-finite or negative variance)")
            }
            FilterError::NonFinite(what) => {
                write!(f, "non-finite {what} reached the Kalman filter")
            }
        }
    }
}

/// Specific-force input for one prediction step.
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
pub struct ImuInput {
    /// Specific force, body FRD, m/s².
    pub f_body: Vector3<f64>,
    /// Attitude body -> NED.
    pub q: UnitQuaternion<f64>,
}

/// Result of one measurement update (or of a rejected one): the innovation
/// `nu = y - H x⁻` and its variance `S = H P⁻ Hᵀ + R`, per scalar channel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Innovation<const M: usize> {
    /// Innovation `nu = y - H x⁻` per channel (the measurement's unit).
    pub nu: [f64; M],
    /// Its variance `S = H P⁻ Hᵀ + R` per channel (unit squared).
    pub s: [f64; M],
}

impl<const M: usize> Default for Innovation<M> {
    fn default() -> Self {
        Innovation { nu: [0.0; M], s: [0.0; M] }
    }
}

/// Covariance transition accumulated since the last [`Kf::flush`].
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
struct Pending {
    /// Elapsed time, s.
    t: f64,
    /// Position and velocity sensitivity to the accelerometer bias.
    phi_pb: Matrix3<f64>,
    phi_vb: Matrix3<f64>,
    /// p–v process noise per axis (pp, pv, vv), bias and baro noise.
    q11: f64,
    q12: f64,
    q22: f64,
    qb: f64,
    qbaro: f64,
}

impl Default for Pending {
    fn default() -> Self {
        Pending {
            t: 0.0,
            phi_pb: Matrix3::zeros(),
            phi_vb: Matrix3::zeros(),
            q11: 0.0,
            q12: 0.0,
            q22: 0.0,
            qb: 0.0,
            qbaro: 0.0,
        }
    }
}

/// The filter.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Kf {
    x: StateVec,
    /// State covariance, current after any innovation or update call (or
    /// [`Kf::flush`]); between predictions and the next measurement it lags.
    /// Read through the accessors below, which name what they return.
    P: StateMat,
    noise: FilterNoise,
    baro_initialised: bool,
    pending: Pending,
    /// Hold the accelerometer-bias estimate: updates leave it (and its
    /// covariance) alone, as a "consider" state. Set while the IMU itself is
    /// suspected, so the filter does not learn a fault as the sensor's bias
    /// and carry that error past the fault's end.
    hold_bias: bool,
    /// Accelerometer noise learnt in flight, as a density (m/s²)²·s: the
    /// airframe's vibration as the IMU sampled it. Added to the configured
    /// density, so the prediction's covariance is as honest about a
    /// vibrating or snapshot-sampled IMU as about a quiet one, whatever its
    /// rate (a density, not a per-sample variance).
    #[serde(default)]
    accel_psd: f64,
}

impl Kf {
    /// Start at position `p` (NED, m) and velocity `v` (m/s) with the given
    /// 1-sigma uncertainties.
    pub fn new(noise: FilterNoise, p: Vector3<f64>, v: Vector3<f64>, p_sigma: f64, v_sigma: f64) -> Self {
        let mut x = StateVec::zeros();
        x.fixed_rows_mut::<3>(IP).copy_from(&p);
        x.fixed_rows_mut::<3>(IV).copy_from(&v);
        let mut P = StateMat::zeros();
        for i in 0..3 {
            P[(IP + i, IP + i)] = p_sigma * p_sigma;
            P[(IV + i, IV + i)] = v_sigma * v_sigma;
            P[(IB + i, IB + i)] = 0.05 * 0.05;
        }
        P[(IBARO, IBARO)] = 100.0;
        Kf { x, P, noise, baro_initialised: false, pending: Pending::default(), hold_bias: false, accel_psd: 0.0 }
    }

    /// Set the learnt accelerometer noise density, (m/s²)²·s (see
    /// `accel_psd`); a negative or non-finite value is ignored.
    pub fn set_accel_psd(&mut self, psd: f64) {
        if psd.is_finite() && psd >= 0.0 {
            self.accel_psd = psd;
        }
    }

    /// Hold (or release) the accelerometer-bias estimate (see `hold_bias`).
    pub fn set_hold_bias(&mut self, hold: bool) {
        self.hold_bias = hold;
    }

    /// Estimated position NED, m.
    pub fn position(&self) -> Vector3<f64> {
        self.x.fixed_rows::<3>(IP).into_owned()
    }

    /// Estimated velocity NED, m/s.
    pub fn velocity(&self) -> Vector3<f64> {
        self.x.fixed_rows::<3>(IV).into_owned()
    }

    /// Estimated accelerometer bias, body frame, m/s².
    pub fn accel_bias(&self) -> Vector3<f64> {
        self.x.fixed_rows::<3>(IB).into_owned()
    }

    /// Set the accelerometer-bias estimate, body frame, m/s² (its
    /// covariance stays): an IMU episode rolls the fault back off it.
    pub fn set_accel_bias(&mut self, b: &Vector3<f64>) {
        self.x.fixed_rows_mut::<3>(IB).copy_from(b);
    }

    /// The barometer reading the state predicts: altitude up plus the baro
    /// offset, m.
    pub fn baro_height(&self) -> f64 {
        -self.x[IP + 2] + self.x[IBARO]
    }

    /// Variance of [`Kf::baro_height`], m² (`H P Hᵀ` with `H = [-1 at pD, 1 at
    /// the offset]`). Like every covariance read, current only after an
    /// innovation or update call.
    pub fn baro_height_var(&self) -> f64 {
        self.P[(IP + 2, IP + 2)] + self.P[(IBARO, IBARO)] - 2.0 * self.P[(IP + 2, IBARO)]
    }

    /// Variance of position axis `axis` (0..3, NED), m².
    pub fn position_var(&self, axis: usize) -> f64 {
        self.P[(IP + axis, IP + axis)]
    }

    /// Variance of velocity axis `axis` (0..3, NED), (m/s)².
    pub fn velocity_var(&self, axis: usize) -> f64 {
        self.P[(IV + axis, IV + axis)]
    }

    /// The position–velocity block of `P` (position N/E/D then velocity
    /// N/E/D).
    pub fn pos_vel_covariance(&self) -> SMatrix<f64, 6, 6> {
        self.P.fixed_view::<6, 6>(IP, IP).into_owned()
    }

    /// Propagate by `dt` s. With `imu`, strapdown mechanisation in NED
    /// (flat earth: a few km around the anchor); without, constant velocity.
    ///
    /// The state moves at once; the covariance does not. Its transition is
    /// accumulated in closed form (the p–v block is time-invariant and the
    /// bias coupling composes as 3×3 sums), and `P = Φ P Φᵀ + Q` runs once
    /// when a measurement needs `P` ([`Kf::flush`]). That turns a 10×10
    /// product per IMU sample into one per GPS or baro update, the same
    /// result up to the bias-noise-to-velocity coupling inside one interval.
    pub fn predict(&mut self, dt: f64, imu: Option<&ImuInput>) -> Result<(), FilterError> {
        if !dt.is_finite() || dt < 0.0 {
            return Err(FilterError::NonFinite("time step"));
        }
        if dt == 0.0 {
            return Ok(());
        }
        let dt2 = dt * dt;
        let q_acc;
        let pd = &mut self.pending;
        match imu {
            Some(u) => {
                let C: Matrix3<f64> = u.q.to_rotation_matrix().into_inner();
                let f = u.f_body - self.x.fixed_rows::<3>(IB);
                let a = C * f + Vector3::new(0.0, 0.0, GRAVITY);
                if !a.iter().all(|v| v.is_finite()) {
                    return Err(FilterError::NonFinite("acceleration"));
                }
                let v0 = self.x.fixed_rows::<3>(IV).into_owned();
                let p = self.x.fixed_rows::<3>(IP) + v0 * dt + a * (0.5 * dt2);
                self.x.fixed_rows_mut::<3>(IP).copy_from(&p);
                self.x.fixed_rows_mut::<3>(IV).copy_from(&(v0 + a * dt));
                // Compose the step's transition onto the pending one.
                pd.phi_pb += pd.phi_vb * dt - C * (0.5 * dt2);
                pd.phi_vb -= C * dt;
                q_acc = self.noise.accel * self.noise.accel + self.accel_psd;
                pd.qb += self.noise.accel_bias_rw * self.noise.accel_bias_rw * dt;
            }
            None => {
                let p = self.x.fixed_rows::<3>(IP) + self.x.fixed_rows::<3>(IV) * dt;
                self.x.fixed_rows_mut::<3>(IP).copy_from(&p);
                pd.phi_pb += pd.phi_vb * dt;
                q_acc = self.noise.cv_accel * self.noise.cv_accel;
            }
        }
        // White-acceleration noise on p–v, composed exactly per axis.
        pd.q11 += 2.0 * dt * pd.q12 + dt2 * pd.q22 + q_acc * dt2 * dt / 3.0;
        pd.q12 += dt * pd.q22 + q_acc * dt2 / 2.0;
        pd.q22 += q_acc * dt;
        pd.qbaro += self.noise.baro_rw * self.noise.baro_rw * dt;
        pd.t += dt;
        if !self.x.iter().all(|v| v.is_finite()) {
            return Err(FilterError::NonFinite("state"));
        }
        Ok(())
    }

    /// Apply the accumulated covariance propagation (see [`Kf::predict`]).
    pub fn flush(&mut self) -> Result<(), FilterError> {
        let pd = core::mem::take(&mut self.pending);
        if pd.t == 0.0 {
            return Ok(());
        }
        // Φ = I + E with E nonzero only in the (p,v), (p,b), (v,b) blocks, so
        // Φ P Φᵀ = P + M + Mᵀ + M Eᵀ with M = E P (rows 0..6 only): about a
        // third of the work of two dense 10×10 products.
        let mut m = [[0.0f64; N]; 6];
        for j in 0..N {
            for i in 0..3 {
                let mut acc = pd.t * self.P[(IV + i, j)];
                let mut accv = 0.0;
                for k in 0..3 {
                    acc += pd.phi_pb[(i, k)] * self.P[(IB + k, j)];
                    accv += pd.phi_vb[(i, k)] * self.P[(IB + k, j)];
                }
                m[i][j] = acc;
                m[3 + i][j] = accv;
            }
        }
        // P + M + Mᵀ + M Eᵀ by region, in place (M holds everything read
        // from the old P), each entry summed in the order
        // m[i][j] + m[j][i] + Σ_k m[i][k] E[j][k] (E's nonzero entries only:
        // row j < 3 has t at column 3 + j and phi_pb in 6..9, rows 3..6 have
        // phi_vb in 6..9), so no structural zero is multiplied.
        let P = &mut self.P;
        for i in 0..6 {
            for j in 0..3 {
                let mut v = m[i][j] + m[j][i];
                v += m[i][3 + j] * pd.t;
                for k in 0..3 {
                    v += m[i][6 + k] * pd.phi_pb[(j, k)];
                }
                P[(i, j)] += v;
            }
            for j in 3..6 {
                let mut v = m[i][j] + m[j][i];
                for k in 0..3 {
                    v += m[i][6 + k] * pd.phi_vb[(j - 3, k)];
                }
                P[(i, j)] += v;
            }
            for j in 6..N {
                P[(i, j)] += m[i][j];
                P[(j, i)] += m[i][j];
            }
        }
        for i in 0..3 {
            P[(IP + i, IP + i)] += pd.q11;
            P[(IP + i, IV + i)] += pd.q12;
            P[(IV + i, IP + i)] += pd.q12;
            P[(IV + i, IV + i)] += pd.q22;
            P[(IB + i, IB + i)] += pd.qb;
        }
        P[(IBARO, IBARO)] += pd.qbaro;
        // Symmetrise once per propagation (the scalar updates keep symmetry
        // term by term, up to rounding): (a + b)/2 into both halves.
        for i in 0..N {
            for j in i + 1..N {
                let v = (P[(i, j)] + P[(j, i)]) * 0.5;
                P[(i, j)] = v;
                P[(j, i)] = v;
            }
        }
        self.check_health()
    }

    /// Predicted GPS position innovation without updating.
    pub fn position_innovation(&mut self, y: &Vector3<f64>) -> Innovation<3> {
        self.flush_or_poison();
        let r = [self.noise.gps_pos_h, self.noise.gps_pos_h, self.noise.gps_pos_v];
        let mut out = Innovation::<3>::default();
        for i in 0..3 {
            out.nu[i] = y[i] - self.x[IP + i];
            out.s[i] = self.P[(IP + i, IP + i)] + r[i] * r[i];
        }
        out
    }

    /// Predicted GPS velocity innovation without updating.
    pub fn velocity_innovation(&mut self, y: &Vector3<f64>) -> Innovation<3> {
        self.flush_or_poison();
        let r = self.noise.gps_vel;
        let mut out = Innovation::<3>::default();
        for i in 0..3 {
            out.nu[i] = y[i] - self.x[IV + i];
            out.s[i] = self.P[(IV + i, IV + i)] + r * r;
        }
        out
    }

    /// Predicted barometer innovation (baro is altitude up: -pD + offset).
    pub fn baro_innovation(&mut self, baro: f64) -> Innovation<1> {
        self.flush_or_poison();
        let r = self.noise.baro;
        Innovation { nu: [baro - self.baro_height()], s: [self.baro_height_var() + r * r] }
    }

    /// GPS position update (m, NED).
    pub fn update_position(&mut self, y: &Vector3<f64>) -> Result<(), FilterError> {
        self.update_position_scaled(y, 1.0)
    }

    /// GPS position update (m, NED) with the measurement σ multiplied by
    /// `k` (≥ 1: the receiver says this fix is `k` times worse than usual).
    pub fn update_position_scaled(&mut self, y: &Vector3<f64>, k: f64) -> Result<(), FilterError> {
        let r = [self.noise.gps_pos_h, self.noise.gps_pos_h, self.noise.gps_pos_v].map(|r| r * k);
        for i in 0..3 {
            self.scalar_update(&[(IP + i, 1.0)], y[i], r[i] * r[i])?;
        }
        self.check_health()
    }

    /// GPS velocity update (m/s, NED).
    pub fn update_velocity(&mut self, y: &Vector3<f64>) -> Result<(), FilterError> {
        self.update_velocity_scaled(y, 1.0)
    }

    /// GPS velocity update (m/s, NED), σ multiplied by `k` as in
    /// [`Kf::update_position_scaled`].
    pub fn update_velocity_scaled(&mut self, y: &Vector3<f64>, k: f64) -> Result<(), FilterError> {
        let r = self.noise.gps_vel * k;
        for i in 0..3 {
            self.scalar_update(&[(IV + i, 1.0)], y[i], r * r)?;
        }
        self.check_health()
    }

    /// Barometer update (m, altitude up). The first one fixes the offset
    /// between barometric and GPS altitude, since they share no datum.
    pub fn update_baro(&mut self, baro: f64) -> Result<(), FilterError> {
        if !baro.is_finite() {
            return Err(FilterError::NonFinite("baro"));
        }
        self.flush()?;
        if !self.baro_initialised {
            self.x[IBARO] = baro + self.x[IP + 2];
            self.P[(IBARO, IBARO)] = self.P[(IP + 2, IP + 2)] + self.noise.baro * self.noise.baro;
            self.baro_initialised = true;
            return Ok(());
        }
        self.scalar_update(&[(IP + 2, -1.0), (IBARO, 1.0)], baro, self.noise.baro * self.noise.baro)?;
        self.check_health()
    }

    /// Re-anchor the barometer offset at the next baro sample (after a
    /// baro fault the offset state holds whatever it absorbed).
    pub fn reset_baro(&mut self) {
        self.baro_initialised = false;
    }

    /// Whether the barometer offset has been set from a first baro reading
    /// (since the start or the last [`Kf::reset_baro`]).
    pub fn baro_initialised(&self) -> bool {
        self.baro_initialised
    }

    /// Move position and velocity onto a measurement (after a long coast),
    /// keeping biases; position/velocity uncertainty reset to the sensor's.
    pub fn reset_to(&mut self, p: &Vector3<f64>, v: Option<&Vector3<f64>>) {
        self.flush_or_poison();
        for i in 0..3 {
            self.x[IP + i] = p[i];
            if let Some(v) = v {
                self.x[IV + i] = v[i];
            }
        }
        for i in 0..6 {
            for j in 0..N {
                if i != j {
                    self.P[(i, j)] = 0.0;
                    self.P[(j, i)] = 0.0;
                }
            }
        }
        let (h, vv) = (self.noise.gps_pos_h, self.noise.gps_pos_v);
        self.P[(0, 0)] = h * h;
        self.P[(1, 1)] = h * h;
        self.P[(2, 2)] = vv * vv;
        let sv = if v.is_some() { self.noise.gps_vel } else { 3.0 };
        for i in 3..6 {
            self.P[(i, i)] = sv * sv;
        }
        self.baro_initialised = false;
    }

    /// Flush for a read-only query; a failure leaves `P` non-finite so the
    /// next update reports it as an error.
    fn flush_or_poison(&mut self) {
        if self.flush().is_err() {
            self.P[(0, 0)] = f64::NAN;
        }
    }

    /// One scalar update `y = hᵀx + e`, `e ~ N(0, r)`, Joseph form, with the
    /// sparse `h` given as (state index, coefficient) pairs. Not built for
    /// size: that takes 2.6 KB off the core module but costs 10% of
    /// `pushColumns` (session 18, README "Speed and size").
    fn scalar_update(&mut self, h: &[(usize, f64)], y: f64, r: f64) -> Result<(), FilterError> {
        self.flush()?;
        if !y.is_finite() {
            return Err(FilterError::NonFinite("measurement"));
        }
        let mut ph = [0.0; N];
        let mut hx = 0.0;
        for &(j, c) in h {
            for (i, v) in ph.iter_mut().enumerate() {
                *v += c * self.P[(i, j)];
            }
            hx += c * self.x[j];
        }
        let s: f64 = h.iter().map(|&(j, c)| c * ph[j]).sum::<f64>() + r;
        if !(s.is_finite() && s > 0.0) {
            return Err(FilterError::CovarianceUnhealthy(0));
        }
        let held = |i: usize| self.hold_bias && (IB..IB + 3).contains(&i);
        let k: [f64; N] = core::array::from_fn(|i| if held(i) { 0.0 } else { ph[i] / s });
        let nu = y - hx;
        for i in 0..N {
            self.x[i] += k[i] * nu;
        }
        // Joseph form (I−khᵀ)P(I−khᵀ)ᵀ + r kkᵀ, expanded for a scalar
        // measurement: P − k phᵀ − ph kᵀ + s kkᵀ with ph = Ph, s = hᵀPh + r.
        // It holds for any gain, so zeroing the held bias rows keeps P exact.
        // Symmetric term by term: the upper triangle is computed and mirrored,
        // O(n²) instead of two n³ products.
        for i in 0..N {
            for j in i..N {
                let v = self.P[(i, j)] + s * k[i] * k[j] - k[i] * ph[j] - ph[i] * k[j];
                self.P[(i, j)] = v;
                self.P[(j, i)] = v;
            }
        }
        Ok(())
    }

    /// Check `P` and `x`: positive finite variances, finite state. A NaN
    /// off the diagonal reaches a variance or an innovation variance at the
    /// next update, which reports it then. Built for size (issue 15's
    /// budget): a loop over the diagonal, which opt-level 3 unrolled into
    /// 1.1 KB.
    #[cfg_attr(navguard_cold_size, optimize(size))]
    #[inline(never)]
    fn check_health(&mut self) -> Result<(), FilterError> {
        for i in 0..N {
            let d = self.P[(i, i)];
            if !(d.is_finite() && d > 0.0) {
                return Err(FilterError::CovarianceUnhealthy(i));
            }
        }
        if !self.x.iter().all(|v| v.is_finite()) {
            return Err(FilterError::CovarianceUnhealthy(0));
        }
        Ok(())
    }
}

/// Quaternion from the contract's (w, x, y, z), normalised. `None` when the
/// norm is far from 1 (not an attitude).
pub fn quat_from_wxyz(w: f64, x: f64, y: f64, z: f64) -> Option<UnitQuaternion<f64>> {
    let q = Quaternion::new(w, x, y, z);
    let n = q.norm();
    if !(n.is_finite() && (0.5..=1.5).contains(&n)) {
        return None;
    }
    Some(UnitQuaternion::from_quaternion(q))
}

#[cfg(all(test, not(target_arch = "wasm32")))]
mod tests {
    use super::*;
    use approx::assert_abs_diff_eq;
    use proptest::prelude::*;

    fn level() -> UnitQuaternion<f64> {
        UnitQuaternion::identity()
    }

    #[test]
    fn hover_specific_force_cancels_gravity() {
        let mut kf = Kf::new(FilterNoise::default(), Vector3::zeros(), Vector3::zeros(), 1.0, 0.1);
        let imu = ImuInput { f_body: Vector3::new(0.0, 0.0, -GRAVITY), q: level() };
        for _ in 0..100 {
            kf.predict(0.01, Some(&imu)).unwrap();
        }
        assert_abs_diff_eq!(kf.velocity().norm(), 0.0, epsilon = 1e-12);
        assert_abs_diff_eq!(kf.position().norm(), 0.0, epsilon = 1e-12);
    }

    #[test]
    fn forward_acceleration_integrates() {
        // 1 m/s² forward for 2 s, body yawed 90° (nose east): east velocity 2 m/s, 2 m east.
        let q = UnitQuaternion::from_euler_angles(0.0, 0.0, core::f64::consts::FRAC_PI_2);
        let mut kf = Kf::new(FilterNoise::default(), Vector3::zeros(), Vector3::zeros(), 1.0, 0.1);
        let imu = ImuInput { f_body: Vector3::new(1.0, 0.0, -GRAVITY), q };
        for _ in 0..200 {
            kf.predict(0.01, Some(&imu)).unwrap();
        }
        assert_abs_diff_eq!(kf.velocity()[1], 2.0, epsilon = 1e-9);
        assert_abs_diff_eq!(kf.velocity()[0], 0.0, epsilon = 1e-9);
        assert_abs_diff_eq!(kf.position()[1], 2.0, epsilon = 1e-9);
    }

    #[test]
    fn scalar_update_matches_closed_form() {
        // Prior var 4, meas var 1 at offset 5: gain 0.8, posterior 4, var 0.8.
        let mut kf = Kf::new(
            FilterNoise { gps_pos_h: 1.0, ..FilterNoise::default() },
            Vector3::zeros(),
            Vector3::zeros(),
            2.0,
            0.1,
        );
        let inn = kf.position_innovation(&Vector3::new(5.0, 0.0, 0.0));
        assert_abs_diff_eq!(inn.nu[0], 5.0);
        assert_abs_diff_eq!(inn.s[0], 5.0);
        kf.update_position(&Vector3::new(5.0, 0.0, 0.0)).unwrap();
        assert_abs_diff_eq!(kf.position()[0], 4.0, epsilon = 1e-12);
        assert_abs_diff_eq!(kf.P[(0, 0)], 0.8, epsilon = 1e-12);
    }

    #[test]
    fn cv_model_covariance_growth() {
        // Constant-velocity: var(p) grows by q dt³/3 + dt² var(v).
        let noise = FilterNoise { cv_accel: 2.0, ..FilterNoise::default() };
        let mut kf = Kf::new(noise, Vector3::zeros(), Vector3::new(1.0, 0.0, 0.0), 1.0, 0.5);
        kf.predict(0.25, None).unwrap();
        kf.predict(0.75, None).unwrap();
        kf.flush().unwrap();
        assert_abs_diff_eq!(kf.position()[0], 1.0, epsilon = 1e-12);
        assert_abs_diff_eq!(kf.P[(0, 0)], 1.0 + 0.25 + 4.0 / 3.0, epsilon = 1e-12);
        assert_abs_diff_eq!(kf.P[(3, 3)], 0.25 + 4.0, epsilon = 1e-12);
    }

    #[test]
    fn deferred_propagation_equals_stepwise() {
        // With no bias random walk the accumulated transition is exact.
        let noise = FilterNoise { accel_bias_rw: 0.0, ..FilterNoise::default() };
        let mut a = Kf::new(noise, Vector3::zeros(), Vector3::new(3.0, 1.0, 0.0), 1.0, 0.3);
        let mut b = a.clone();
        for k in 0..50 {
            let q = UnitQuaternion::from_euler_angles(0.1 * (k as f64).sin(), 0.2, 0.05 * k as f64);
            let imu = ImuInput { f_body: Vector3::new(0.5, -0.2, -9.7), q };
            let u = if k % 7 == 3 { None } else { Some(&imu) };
            a.predict(0.02, u).unwrap();
            b.predict(0.02, u).unwrap();
            b.flush().unwrap();
        }
        a.flush().unwrap();
        assert!((a.P - b.P).abs().max() < 1e-12, "max diff {}", (a.P - b.P).abs().max());
        assert_eq!(a.x, b.x);
    }

    #[test]
    fn structured_flush_equals_dense_phi_p_phit() {
        let mut kf = Kf::new(FilterNoise::default(), Vector3::zeros(), Vector3::new(1.0, 2.0, 0.5), 2.0, 0.5);
        // A full, correlated P to exercise every block.
        for i in 0..N {
            for j in 0..N {
                kf.P[(i, j)] += 0.01 * ((i * 7 + j * 3) % 5) as f64 * if i == j { 10.0 } else { 1.0 };
            }
        }
        kf.P = (kf.P + kf.P.transpose()) * 0.5;
        let p0 = kf.P;
        let q = UnitQuaternion::from_euler_angles(0.2, -0.1, 1.0);
        let imu = ImuInput { f_body: Vector3::new(0.3, 0.1, -9.9), q };
        kf.predict(0.05, Some(&imu)).unwrap();
        kf.predict(0.05, Some(&imu)).unwrap();
        let pd = kf.pending;
        kf.flush().unwrap();
        let mut F = StateMat::identity();
        let mut Q = StateMat::zeros();
        for i in 0..3 {
            F[(i, 3 + i)] = pd.t;
            Q[(i, i)] = pd.q11;
            Q[(i, 3 + i)] = pd.q12;
            Q[(3 + i, i)] = pd.q12;
            Q[(3 + i, 3 + i)] = pd.q22;
            Q[(6 + i, 6 + i)] = pd.qb;
        }
        Q[(9, 9)] = pd.qbaro;
        F.fixed_view_mut::<3, 3>(0, 6).copy_from(&pd.phi_pb);
        F.fixed_view_mut::<3, 3>(3, 6).copy_from(&pd.phi_vb);
        let dense = F * p0 * F.transpose() + Q;
        assert!((kf.P - dense).abs().max() < 1e-12, "{}", (kf.P - dense).abs().max());
        // Closed form of the bias sensitivity for constant C over 0.1 s.
        let C = q.to_rotation_matrix().into_inner();
        assert!((pd.phi_vb + C * 0.1).abs().max() < 1e-15);
        assert!((pd.phi_pb + C * 0.005).abs().max() < 1e-15);
    }

    #[test]
    fn held_bias_is_left_alone_and_p_is_the_joseph_form_of_that_gain() {
        let mut kf = Kf::new(FilterNoise::default(), Vector3::zeros(), Vector3::zeros(), 2.0, 0.5);
        let imu = ImuInput { f_body: Vector3::new(0.3, -0.2, -9.81), q: level() };
        kf.predict(1.0, Some(&imu)).unwrap();
        kf.flush().unwrap();
        kf.set_hold_bias(true);
        let (x0, p0) = (kf.x, kf.P);
        kf.update_velocity(&Vector3::new(0.4, 0.0, 0.0)).unwrap();
        // Bias and its covariance untouched; velocity N moved towards 0.4.
        for i in IB..IB + 3 {
            assert_eq!(kf.x[i], x0[i]);
            for j in IB..IB + 3 {
                assert_abs_diff_eq!(kf.P[(i, j)], p0[(i, j)], epsilon = 1e-15);
            }
        }
        assert!(kf.x[IV] > x0[IV] + 0.01, "velocity {} -> {}", x0[IV], kf.x[IV]);
        // The first scalar update against the dense Joseph form with the
        // bias rows of K zeroed: (I − khᵀ)P(I − khᵀ)ᵀ + r kkᵀ.
        let mut kf1 = Kf::new(FilterNoise::default(), Vector3::zeros(), Vector3::zeros(), 2.0, 0.5);
        kf1.predict(1.0, Some(&imu)).unwrap();
        kf1.flush().unwrap();
        kf1.set_hold_bias(true);
        let p = kf1.P;
        let r = kf1.noise.gps_vel * kf1.noise.gps_vel;
        let mut h = StateVec::zeros();
        h[IV] = 1.0;
        let mut k = p * h / (h.dot(&(p * h)) + r);
        for i in IB..IB + 3 {
            k[i] = 0.0;
        }
        let a = StateMat::identity() - k * h.transpose();
        let dense = a * p * a.transpose() + k * k.transpose() * r;
        kf1.scalar_update(&[(IV, 1.0)], 0.4, r).unwrap();
        assert!((kf1.P - dense).abs().max() < 1e-12, "{}", (kf1.P - dense).abs().max());
        // Without the hold the same update moves the bias.
        let mut kf2 = Kf::new(FilterNoise::default(), Vector3::zeros(), Vector3::zeros(), 2.0, 0.5);
        kf2.predict(1.0, Some(&imu)).unwrap();
        kf2.update_velocity(&Vector3::new(0.4, 0.0, 0.0)).unwrap();
        assert!((kf2.accel_bias() - x0.fixed_rows::<3>(IB)).norm() > 1e-4);
    }

    #[test]
    fn non_finite_input_is_an_error_not_a_panic() {
        let mut kf = Kf::new(FilterNoise::default(), Vector3::zeros(), Vector3::zeros(), 1.0, 0.1);
        assert!(kf.predict(f64::NAN, None).is_err());
        assert!(kf.update_position(&Vector3::new(f64::NAN, 0.0, 0.0)).is_err());
        let imu = ImuInput { f_body: Vector3::new(1e308, 1e308, 1e308), q: level() };
        assert!(kf.predict(1e10, Some(&imu)).is_err());
    }

    proptest! {
        #[test]
        fn covariance_stays_symmetric_psd(
            steps in proptest::collection::vec((0.001f64..0.5, -20.0f64..20.0, -20.0f64..20.0, -30.0f64..10.0, 0u8..4), 1..120),
            yaw in -3.2f64..3.2, pitch in -0.8f64..0.8,
            hold_mask in proptest::prelude::any::<u64>(),
        ) {
            let mut kf = Kf::new(FilterNoise::default(), Vector3::zeros(), Vector3::zeros(), 3.0, 1.0);
            let q = UnitQuaternion::from_euler_angles(0.1, pitch, yaw);
            for (i, (dt, a, b, c, kind)) in steps.into_iter().enumerate() {
                // The bias hold (a suboptimal gain) must keep P valid too.
                kf.set_hold_bias((hold_mask >> (i % 64)) & 1 == 1);
                let imu = ImuInput { f_body: Vector3::new(a, b, c), q };
                kf.predict(dt, if kind == 3 { None } else { Some(&imu) }).unwrap();
                match kind {
                    0 => kf.update_position(&Vector3::new(a, b, c)).unwrap(),
                    1 => kf.update_velocity(&Vector3::new(b, a, 0.1 * c)).unwrap(),
                    2 => kf.update_baro(c).unwrap(),
                    _ => {}
                }
                let P = kf.P;
                prop_assert!((P - P.transpose()).abs().max() <= 1e-9 * P.abs().max().max(1.0));
                let eig = P.symmetric_eigen();
                prop_assert!(eig.eigenvalues.min() > -1e-9 * P.abs().max().max(1.0), "min eig {}", eig.eigenvalues.min());
            }
        }
    }
}

/// The snapshot codec of this file's state types ([`crate::codec`]): each
/// struct's fields in declaration order (a field left out does not compile;
/// `skip`: not saved, rebuilt on restore).
mod codec_impls {
    use super::*;
    use crate::codec::impl_codec;

    impl_codec!(FilterNoise { accel, cv_accel, accel_bias_rw, baro_rw, gps_pos_h, gps_pos_v, gps_vel, baro });
    impl_codec!(ImuInput { f_body, q });
    impl_codec!(Pending { t, phi_pb, phi_vb, q11, q12, q22, qb, qbaro });
    impl_codec!(Kf { x, P, noise, baro_initialised, pending, hold_bias, accel_psd });
}
