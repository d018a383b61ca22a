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
use super::gan_fdsr::GanDetectorModel;
use super::tc_ekf::{EkfConfig, NavState, PrMeas, TcEkf};
use super::TightError;

/// One pseudo-range.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PrObs {
    /// Satellite id (1..=n_sats).
    pub prn: u8,
    /// Pseudo-range, m.
    pub pr: f64,
}

/// One input row.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EpochRow {
    /// Time, s.
    pub t: f64,
    /// Gyro, rad/s, body frame.
    pub gyro: [f64; 3],
    /// Specific force, m/s², body frame.
    pub accel: [f64; 3],
    /// Pseudo-ranges of this row (empty: IMU-only row).
    #[serde(default)]
    pub pr: Vec<PrObs>,
}

/// Known initial state (e.g. from the autopilot); without it the detector
/// waits for a row with ≥ 4 pseudo-ranges and starts from a least-squares
/// fix, level attitude with `initial_yaw_deg` and `initial_velocity_ned`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct InitialState {
    /// Time of this state, s (rows must come after it).
    pub t: f64,
    /// Position in the site NED frame, m.
    pub position_ned: [f64; 3],
    /// Velocity, NED, m/s.
    pub velocity_ned: [f64; 3],
    /// Roll, pitch, yaw (deg).
    pub roll_pitch_yaw_deg: [f64; 3],
    /// Receiver clock bias (m) and drift (m/s).
    pub clock_bias_m: f64,
    pub clock_drift_mps: f64,
}

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
    pub ekf: EkfConfig,
    pub initial: Option<InitialState>,
    pub initial_velocity_ned: [f64; 3],
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
    pub t: f64,
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
    pub action: Option<Action>,
    /// GAN-FDSR only: the largest GAN score of the epoch (T2 is the model's
    /// threshold); `None` for other strategies or while windows fill.
    #[serde(default)]
    pub gan_score_max: Option<f64>,
    /// Pseudo-ranges at this row.
    pub n_sats: usize,
    /// Estimated position (NED, m), velocity (NED, m/s), clock bias (m).
    pub position_ned: [f64; 3],
    pub velocity_ned: [f64; 3],
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
        let fdsr = Reconfigurator::new(FdsrConfig { strategy: cfg.strategy, alpha: cfg.alpha, eta: cfg.eta }, predictor)?;
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

const IMU_COLS: [&str; 7] = ["t", "gx", "gy", "gz", "ax", "ay", "az"];

/// Parse CSV rows. Two layouts, chosen by the header:
///
/// * wide: `t,gx,gy,gz,ax,ay,az,pr_<prn>...`, one row per IMU sample;
/// * long: `t,gx,gy,gz,ax,ay,az,sat_id,pr`, one row per satellite; rows
///   with the same `t` (consecutive) form one epoch and must repeat the
///   same IMU values; a row with empty `sat_id` and `pr` is IMU-only.
///
/// Blank lines and lines starting with `#` are skipped. Errors name the
/// line, the column and the bad value.
pub fn parse_csv(text: &str) -> Result<Vec<EpochRow>, TightError> {
    let mut lines = text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'));
    let (_, header) = lines.next().ok_or_else(|| TightError::new("header", "empty input: no header line"))?;
    let cols: Vec<&str> = header.split(',').map(|c| c.trim()).collect();
    if cols.contains(&"sat_id") {
        return parse_long(&cols, lines);
    }
    let mut imu_idx = [usize::MAX; 7];
    let mut pr_cols: Vec<(usize, u8)> = Vec::new();
    for (i, c) in cols.iter().enumerate() {
        if let Some(k) = IMU_COLS.iter().position(|x| x == c) {
            if imu_idx[k] != usize::MAX {
                return Err(TightError::new(*c, "column appears twice in the header"));
            }
            imu_idx[k] = i;
        } else if let Some(n) = c.strip_prefix("pr_") {
            let prn: u8 = n.parse().map_err(|_| TightError::new(*c, format!("satellite id must be an integer 1..=255, got {n:?}")))?;
            if prn == 0 {
                return Err(TightError::new(*c, "satellite id must be >= 1, got 0"));
            }
            if pr_cols.iter().any(|&(_, p)| p == prn) {
                return Err(TightError::new(*c, "column appears twice in the header"));
            }
            pr_cols.push((i, prn));
        } else {
            return Err(TightError::new(*c, "unknown column (expected t, gx, gy, gz, ax, ay, az, pr_<prn>)"));
        }
    }
    if let Some(k) = imu_idx.iter().position(|&i| i == usize::MAX) {
        return Err(TightError::new(IMU_COLS[k], "required column missing from the header"));
    }
    let mut rows = Vec::new();
    for (ln, line) in lines {
        let cells: Vec<&str> = line.split(',').map(|c| c.trim()).collect();
        let lno = ln + 1;
        if cells.len() != cols.len() {
            return Err(TightError::new(format!("line {lno}"), format!("{} cells, header has {}", cells.len(), cols.len())));
        }
        let num = |i: usize| -> Result<f64, TightError> {
            let s = cells[i];
            s.parse::<f64>().ok().filter(|v| v.is_finite()).ok_or_else(|| TightError::new(format!("line {lno}: {}", cols[i]), format!("must be a finite number, got {s:?}")))
        };
        let mut v = [0.0; 7];
        for k in 0..7 {
            v[k] = num(imu_idx[k])?;
        }
        let mut pr = Vec::new();
        for &(i, prn) in &pr_cols {
            let s = cells[i];
            if s.is_empty() || s.eq_ignore_ascii_case("nan") {
                continue;
            }
            pr.push(PrObs { prn, pr: num(i)? });
        }
        rows.push(EpochRow { t: v[0], gyro: [v[1], v[2], v[3]], accel: [v[4], v[5], v[6]], pr });
    }
    Ok(rows)
}

fn parse_long<'a>(cols: &[&str], lines: impl Iterator<Item = (usize, &'a str)>) -> Result<Vec<EpochRow>, TightError> {
    let want = ["t", "gx", "gy", "gz", "ax", "ay", "az", "sat_id", "pr"];
    for c in cols {
        if !want.contains(c) {
            return Err(TightError::new(*c, "unknown column (long layout: t, gx, gy, gz, ax, ay, az, sat_id, pr)"));
        }
    }
    let mut idx = [usize::MAX; 9];
    for (k, w) in want.iter().enumerate() {
        let found: Vec<usize> = cols.iter().enumerate().filter(|(_, c)| *c == w).map(|(i, _)| i).collect();
        match found.as_slice() {
            [i] => idx[k] = *i,
            [] => return Err(TightError::new(*w, "required column missing from the header")),
            _ => return Err(TightError::new(*w, "column appears twice in the header")),
        }
    }
    let mut rows: Vec<EpochRow> = Vec::new();
    for (ln, line) in lines {
        let lno = ln + 1;
        let cells: Vec<&str> = line.split(',').map(|c| c.trim()).collect();
        if cells.len() != cols.len() {
            return Err(TightError::new(format!("line {lno}"), format!("{} cells, header has {}", cells.len(), cols.len())));
        }
        let num = |k: usize| -> Result<f64, TightError> {
            let s = cells[idx[k]];
            s.parse::<f64>().ok().filter(|v| v.is_finite()).ok_or_else(|| TightError::new(format!("line {lno}: {}", want[k]), format!("must be a finite number, got {s:?}")))
        };
        let mut v = [0.0; 7];
        for (k, x) in v.iter_mut().enumerate() {
            *x = num(k)?;
        }
        let (sid, prs) = (cells[idx[7]], cells[idx[8]]);
        let obs = if sid.is_empty() && (prs.is_empty() || prs.eq_ignore_ascii_case("nan")) {
            None
        } else {
            let prn: u8 = sid
                .parse()
                .ok()
                .filter(|p| *p >= 1)
                .ok_or_else(|| TightError::new(format!("line {lno}: sat_id"), format!("must be an integer 1..=255, got {sid:?}")))?;
            if prs.is_empty() || prs.eq_ignore_ascii_case("nan") {
                None
            } else {
                Some(PrObs { prn, pr: num(8)? })
            }
        };
        match rows.last_mut() {
            Some(last) if last.t == v[0] => {
                if last.gyro != [v[1], v[2], v[3]] || last.accel != [v[4], v[5], v[6]] {
                    return Err(TightError::new(format!("line {lno}: gx..az"), format!("IMU values differ from the previous row of the same epoch t = {}", v[0])));
                }
                if let Some(o) = obs {
                    last.pr.push(o);
                }
            }
            _ => rows.push(EpochRow { t: v[0], gyro: [v[1], v[2], v[3]], accel: [v[4], v[5], v[6]], pr: obs.into_iter().collect() }),
        }
    }
    Ok(rows)
}

/// Write rows in the `pr_<prn>` CSV format (columns for every satellite
/// that appears; empty cell where a row has no pseudo-range for it).
pub fn to_csv(rows: &[EpochRow]) -> String {
    let mut prns: Vec<u8> = rows.iter().flat_map(|r| r.pr.iter().map(|o| o.prn)).collect();
    prns.sort_unstable();
    prns.dedup();
    let mut s = String::from("t,gx,gy,gz,ax,ay,az");
    for p in &prns {
        s.push_str(&format!(",pr_{p}"));
    }
    s.push('\n');
    for r in rows {
        s.push_str(&format!("{},{},{},{},{},{},{}", r.t, r.gyro[0], r.gyro[1], r.gyro[2], r.accel[0], r.accel[1], r.accel[2]));
        for p in &prns {
            match r.pr.iter().find(|o| o.prn == *p) {
                Some(o) => s.push_str(&format!(",{}", o.pr)),
                None => s.push(','),
            }
        }
        s.push('\n');
    }
    s
}

#[cfg(all(test, not(target_arch = "wasm32")))]
mod tests {
    use super::*;

    #[test]
    fn csv_round_trip_and_absent_values() {
        let text = "# comment\nt,gx,gy,gz,ax,ay,az,pr_3,pr_17\n0.05,0,0,0.01,0,0,-9.8,,\n1.0,0,0,0,0.1,0,-9.8,20000000.5,NaN\n";
        let rows = parse_csv(text).unwrap();
        assert_eq!(rows.len(), 2);
        assert!(rows[0].pr.is_empty());
        assert_eq!(rows[1].pr, vec![PrObs { prn: 3, pr: 20000000.5 }]);
        assert_eq!(rows[1].accel, [0.1, 0.0, -9.8]);
        let again = parse_csv(&to_csv(&rows)).unwrap();
        assert_eq!(again, rows);
    }

    #[test]
    fn long_layout_with_sat_id() {
        let text = "t,gx,gy,gz,ax,ay,az,sat_id,pr\n0.05,0,0,0,0,0,-9.8,,\n1,0,0,0,0,0,-9.8,3,20000000.5\n1,0,0,0,0,0,-9.8,17,21000000\n1,0,0,0,0,0,-9.8,9,NaN\n";
        let rows = parse_csv(text).unwrap();
        assert_eq!(rows.len(), 2);
        assert!(rows[0].pr.is_empty());
        assert_eq!(rows[1].pr, vec![PrObs { prn: 3, pr: 20000000.5 }, PrObs { prn: 17, pr: 21000000.0 }]);
        // Same as the wide layout.
        let wide = parse_csv("t,gx,gy,gz,ax,ay,az,pr_3,pr_17\n0.05,0,0,0,0,0,-9.8,,\n1,0,0,0,0,0,-9.8,20000000.5,21000000\n").unwrap();
        assert_eq!(rows, wide);
        let e = parse_csv("t,gx,gy,gz,ax,ay,az,sat_id,pr\n1,0,0,0,0,0,-9.8,3,2e7\n1,0,0,0,0.5,0,-9.8,4,2e7\n").unwrap_err();
        assert!(e.field.contains("line 3"), "{e}");
        let e = parse_csv("t,gx,gy,gz,ax,ay,az,sat_id,pr\n1,0,0,0,0,0,-9.8,G7,2e7\n").unwrap_err();
        assert_eq!(e.field, "line 2: sat_id");
        assert!(e.message.contains("\"G7\""));
    }

    #[test]
    fn csv_errors_name_field_and_value() {
        let e = parse_csv("t,gx,gy,gz,ax,ay,pr_3\n").unwrap_err();
        assert_eq!(e.field, "az");
        let e = parse_csv("t,gx,gy,gz,ax,ay,az,pr_x\n").unwrap_err();
        assert_eq!(e.field, "pr_x");
        let e = parse_csv("t,gx,gy,gz,ax,ay,az,speed\n").unwrap_err();
        assert_eq!(e.field, "speed");
        let e = parse_csv("t,gx,gy,gz,ax,ay,az,pr_3\n0,0,0,0,0,0,-9.8,abc\n").unwrap_err();
        assert_eq!(e.field, "line 2: pr_3");
        assert!(e.message.contains("\"abc\""), "{e}");
        let e = parse_csv("t,gx,gy,gz,ax,ay,az\n0,0,0,0,0,0\n").unwrap_err();
        assert!(e.message.contains("6 cells"), "{e}");
        assert!(parse_csv("").is_err());
    }

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
