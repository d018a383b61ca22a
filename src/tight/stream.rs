//! Streaming API: [`TightDetector`] takes raw rows (time, IMU, per-satellite
//! pseudo-ranges) one at a time and returns a status per row plus the faulty
//! satellite's id. Plain serde structs in and out, so a wasm facade can pass
//! them through `serde-wasm-bindgen` unchanged.
//!
//! Row format (CSV, one row per IMU sample; see `docs/tight.md`):
//!
//! | column | unit | meaning |
//! |---|---|---|
//! | `t` | s | receiver time, strictly increasing |
//! | `gx`,`gy`,`gz` | rad/s | gyro, body forward-right-down |
//! | `ax`,`ay`,`az` | m/s² | specific force, body (level and still: `az` = −9.81) |
//! | `pr_<prn>` | m | pseudo-range of satellite `<prn>` (1..=n_sats); empty or `NaN` = not tracked this row |
//!
//! The IMU reading of a row applies over the interval from the previous row
//! to this one. A row with at least one pseudo-range is a GNSS epoch: the
//! time update runs first, then detection and the measurement update.

use nalgebra::{Matrix4, UnitQuaternion, Vector3, Vector4};
use serde::{Deserialize, Serialize};

use super::constellation::{Constellation, Site};
use super::fdi::{Action, FdsrConfig, FilterPredictor, RangePredictor, Reconfigurator, Strategy};
use super::gan_fdsr::{default_model, GanDetectorModel};
pub use super::rows::{parse_csv, to_csv, EpochRow, InitialState, PrObs};
use super::tc_ekf::{EkfConfig, NavState, PrMeas, TcEkf};
use super::TightError;

/// Detector configuration. Every field has a default (serde `default`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct TightConfig {
    /// Site latitude, longitude (deg), height (m): origin of the NED frame.
    pub site: [f64; 3],
    /// Satellites in the (simulated) almanac, 24..=31.
    pub n_sats: usize,
    /// Constellation time at row time 0, s (satellite positions come from
    /// the almanac at `t0 + t`).
    pub t0: f64,
    /// Detection and reconfiguration: `none`, `fdi`, `fda`, `switch` or
    /// `gan` (GAN-FDSR); `method` is accepted as another name.
    #[serde(alias = "method")]
    pub strategy: Strategy,
    /// False-alarm rate α of the λ test.
    pub alpha: f64,
    /// RDPOP threshold η.
    pub eta: f64,
    /// Filter noise and initial uncertainty.
    pub ekf: EkfConfig,
    /// Known initial state (else a least-squares fix).
    pub initial: Option<InitialState>,
    /// Initial velocity without `initial`, NED, m/s.
    pub initial_velocity_ned: [f64; 3],
    /// Initial yaw without `initial`, deg.
    pub initial_yaw_deg: f64,
}

impl Default for TightConfig {
    fn default() -> Self {
        let o = crate::sim::ORIGIN;
        TightConfig {
            site: [o.0, o.1, o.2],
            n_sats: 31,
            t0: 0.0,
            strategy: Strategy::Switch,
            alpha: 0.001,
            eta: 0.035,
            ekf: EkfConfig::default(),
            initial: None,
            initial_velocity_ned: [0.0; 3],
            initial_yaw_deg: 0.0,
        }
    }
}

/// Per-row status.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Status {
    /// Waiting for a row with ≥ 4 pseudo-ranges to start.
    Initializing,
    /// IMU-only row: time update.
    NoGnss,
    /// GNSS epoch, no fault detected.
    Ok,
    /// GNSS epoch with a faulty satellite (`faulty_prn`).
    Fault,
}

/// Per-row output.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EpochOutput {
    /// Row time, s.
    pub t: f64,
    /// Status of the row.
    pub status: Status,
    /// The satellite flagged faulty at this epoch.
    pub faulty_prn: Option<u8>,
    /// Its test statistic (λ, or the predictor consistency statistic while
    /// the switch keeps it under repair).
    pub statistic: Option<f64>,
    /// Largest |λ| over the epoch's satellites.
    pub lambda_max: f64,
    /// RDPOP of the flagged satellite.
    pub rdpop: Option<f64>,
    /// What was done with the epoch's measurements (GNSS epochs only).
    pub action: Option<Action>,
    /// GAN-FDSR only: the largest GAN score of the epoch (T2 is the model's
    /// threshold); `None` for other strategies or while windows fill.
    #[serde(default)]
    pub gan_score_max: Option<f64>,
    /// Pseudo-ranges at this row.
    pub n_sats: usize,
    /// Estimated position, NED, m.
    pub position_ned: [f64; 3],
    /// Estimated velocity, NED, m/s.
    pub velocity_ned: [f64; 3],
    /// Estimated clock bias, m.
    pub clock_bias_m: f64,
}

/// The streaming detector.
pub struct TightDetector {
    cfg: TightConfig,
    constellation: Constellation,
    site: Site,
    ekf: Option<TcEkf>,
    fdsr: Reconfigurator,
    last_t: Option<f64>,
}

impl TightDetector {
    /// With the filter's own prediction as reconstruction predictor.
    pub fn new(cfg: TightConfig) -> Result<Self, TightError> {
        let var = cfg.ekf.sigma_pr * cfg.ekf.sigma_pr;
        Self::with_predictor(cfg, Box::new(FilterPredictor::new(var)))
    }

    /// With another reconstruction predictor (e.g. a GAN generator).
    pub fn with_predictor(cfg: TightConfig, predictor: Box<dyn RangePredictor>) -> Result<Self, TightError> {
        cfg.ekf.check()?;
        let constellation = Constellation::gps_like(cfg.n_sats)?;
        let site = Site::new(cfg.site[0], cfg.site[1], cfg.site[2])?;
        if !cfg.t0.is_finite() {
            return Err(TightError::new("t0", format!("must be finite, got {}", cfg.t0)));
        }
        let gan = if cfg.strategy == Strategy::Gan { Some(default_model()?) } else { None };
        let fdsr = Reconfigurator::new(FdsrConfig { strategy: cfg.strategy, alpha: cfg.alpha, eta: cfg.eta }, predictor, gan)?;
        let mut d = TightDetector { cfg, constellation, site, ekf: None, fdsr, last_t: None };
        if let Some(init) = d.cfg.initial {
            d.ekf = Some(d.filter_from(&init)?);
            d.last_t = Some(init.t);
        }
        Ok(d)
    }

    /// GAN-FDSR with a given model (e.g. trained by `tightGanTrain`) in place
    /// of the embedded default; `cfg.strategy` is set to `gan`.
    pub fn with_gan(mut cfg: TightConfig, model: GanDetectorModel) -> Result<Self, TightError> {
        cfg.strategy = Strategy::Gan;
        let mut d = Self::with_predictor(TightConfig { strategy: Strategy::Fdi, ..cfg.clone() }, Box::new(FilterPredictor::new(1.0)))?;
        d.fdsr = Reconfigurator::with_gan(FdsrConfig { strategy: Strategy::Gan, alpha: cfg.alpha, eta: cfg.eta }, model)?;
        d.cfg = cfg;
        Ok(d)
    }

    fn filter_from(&self, s: &InitialState) -> Result<TcEkf, TightError> {
        let vals = [
            ("initial.t", s.t),
            ("initial.clock_bias_m", s.clock_bias_m),
            ("initial.clock_drift_mps", s.clock_drift_mps),
        ];
        for (f, v) in vals {
            super::finite(f, v)?;
        }
        for i in 0..3 {
            super::finite(&format!("initial.position_ned[{i}]"), s.position_ned[i])?;
            super::finite(&format!("initial.velocity_ned[{i}]"), s.velocity_ned[i])?;
            super::finite(&format!("initial.roll_pitch_yaw_deg[{i}]"), s.roll_pitch_yaw_deg[i])?;
        }
        let [r, p, y] = s.roll_pitch_yaw_deg;
        let x = NavState {
            q: UnitQuaternion::from_rotation_matrix(&euler_dcm(r.to_radians(), p.to_radians(), y.to_radians())),
            v: Vector3::from(s.velocity_ned),
            p: Vector3::from(s.position_ned),
            bg: Vector3::zeros(),
            ba: Vector3::zeros(),
            clk: s.clock_bias_m,
            drift: s.clock_drift_mps,
        };
        TcEkf::new(x, self.cfg.ekf)
    }

    /// The configuration in use.
    pub fn config(&self) -> &TightConfig {
        &self.cfg
    }

    /// Process one row.
    pub fn push(&mut self, row: &EpochRow) -> Result<EpochOutput, TightError> {
        super::finite("t", row.t)?;
        if let Some(lt) = self.last_t {
            if row.t <= lt {
                return Err(TightError::new("t", format!("must increase: {} after {}", row.t, lt)));
            }
        }
        for i in 0..3 {
            super::finite(["gx", "gy", "gz"][i], row.gyro[i])?;
            super::finite(["ax", "ay", "az"][i], row.accel[i])?;
        }
        let mut meas = Vec::with_capacity(row.pr.len());
        for (k, o) in row.pr.iter().enumerate() {
            let field = format!("pr_{}", o.prn);
            let orbit = self
                .constellation
                .orbit(o.prn)
                .ok_or_else(|| TightError::new(&field, format!("unknown satellite {} (almanac has 1..={})", o.prn, self.cfg.n_sats)))?;
            if !(o.pr.is_finite() && o.pr > 1.0e6 && o.pr < 1.0e8) {
                return Err(TightError::new(&field, format!("pseudo-range must be finite and in (1e6, 1e8) m, got {}", o.pr)));
            }
            if row.pr[..k].iter().any(|x| x.prn == o.prn) {
                return Err(TightError::new(&field, format!("satellite {} appears twice in one row", o.prn)));
            }
            let sat = self.site.ecef_to_ned(&orbit.position_ecef(self.cfg.t0 + row.t));
            meas.push(PrMeas { prn: o.prn, pr: o.pr, sat });
        }
        let gyro = Vector3::from(row.gyro);
        let accel = Vector3::from(row.accel);

        let Some(ekf) = self.ekf.as_mut() else {
            // Start from a least-squares fix.
            if meas.len() >= 4 {
                if let Some((p, clk)) = least_squares_fix(&meas) {
                    let init = InitialState {
                        t: row.t,
                        position_ned: [p[0], p[1], p[2]],
                        velocity_ned: self.cfg.initial_velocity_ned,
                        roll_pitch_yaw_deg: [0.0, 0.0, self.cfg.initial_yaw_deg],
                        clock_bias_m: clk,
                        clock_drift_mps: 0.0,
                    };
                    let ekf = self.filter_from(&init)?;
                    let out = output(row.t, Status::Ok, &ekf, meas.len());
                    self.ekf = Some(ekf);
                    self.last_t = Some(row.t);
                    return Ok(out);
                }
            }
            self.last_t = Some(row.t);
            let out = EpochOutput {
                t: row.t,
                status: Status::Initializing,
                faulty_prn: None,
                statistic: None,
                lambda_max: 0.0,
                rdpop: None,
                action: None,
                gan_score_max: None,
                n_sats: meas.len(),
                position_ned: [f64::NAN; 3],
                velocity_ned: [f64::NAN; 3],
                clock_bias_m: f64::NAN,
            };
            return Ok(out);
        };
        let dt = row.t - self.last_t.unwrap_or(row.t);
        ekf.propagate(&gyro, &accel, dt);
        self.last_t = Some(row.t);
        if meas.is_empty() {
            return Ok(output(row.t, Status::NoGnss, ekf, 0));
        }
        let d = self.fdsr.epoch(ekf, &meas, row.t);
        let mut out = output(row.t, if d.detection.is_some() { Status::Fault } else { Status::Ok }, ekf, meas.len());
        out.faulty_prn = d.detection.map(|x| x.prn);
        out.statistic = d.detection.map(|x| x.lambda);
        out.lambda_max = d.lambda_max;
        out.rdpop = d.rdpop;
        out.action = Some(d.action);
        out.gan_score_max = d.gan_scores.iter().map(|x| x.1).filter(|x| x.is_finite()).fold(None, |m: Option<f64>, x| Some(m.map_or(x, |m| m.max(x))));
        Ok(out)
    }

    /// Process many rows; stops at the first bad row (its index in the error).
    pub fn run(&mut self, rows: &[EpochRow]) -> Result<Vec<EpochOutput>, TightError> {
        let mut out = Vec::with_capacity(rows.len());
        for (i, r) in rows.iter().enumerate() {
            out.push(self.push(r).map_err(|e| TightError::new(format!("row {i}: {}", e.field), e.message))?);
        }
        Ok(out)
    }
}

fn output(t: f64, status: Status, ekf: &TcEkf, n_sats: usize) -> EpochOutput {
    EpochOutput {
        t,
        status,
        faulty_prn: None,
        statistic: None,
        lambda_max: 0.0,
        rdpop: None,
        action: None,
        gan_score_max: None,
        n_sats,
        position_ned: [ekf.x.p[0], ekf.x.p[1], ekf.x.p[2]],
        velocity_ned: [ekf.x.v[0], ekf.x.v[1], ekf.x.v[2]],
        clock_bias_m: ekf.x.clk,
    }
}

/// Body-to-NED rotation from roll, pitch, yaw (rad), libm trigonometry.
fn euler_dcm(r: f64, p: f64, y: f64) -> nalgebra::Rotation3<f64> {
    let (sr, cr, sp, cp, sy, cy) = (libm::sin(r), libm::cos(r), libm::sin(p), libm::cos(p), libm::sin(y), libm::cos(y));
    #[rustfmt::skip]
    let m = nalgebra::Matrix3::new(
        cp * cy, sr * sp * cy - cr * sy, cr * sp * cy + sr * sy,
        cp * sy, sr * sp * sy + cr * cy, cr * sp * sy - sr * cy,
        -sp,     sr * cp,                cr * cp,
    );
    nalgebra::Rotation3::from_matrix_unchecked(m)
}

/// Single-epoch least-squares position (NED, m) and clock bias (m):
/// Gauss–Newton from the site origin. `None` if the geometry is singular.
pub fn least_squares_fix(meas: &[PrMeas]) -> Option<(Vector3<f64>, f64)> {
    if meas.len() < 4 {
        return None;
    }
    let (mut p, mut clk) = (Vector3::zeros(), 0.0);
    for _ in 0..10 {
        let mut ata = Matrix4::<f64>::zeros();
        let mut atb = Vector4::<f64>::zeros();
        for m in meas {
            let d = m.sat - p;
            let r = d.norm();
            let g = Vector4::new(-d[0] / r, -d[1] / r, -d[2] / r, 1.0);
            let res = m.pr - (r + clk);
            ata += g * g.transpose();
            atb += g * res;
        }
        let dx = ata.try_inverse()? * atb;
        p += Vector3::new(dx[0], dx[1], dx[2]);
        clk += dx[3];
        if dx.norm() < 1e-4 {
            break;
        }
    }
    (p.iter().all(|x| x.is_finite()) && clk.is_finite()).then_some((p, clk))
}

#[cfg(all(test, not(target_arch = "wasm32")))]
mod tests {
    use super::*;

    #[test]
    fn push_rejects_bad_rows() {
        let mut d = TightDetector::new(TightConfig::default()).unwrap();
        let row = EpochRow { t: 1.0, gyro: [0.0; 3], accel: [0.0, 0.0, -9.8], pr: vec![PrObs { prn: 40, pr: 2.1e7 }] };
        let e = d.push(&row).unwrap_err();
        assert_eq!(e.field, "pr_40");
        let row = EpochRow { pr: vec![PrObs { prn: 4, pr: f64::NAN }], ..row };
        assert_eq!(d.push(&row).unwrap_err().field, "pr_4");
        let row = EpochRow { t: f64::INFINITY, pr: vec![], ..row };
        assert_eq!(d.push(&row).unwrap_err().field, "t");
        let ok = EpochRow { t: 2.0, gyro: [0.0; 3], accel: [0.0, 0.0, -9.8], pr: vec![] };
        assert_eq!(d.push(&ok).unwrap().status, Status::Initializing);
        let back = EpochRow { t: 1.5, ..ok.clone() };
        assert_eq!(d.push(&back).unwrap_err().field, "t");
        let bad_imu = EpochRow { t: 3.0, gyro: [0.0, f64::NAN, 0.0], ..ok };
        assert_eq!(d.push(&bad_imu).unwrap_err().field, "gy");
        let cfg = TightConfig { alpha: 2.0, ..TightConfig::default() };
        assert_eq!(TightDetector::new(cfg).err().map(|e| e.field), Some("alpha".to_string()));
    }
}
