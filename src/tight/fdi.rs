//! Fault detection (Appendix A), isolation (Appendix B), adaptation
//! (Appendix C), RDPOP (eq. 26) and the RDPOP switch between isolation and
//! measurement reconstruction (eq. 27) of Shen et al. 2022.
//!
//! All functions work on a [`Linearized`] measurement set (innovations `v`,
//! `H`, `R`) and the predicted covariance `P_{k,k−1}`; `P_v = H P Hᵀ + R`.

use std::collections::BTreeMap;

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

use super::gan_fdsr::{GanDetectorModel, GanMonitor};
pub use super::predict::{FilterPredictor, RangePredictor, Reconstruction};
pub use super::stats::{chi2_quantile, normal_upper_quantile, threshold_t1};
use super::tc_ekf::{Linearized, Mat17, PrMeas, TcEkf, N, POS};
use super::TightError;

/// Normalized innovations (eq. A2): `λ_i = c_iᵀ P_v⁻¹ v / √(c_iᵀ P_v⁻¹ c_i)`.
/// Each is N(0, 1) when fault-free. `None` if `P_v` is not positive definite.
pub fn w_test(pv: &DMatrix<f64>, v: &DVector<f64>) -> Option<DVector<f64>> {
    let inv = pv.clone().cholesky()?.inverse();
    let y = &inv * v;
    let mut lam = DVector::zeros(v.len());
    for i in 0..v.len() {
        let d = inv[(i, i)];
        if d.is_nan() || d <= 0.0 {
            return None;
        }
        lam[i] = y[i] / libm::sqrt(d);
    }
    Some(lam)
}

/// A satellite flagged by the test.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Detection {
    /// Row in the measurement set.
    pub index: usize,
    /// The flagged satellite.
    pub prn: u8,
    /// Its normalized innovation λ (signed).
    pub lambda: f64,
}

/// The row with the largest |λ| if it exceeds `t1` (single-fault assumption).
pub fn detect(lambdas: &DVector<f64>, prns: &[u8], t1: f64) -> Option<Detection> {
    let (mut best, mut best_abs) = (None, t1);
    for (i, &l) in lambdas.iter().enumerate() {
        if l.abs() > best_abs {
            best_abs = l.abs();
            best = Some(Detection { index: i, prn: prns[i], lambda: l });
        }
    }
    best
}

/// Updated covariance `P_k = P − P Hᵀ (H P Hᵀ + R)⁻¹ H P` (eq. 9 / A6).
pub fn updated_covariance(p_pred: &Mat17, lin: &Linearized) -> Option<Mat17> {
    if lin.is_empty() {
        return Some(*p_pred);
    }
    let p = DMatrix::from_column_slice(N, N, p_pred.as_slice());
    let pht = &p * lin.h.transpose();
    let s = &lin.h * &pht + &lin.r;
    let s_inv = s.cholesky()?.inverse();
    let pk = &p - &pht * s_inv * pht.transpose();
    Some(Mat17::from_column_slice(pk.as_slice()))
}

/// Fault isolation (Appendix B): the measurement set without row `i`
/// (eq. A5) and the covariance `P̃_k^i` of the estimate without it (eq. A6).
pub fn isolate(p_pred: &Mat17, lin: &Linearized, i: usize) -> Option<(Linearized, Mat17)> {
    if i >= lin.len() {
        return None;
    }
    let reduced = lin.without(i);
    let p = updated_covariance(p_pred, &reduced)?;
    Some((reduced, p))
}

/// Fault estimate of row `i` (eqs. C2–C3): `∇̂ = (e_iᵀ P_v⁻¹ e_i)⁻¹ e_iᵀ P_v⁻¹ v`
/// (m) and its variance `P_∇ = (e_iᵀ P_v⁻¹ e_i)⁻¹` (m²).
pub fn fault_estimate(pv: &DMatrix<f64>, v: &DVector<f64>, i: usize) -> Option<(f64, f64)> {
    if i >= v.len() {
        return None;
    }
    let inv = pv.clone().cholesky()?.inverse();
    let d = inv[(i, i)];
    if d.is_nan() || d <= 0.0 {
        return None;
    }
    let y = (&inv * v)[i];
    Some((y / d, 1.0 / d))
}

/// Fault adaptation (Appendix C): `Z' = Z − e_i ∇̂` (eq. C4) with noise
/// covariance `R' ≈ R + e_i P_∇ e_iᵀ`. Updating with the returned set is the
/// gain form of eqs. C5–C6. Also returns `(∇̂, P_∇)`.
pub fn adapt(lin: &Linearized, pv: &DMatrix<f64>, i: usize) -> Option<(Linearized, f64, f64)> {
    let (nabla, var) = fault_estimate(pv, &lin.v, i)?;
    let mut out = lin.clone();
    out.v[i] -= nabla;
    out.r[(i, i)] += var;
    Some((out, nabla, var))
}

/// Relative differential precision of positioning of row `i` (eq. 26):
/// `(Σ_{j=7..9} P̃_k^i[jj] − Σ P_k[jj]) / Σ P_k[jj]`, the relative growth of
/// the position variance when satellite `i` is isolated.
pub fn rdpop(p_pred: &Mat17, lin: &Linearized, i: usize) -> Option<f64> {
    let full = updated_covariance(p_pred, lin)?;
    let (_, iso) = isolate(p_pred, lin, i)?;
    let tr = |m: &Mat17| (POS..POS + 3).map(|j| m[(j, j)]).sum::<f64>();
    let base = tr(&full);
    if base.is_nan() || base <= 0.0 {
        return None;
    }
    Some((tr(&iso) - base) / base)
}

/// How a detected fault is handled.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Strategy {
    /// No detection: every pseudo-range is used (the fault-free reference
    /// when no fault is injected).
    None,
    /// FDI: detection (Appendix A) then isolation (Appendix B).
    Fdi,
    /// FDA: detection then adaptation (Appendix C, DIA style).
    Fda,
    /// Detection then RDPOP switch (eq. 27): reconstruct when RDPOP > η,
    /// else isolate.
    Switch,
    /// GAN-FDSR: the GAN detection function (score > T2) then the RDPOP
    /// switch, reconstructing from the generator (eq. 12).
    Gan,
}

impl Strategy {
    /// Name in reports (as in the paper's tables).
    pub fn name(self) -> &'static str {
        match self {
            Strategy::None => "none",
            Strategy::Fdi => "FDI",
            Strategy::Fda => "FDA",
            Strategy::Switch => "RDPOP-switch",
            Strategy::Gan => "GAN-FDSR",
        }
    }
}

/// What was done with the epoch's measurements.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Action {
    /// No pseudo-ranges: time update only.
    NoMeasurements,
    /// All pseudo-ranges used.
    UpdateAll,
    /// The flagged satellite was left out.
    Isolate,
    /// The flagged satellite was adapted.
    Adapt,
    /// The flagged satellite was replaced by the predictor's pseudo-range.
    Reconstruct,
    /// The update was rejected (innovation covariance not positive definite).
    Rejected,
}

/// The outcome of one GNSS epoch.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EpochDecision {
    /// (prn, λ) for every satellite of the epoch.
    pub lambdas: Vec<(u8, f64)>,
    /// Largest |λ|.
    pub lambda_max: f64,
    /// The flagged satellite, if any.
    pub detection: Option<Detection>,
    /// RDPOP of the flagged satellite.
    pub rdpop: Option<f64>,
    /// What was done with the measurements.
    pub action: Action,
    /// GAN-FDSR only: (prn, score) per satellite (NaN while its window fills).
    #[serde(default)]
    pub gan_scores: Vec<(u8, f64)>,
}

/// Detection parameters.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FdsrConfig {
    /// How a detected fault is handled.
    pub strategy: Strategy,
    /// False-alarm rate α of the λ test.
    pub alpha: f64,
    /// RDPOP threshold η of eq. 27.
    pub eta: f64,
}

impl Default for FdsrConfig {
    fn default() -> Self {
        FdsrConfig { strategy: Strategy::Switch, alpha: 0.001, eta: 0.1 }
    }
}

impl FdsrConfig {
    /// Check α and η; returns the detection threshold T1.
    pub fn check(&self) -> Result<f64, TightError> {
        if !(self.eta.is_finite() && self.eta >= 0.0) {
            return Err(TightError::new("eta", format!("must be finite and >= 0, got {}", self.eta)));
        }
        threshold_t1(self.alpha)
    }
}

/// Detection and reconfiguration state across epochs: the λ test, the
/// predictor and, for [`Strategy::Switch`], the satellites under repair.
///
/// FDI and FDA test every epoch afresh (Appendix A), as in the paper; their
/// weakness is that while a satellite is left out the filter's prediction
/// drifts along its line of sight, λ shrinks below T1 and the fault leaks in
/// (the decreasing detection function of the paper's Figure 10).
/// The switch keeps a flagged satellite under repair while its pseudo-range
/// disagrees with the predictor, `|ρ − ρ̂| / √(R + σ̂²) > T1`: a stand-in for
/// the GAN generation score, checked against the same threshold.
pub struct Reconfigurator {
    /// The detection parameters.
    pub cfg: FdsrConfig,
    /// Detection threshold T1.
    pub t1: f64,
    /// Rebuilds a flagged pseudo-range (switch strategy).
    pub predictor: Box<dyn RangePredictor>,
    /// Satellites under repair (switch only): prn -> time first flagged, s.
    pub under_repair: BTreeMap<u8, f64>,
    /// The GAN detection function ([`Strategy::Gan`] only).
    pub gan: Option<Box<GanMonitor>>,
}

impl Reconfigurator {
    /// A reconfigurator for `cfg.strategy`. [`Strategy::Gan`] needs its
    /// model in `gan` (the caller picks it: the embedded default or one
    /// trained on the user's data); other strategies ignore `gan`.
    pub fn new(cfg: FdsrConfig, predictor: Box<dyn RangePredictor>, gan: Option<GanDetectorModel>) -> Result<Self, TightError> {
        let t1 = cfg.check()?;
        let gan = match (cfg.strategy, gan) {
            (Strategy::Gan, Some(m)) => Some(Box::new(GanMonitor::new(m))),
            (Strategy::Gan, None) => return Err(TightError::new("strategy", "GAN-FDSR needs a GAN model")),
            _ => None,
        };
        Ok(Reconfigurator { cfg, t1, predictor, under_repair: BTreeMap::new(), gan })
    }

    /// [`Strategy::Gan`] with a given model (e.g. one trained on the user's
    /// data), whatever `cfg.strategy` says.
    pub fn with_gan(cfg: FdsrConfig, model: GanDetectorModel) -> Result<Self, TightError> {
        // The GAN path rebuilds from its generator; this predictor is unused.
        Self::new(FdsrConfig { strategy: Strategy::Gan, ..cfg }, Box::new(FilterPredictor::new(1.0)), Some(model))
    }

    /// One GNSS epoch at time `t` (s): test, reconfigure, update the filter.
    pub fn epoch(&mut self, ekf: &mut TcEkf, meas: &[PrMeas], t: f64) -> EpochDecision {
        let cfg = self.cfg;
        let lin = ekf.linearize(meas);
        let mut out = EpochDecision {
            lambdas: Vec::new(),
            lambda_max: 0.0,
            detection: None,
            rdpop: None,
            action: Action::NoMeasurements,
            gan_scores: Vec::new(),
        };
        if lin.is_empty() {
            return out;
        }
        let pv = ekf.innovation_cov(&lin);
        let Some(lam) = w_test(&pv, &lin.v) else {
            out.action = Action::Rejected;
            return out;
        };
        out.lambdas = lin.prns.iter().zip(lam.iter()).map(|(&p, &l)| (p, l)).collect();
        out.lambda_max = lam.iter().fold(0.0f64, |m, l| m.max(l.abs()));
        if let Some(gan) = self.gan.as_deref_mut() {
            epoch_gan(gan, &mut self.under_repair, self.t1, cfg.eta, ekf, &lin, &pv, t, &mut out);
            return out;
        }

        // Satellites under repair stay flagged while they disagree with the
        // predictor; the first one still inconsistent is the detection.
        let mut det = None;
        if cfg.strategy == Strategy::Switch {
            let predictor = &mut self.predictor;
            let (d, release) = repair_check(&self.under_repair, &lin, self.t1, |prn, pred| predictor.reconstruct(t, prn, pred));
            det = d;
            for p in release {
                self.under_repair.remove(&p);
            }
        }
        if det.is_none() && cfg.strategy != Strategy::None {
            det = detect(&lam, &lin.prns, self.t1);
            if let (Some(d), Strategy::Switch) = (det, cfg.strategy) {
                self.under_repair.entry(d.prn).or_insert(t);
            }
        }
        out.detection = det;
        let flagged = det.map(|d| d.index);
        // Healthy satellites feed the predictor's history.
        for i in 0..lin.len() {
            if Some(i) != flagged && !self.under_repair.contains_key(&lin.prns[i]) {
                self.predictor.observe(t, lin.prns[i], lin.predicted[i] + lin.v[i], lin.predicted[i]);
            }
        }
        let (used, action) = match det {
            None => (lin.clone(), Action::UpdateAll),
            Some(d) => {
                out.rdpop = rdpop(&ekf.p, &lin, d.index);
                match cfg.strategy {
                    Strategy::None => (lin.clone(), Action::UpdateAll),
                    Strategy::Fdi => (lin.without(d.index), Action::Isolate),
                    Strategy::Fda => match adapt(&lin, &pv, d.index) {
                        Some((a, _, _)) => (a, Action::Adapt),
                        None => (lin.without(d.index), Action::Isolate),
                    },
                    Strategy::Switch | Strategy::Gan => {
                        let rec = if out.rdpop.is_some_and(|r| r > cfg.eta) {
                            self.predictor.reconstruct(t, d.prn, lin.predicted[d.index])
                        } else {
                            None
                        };
                        reconstruct_or_isolate(&lin, &pv, d.index, rec)
                    }
                }
            }
        };
        out.action = action;
        if !used.is_empty() && ekf.update(&used).is_none() {
            out.action = Action::Rejected;
        }
        out
    }
}

/// Satellites under repair stay flagged while their pseudo-range disagrees
/// with the rebuilt one, `|ρ − ρ̂| / √(R + σ̂²) > T1`: the first still
/// inconsistent one is the epoch's detection; the others that agree (or are
/// not tracked, or cannot be rebuilt) are returned for release.
fn repair_check(
    under_repair: &BTreeMap<u8, f64>,
    lin: &Linearized,
    t1: f64,
    mut rebuild: impl FnMut(u8, f64) -> Option<Reconstruction>,
) -> (Option<Detection>, Vec<u8>) {
    let mut det = None;
    let mut release = Vec::new();
    for &prn in under_repair.keys() {
        let Some(i) = lin.index_of(prn) else {
            release.push(prn);
            continue;
        };
        let pr = lin.predicted[i] + lin.v[i];
        match rebuild(prn, lin.predicted[i]) {
            Some(r) => {
                let stat = (pr - r.pr) / libm::sqrt(lin.r[(i, i)] + r.variance);
                if stat.abs() > t1 && det.is_none() {
                    det = Some(Detection { index: i, prn, lambda: stat });
                } else if stat.abs() <= t1 {
                    release.push(prn);
                }
            }
            None => release.push(prn),
        }
    }
    (det, release)
}

/// The measurement set with satellite `i` replaced by `rec`, or without it
/// when there is no reconstruction.
fn reconstruct_or_isolate(lin: &Linearized, pv: &DMatrix<f64>, i: usize, rec: Option<Reconstruction>) -> (Linearized, Action) {
    match rec {
        Some(r) => {
            let mut l = lin.clone();
            l.v[i] = r.pr - lin.predicted[i];
            // The rebuilt range comes through the filter's own prediction, so
            // the predicted-range variance H P Hᵀ is added to the predictor's:
            // less false confidence.
            l.r[(i, i)] = r.variance + (pv[(i, i)] - lin.r[(i, i)]).max(0.0);
            (l, Action::Reconstruct)
        }
        None => (lin.without(i), Action::Isolate),
    }
}

/// One GNSS epoch of GAN-FDSR (Figure 5): score every satellite, keep a
/// flagged satellite under repair while its pseudo-range disagrees with the
/// generator's reconstruction (`|ρ − ρ̂| / √(R + σ̂²) > T1`), then reconstruct
/// (RDPOP > η) or isolate. A step shows in the increment difference only at
/// its onset, so the repair test is what keeps it out afterwards.
#[allow(clippy::too_many_arguments)]
fn epoch_gan(
    gan: &mut GanMonitor,
    under_repair: &mut BTreeMap<u8, f64>,
    t1: f64,
    eta: f64,
    ekf: &mut TcEkf,
    lin: &Linearized,
    pv: &DMatrix<f64>,
    t: f64,
    out: &mut EpochDecision,
) {
    let v: Vec<f64> = lin.v.iter().copied().collect();
    let lam: Vec<f64> = out.lambdas.iter().map(|x| x.1).collect();
    let sd: Vec<f64> = (0..lin.len()).map(|i| libm::sqrt(pv[(i, i)].max(0.0))).collect();
    let scores = match gan.epoch(t, &lin.prns, &v, &lam, &sd) {
        Ok(s) => s,
        Err(_) => {
            out.action = Action::Rejected;
            return;
        }
    };
    out.gan_scores = scores.iter().map(|s| (s.prn, s.score)).collect();
    let (mut det, release) = repair_check(under_repair, lin, t1, |prn, pred| gan.reconstruct(prn, pred));
    for p in release {
        under_repair.remove(&p);
        gan.end_repair(p);
    }
    if det.is_none() {
        let t2 = gan.t2();
        let best = scores
            .iter()
            .enumerate()
            .filter(|(_, s)| s.score > t2 && !under_repair.contains_key(&s.prn))
            .max_by(|a, b| a.1.score.total_cmp(&b.1.score));
        det = best.map(|(i, s)| Detection { index: i, prn: s.prn, lambda: s.score });
        if det.is_none() && gan.model.lambda_test {
            let lam = DVector::from_iterator(out.lambdas.len(), out.lambdas.iter().map(|x| x.1));
            det = detect(&lam, &lin.prns, t1);
        }
        if let Some(d) = det {
            if gan.start_repair(d.prn, lin.r[(d.index, d.index)]) {
                under_repair.entry(d.prn).or_insert(t);
            }
        }
    }
    out.detection = det;
    for i in 0..lin.len() {
        if det.map(|d| d.index) != Some(i) && !under_repair.contains_key(&lin.prns[i]) {
            gan.healthy(lin.prns[i], lin.v[i]);
        }
    }
    let (used, action) = match det {
        None => (lin.clone(), Action::UpdateAll),
        Some(d) => {
            out.rdpop = rdpop(&ekf.p, lin, d.index);
            let rec = if out.rdpop.is_some_and(|r| r > eta) { gan.reconstruct(d.prn, lin.predicted[d.index]) } else { None };
            reconstruct_or_isolate(lin, pv, d.index, rec)
        }
    };
    out.action = action;
    if !used.is_empty() && ekf.update(&used).is_none() {
        out.action = Action::Rejected;
    }
}

#[cfg(all(test, not(target_arch = "wasm32")))]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    /// A hand-made measurement set: rows are unit vectors on the given
    /// error-state indices, R = r·I.
    fn lin(rows: &[usize], v: &[f64], r: f64) -> Linearized {
        let n = rows.len();
        let mut h = DMatrix::zeros(n, N);
        for (i, &k) in rows.iter().enumerate() {
            h[(i, k)] = 1.0;
        }
        Linearized {
            prns: (1..=n as u8).collect(),
            v: DVector::from_column_slice(v),
            h,
            r: DMatrix::from_diagonal_element(n, n, r),
            predicted: vec![0.0; n],
        }
    }

    #[test]
    fn t1_from_alpha() {
        assert_relative_eq!(threshold_t1(0.001).unwrap(), 3.290_526_731, epsilon = 1e-8);
        assert_relative_eq!(threshold_t1(0.05).unwrap(), 1.959_963_985, epsilon = 1e-8);
        // The paper's 2.88 corresponds to a one-sided 0.002.
        assert_relative_eq!(normal_upper_quantile(0.002).unwrap(), 2.878_161_739, epsilon = 1e-8);
        assert!(threshold_t1(0.0).is_err());
        assert!(threshold_t1(f64::NAN).unwrap_err().to_string().contains("alpha"));
        // Wilson–Hilferty against tabulated chi-square quantiles.
        assert_relative_eq!(chi2_quantile(0.975, 10.0).unwrap(), 20.483, max_relative = 0.005);
        assert_relative_eq!(chi2_quantile(0.025, 100.0).unwrap(), 74.222, max_relative = 0.005);
    }

    #[test]
    fn w_test_hand_cases() {
        // Diagonal P_v = diag(4, 9), v = (2, 9): λ = (2/2, 9/3).
        let pv = DMatrix::from_diagonal(&DVector::from_column_slice(&[4.0, 9.0]));
        let l = w_test(&pv, &DVector::from_column_slice(&[2.0, 9.0])).unwrap();
        assert_relative_eq!(l[0], 1.0, epsilon = 1e-12);
        assert_relative_eq!(l[1], 3.0, epsilon = 1e-12);
        // Correlated: P_v = [[2,1],[1,2]], P_v⁻¹ = [[2,−1],[−1,2]]/3, v = (3, 0):
        // P_v⁻¹ v = (2, −1), (P_v⁻¹)_ii = 2/3 -> λ = (2, −1)/√(2/3).
        let pv = DMatrix::from_row_slice(2, 2, &[2.0, 1.0, 1.0, 2.0]);
        let l = w_test(&pv, &DVector::from_column_slice(&[3.0, 0.0])).unwrap();
        let s = (2.0f64 / 3.0).sqrt();
        assert_relative_eq!(l[0], 2.0 / s, epsilon = 1e-12);
        assert_relative_eq!(l[1], -1.0 / s, epsilon = 1e-12);
        // Detection at T1 = 2.0: row 0 (2.449 > 2); none at T1 = 3.29.
        let d = detect(&l, &[7, 9], 2.0).unwrap();
        assert_eq!((d.index, d.prn), (0, 7));
        assert!(detect(&l, &[7, 9], 3.29).is_none());
        // Not positive definite -> None.
        let bad = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 1.0]);
        assert!(w_test(&bad, &DVector::from_column_slice(&[1.0, 1.0])).is_none());
    }

    #[test]
    fn isolation_hand_case() {
        // P = I, R = I, measurements of δp_x and δp_y: full update halves
        // both variances; isolating row 0 leaves P_xx = 1 (eq. A6).
        let p = Mat17::identity();
        let l = lin(&[POS, POS + 1], &[1.0, 2.0], 1.0);
        let full = updated_covariance(&p, &l).unwrap();
        assert_relative_eq!(full[(POS, POS)], 0.5, epsilon = 1e-12);
        assert_relative_eq!(full[(POS + 1, POS + 1)], 0.5, epsilon = 1e-12);
        let (red, iso) = isolate(&p, &l, 0).unwrap();
        assert_eq!(red.prns, vec![2]);
        assert_relative_eq!(red.v[0], 2.0);
        assert_relative_eq!(iso[(POS, POS)], 1.0, epsilon = 1e-12);
        assert_relative_eq!(iso[(POS + 1, POS + 1)], 0.5, epsilon = 1e-12);
        // Information form of eq. A6: (P⁻¹ + H̃ᵀ R̃⁻¹ H̃)⁻¹.
        let info = DMatrix::identity(N, N) + red.h.transpose() * &red.h;
        let inv = info.try_inverse().unwrap();
        for i in 0..N {
            assert_relative_eq!(inv[(i, i)], iso[(i, i)], epsilon = 1e-12);
        }
        assert!(isolate(&p, &l, 2).is_none());
    }

    #[test]
    fn rdpop_hand_cases() {
        let p = Mat17::identity();
        // Two independent rows: trace 0.5+0.5+1 = 2 -> isolated 1+0.5+1 = 2.5.
        let l = lin(&[POS, POS + 1], &[0.0, 0.0], 1.0);
        assert_relative_eq!(rdpop(&p, &l, 0).unwrap(), 0.25, epsilon = 1e-12);
        // Two redundant rows on δp_x: P_xx 1/3 -> 1/2; traces 7/3 -> 5/2.
        let l = lin(&[POS, POS], &[0.0, 0.0], 1.0);
        assert_relative_eq!(rdpop(&p, &l, 1).unwrap(), 1.0 / 14.0, epsilon = 1e-12);
        // A row that does not touch position has RDPOP 0.
        let l = lin(&[POS, 0], &[0.0, 0.0], 1.0);
        assert_relative_eq!(rdpop(&p, &l, 1).unwrap(), 0.0, epsilon = 1e-12);
    }

    #[test]
    fn adaptation_hand_case() {
        // Two redundant measurements of δp_x (P = I, R = I) with innovations
        // (0, 6): P_v = [[2,1],[1,2]], P_v⁻¹ v = (−2, 4), (P_v⁻¹)_22 = 2/3,
        // so ∇̂ = 4 / (2/3) = 6 (eq. C2) and P_∇ = 3/2 (eq. C3).
        let p = Mat17::identity();
        let l = lin(&[POS, POS], &[0.0, 6.0], 1.0);
        let pv = DMatrix::from_row_slice(2, 2, &[2.0, 1.0, 1.0, 2.0]);
        let (nabla, var) = fault_estimate(&pv, &l.v, 1).unwrap();
        assert_relative_eq!(nabla, 6.0, epsilon = 1e-12);
        assert_relative_eq!(var, 1.5, epsilon = 1e-12);
        // λ_i = ∇̂ / √P_∇ (the test statistic is the standardized estimate).
        let lam = w_test(&pv, &l.v).unwrap();
        assert_relative_eq!(lam[1], nabla / var.sqrt(), epsilon = 1e-12);
        let (a, _, _) = adapt(&l, &pv, 1).unwrap();
        assert_relative_eq!(a.v[1], 0.0, epsilon = 1e-12);
        assert_relative_eq!(a.r[(1, 1)], 2.5, epsilon = 1e-12);
        // Eq. C6: P_k⁻¹ = P⁻¹ + Hᵀ R'⁻¹ H -> P_xx = 1/(1 + 1 + 1/2.5).
        let pk = updated_covariance(&p, &a).unwrap();
        assert_relative_eq!(pk[(POS, POS)], 1.0 / 2.4, epsilon = 1e-12);
        // Eq. C5 (information form) equals the gain form: with both
        // adapted innovations zero the state correction is zero; with v = (1, 7)
        // the adapted v is (1, 7 − ∇̂) and δx = P_k Hᵀ R'⁻¹ v'.
        let l2 = lin(&[POS, POS], &[1.0, 7.0], 1.0);
        let (a2, n2, _) = adapt(&l2, &pv, 1).unwrap();
        // P_v⁻¹ v = (2·1 − 7, −1 + 14)/3 = (−5/3, 13/3) -> ∇̂ = (13/3)/(2/3) = 6.5.
        assert_relative_eq!(n2, 6.5, epsilon = 1e-12);
        let dx_info = pk[(POS, POS)] * (a2.v[0] / 1.0 + a2.v[1] / 2.5);
        let pd = DMatrix::from_column_slice(N, N, p.as_slice());
        let s = &a2.h * &pd * a2.h.transpose() + &a2.r;
        let k = &pd * a2.h.transpose() * s.try_inverse().unwrap();
        let dx_gain = (&k * &a2.v)[POS];
        assert_relative_eq!(dx_info, dx_gain, epsilon = 1e-12);
        assert_relative_eq!(dx_info, (1.0 + 0.5 / 2.5) / 2.4, epsilon = 1e-12);
    }

    fn sky() -> (TcEkf, Vec<PrMeas>) {
        use crate::tight::tc_ekf::{EkfConfig, NavState};
        use nalgebra::{UnitQuaternion, Vector3};
        let x = NavState {
            q: UnitQuaternion::identity(),
            v: Vector3::zeros(),
            p: Vector3::zeros(),
            bg: Vector3::zeros(),
            ba: Vector3::zeros(),
            clk: 0.0,
            drift: 0.0,
        };
        let ekf = TcEkf::new(x, EkfConfig::default()).unwrap();
        let dirs = [(0.0, 0.0, -1.0), (0.8, 0.0, -0.6), (-0.4, 0.7, -0.6), (-0.4, -0.7, -0.6), (0.0, 0.9, -0.44), (0.6, -0.6, -0.53)];
        let meas = dirs
            .iter()
            .enumerate()
            .map(|(i, d)| {
                let sat = Vector3::new(d.0, d.1, d.2).normalize() * 2.2e7;
                PrMeas { prn: i as u8 + 1, pr: sat.norm(), sat }
            })
            .collect();
        (ekf, meas)
    }

    #[test]
    fn reconfigurator_actions() {
        let (ekf0, clean) = sky();
        let mut faulty = clean.clone();
        faulty[2].pr += 60.0; // PRN 3
        let run = |strategy: Strategy, eta: f64| {
            let mut ekf = ekf0.clone();
            let gan = (strategy == Strategy::Gan).then(|| crate::tight::gan_fdsr::default_model().unwrap());
            let mut r = Reconfigurator::new(FdsrConfig { strategy, alpha: 0.001, eta }, Box::new(FilterPredictor::new(9.0)), gan).unwrap();
            let d0 = r.epoch(&mut ekf, &clean, 0.0);
            assert_eq!(d0.detection, None);
            assert_eq!(d0.action, Action::UpdateAll);
            let d1 = r.epoch(&mut ekf, &faulty, 1.0);
            (d1, r, ekf)
        };
        // No detection: everything is used, and the 60 m moves the estimate.
        let (d, _, e) = run(Strategy::None, 0.1);
        assert_eq!((d.detection, d.action), (None, Action::UpdateAll));
        assert!(d.lambda_max > 3.29);
        assert!(e.x.p.norm() > 1.0, "{}", e.x.p);
        // FDI names PRN 3 and isolates it: the estimate barely moves.
        let (d, _, e) = run(Strategy::Fdi, 0.1);
        assert_eq!(d.detection.map(|x| x.prn), Some(3));
        assert_eq!(d.action, Action::Isolate);
        assert!(d.rdpop.is_some_and(|r| r > 0.0));
        assert!(e.x.p.norm() < 0.5, "{}", e.x.p);
        // FDA adapts it; the adapted innovation is consistent, so the estimate
        // also stays put.
        let (d, _, e) = run(Strategy::Fda, 0.1);
        assert_eq!((d.detection.map(|x| x.prn), d.action), (Some(3), Action::Adapt));
        assert!(e.x.p.norm() < 0.5, "{}", e.x.p);
        // Switch: η below the RDPOP reconstructs, η above isolates.
        let (d, r, e) = run(Strategy::Switch, 0.0);
        assert_eq!((d.detection.map(|x| x.prn), d.action), (Some(3), Action::Reconstruct));
        assert!(r.under_repair.contains_key(&3));
        assert!(e.x.p.norm() < 0.5, "{}", e.x.p);
        let (d, mut r, mut e) = run(Strategy::Switch, 1.0e9);
        assert_eq!(d.action, Action::Isolate);
        // Still faulty next epoch: kept under repair by the predictor test.
        let d2 = r.epoch(&mut e, &faulty, 2.0);
        assert_eq!(d2.detection.map(|x| x.prn), Some(3));
        // Healthy again: released.
        let d3 = r.epoch(&mut e, &clean, 3.0);
        assert_eq!(d3.detection, None);
        assert!(r.under_repair.is_empty());
    }

    #[test]
    fn filter_predictor_eq12() {
        let mut fp = FilterPredictor::new(9.0);
        assert!(fp.reconstruct(0.0, 5, 100.0).is_none());
        fp.observe(0.0, 5, 103.0, 100.0);
        // First offset is taken as is: ρ̂ = predicted + 3.
        let r = fp.reconstruct(10.0, 5, 250.0).unwrap();
        assert_relative_eq!(r.pr, 253.0);
        // σ grows 0.5 m/s with age: 9 + (0.5·10)².
        assert_relative_eq!(r.variance, 9.0 + 25.0, epsilon = 1e-12);
        // Exponential smoothing with weight 0.2: 0.8·3 + 0.2·(−2) = 2.
        fp.observe(1.0, 5, 98.0, 100.0);
        assert_relative_eq!(fp.reconstruct(1.0, 5, 0.0).unwrap().pr, 2.0, epsilon = 1e-12);
        // Too old.
        assert!(fp.reconstruct(200.0, 5, 0.0).is_none());
    }
}
