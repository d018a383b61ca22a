//! GAN-FDSR detection and reconstruction per satellite (Shen et al. 2022,
//! §2.2 and §3.2–3.3): the pseudo-range increment difference ρD (eq. 10) of
//! each satellite, standardised, reconstructed in phase space (eq. 16) and cut
//! into the window `y_new` (w phase points × m); the trained GRU GAN scores
//! it (`Score = λ·Gs + (1 − λ)·(1 − D)`) against T2, and its generator
//! supplies the increment difference that rebuilds a faulty pseudo-range by
//! eq. 12.
//!
//! ρ_I is the filter's predicted pseudo-range before the update (INS position
//! and clock), so `ρ_G − ρ_I` is the innovation `v` and `ρD_k = v_k − v_{k−1}`.

use std::collections::{BTreeMap, VecDeque};

use serde::{Deserialize, Serialize};

use super::gan::{GanModel, GanScratch, Score};
use super::predict::Reconstruction;
use super::TightError;

/// The per-satellite series the GAN sees.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum GanInput {
    /// The paper's ρD (eq. 10), m: a step shows only at its onset and a
    /// ramp only as a small mean shift.
    IncrementDifference,
    /// The normalised innovation λ (eq. A2) itself: a step or a ramp shifts
    /// its level for as long as it lasts (our variant).
    Innovation,
}

impl GanInput {
    /// Short name in reports: "rhoD" or "lambda".
    pub fn name(self) -> &'static str {
        match self {
            GanInput::IncrementDifference => "rhoD",
            GanInput::Innovation => "lambda",
        }
    }
}

/// A trained detector: the GAN plus the pre-processing it was trained with.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct GanDetectorModel {
    /// Which series the GAN was trained on.
    pub input: GanInput,
    /// Also flag a satellite whose |λ| exceeds T1 (the Appendix A test),
    /// with T2 set at α/2 so the two tests share the false-alarm budget α.
    /// A large step then is flagged at its first epoch, where the windowed
    /// GAN score needs a few samples.
    #[serde(default)]
    pub lambda_test: bool,
    /// Delay τ of the phase-space reconstruction, epochs.
    pub tau: usize,
    /// Embedding dimension m (the GAN's feature count).
    pub m: usize,
    /// Mean and standard deviation of the series on the fault-free training
    /// data (m for ρD, unitless for λ).
    pub mean: f64,
    /// Standard deviation of the series (same units as `mean`).
    pub scale: f64,
    /// RMS of `y − G(z_k)` per element on the training windows (standardised
    /// units): the error of one generated increment difference.
    pub gen_rms: f64,
    /// The GAN, its λ and its threshold T2.
    pub gan: GanModel,
    /// How the model was made (command line, seeds), for reports.
    pub provenance: String,
}

const MAGIC: &[u8; 8] = b"NGGANFD1";

impl GanDetectorModel {
    /// ρD samples one window needs: `w + (m − 1)·τ`.
    pub fn span(&self) -> usize {
        self.gan.config().window + (self.m - 1) * self.tau
    }

    /// The window `y_new` (w × m, row-major, time-major) from the last
    /// [`span`](Self::span) standardised samples, oldest first.
    pub fn window_into(&self, hist: &VecDeque<f64>, y: &mut Vec<f64>) -> bool {
        let span = self.span();
        if hist.len() < span {
            return false;
        }
        let base = hist.len() - span;
        let w = self.gan.config().window;
        y.clear();
        for t in 0..w {
            for k in 0..self.m {
                y.push(hist[base + t + k * self.tau]);
            }
        }
        true
    }

    /// The model as bytes (magic, then postcard).
    pub fn to_bytes(&self) -> Result<Vec<u8>, TightError> {
        let mut out = MAGIC.to_vec();
        let body = postcard::to_allocvec(self).map_err(|e| TightError::new("gan model", format!("cannot encode: {e}")))?;
        out.extend_from_slice(&body);
        Ok(out)
    }

    /// A model read back from [`GanDetectorModel::to_bytes`], checked (a forged model is an error).
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, TightError> {
        let body = bytes
            .strip_prefix(MAGIC.as_slice())
            .ok_or_else(|| TightError::new("gan model", "not a navguard GAN-FDSR model (bad magic)"))?;
        let m: GanDetectorModel = postcard::from_bytes(body).map_err(|e| TightError::new("gan model", format!("damaged: {e}")))?;
        m.check()?;
        Ok(m)
    }

    pub(crate) fn check(&self) -> Result<(), TightError> {
        // Weights, shapes and thresholds: a forged model must fail here, not
        // index out of range during inference.
        self.gan.validate()?;
        if self.tau == 0 || self.tau > 1000 || self.m == 0 || self.m != self.gan.config().dim {
            return Err(TightError::new("gan model", format!("tau {} (1..=1000) / m {} do not match the GAN (dim {})", self.tau, self.m, self.gan.config().dim)));
        }
        if !(self.scale.is_finite() && self.scale > 0.0 && self.mean.is_finite() && self.gen_rms.is_finite() && self.gen_rms >= 0.0) {
            return Err(TightError::new("gan model", format!("bad normalisation: mean {}, scale {}, gen_rms {}", self.mean, self.scale, self.gen_rms)));
        }
        Ok(())
    }
}

/// The default model, trained by `cargo run --release -p navguard-examples --bin navguard-gan -- train`
/// (see `docs/tight.md`) and embedded in the library.
pub fn default_model() -> Result<GanDetectorModel, TightError> {
    let bytes = include_bytes!("gan_default.bin");
    if bytes.is_empty() {
        return Err(TightError::new("strategy", "no GAN-FDSR model is embedded in this build (run `navguard-gan train`)"));
    }
    GanDetectorModel::from_bytes(bytes)
}

/// Per-satellite state.
#[derive(Clone, Debug, Default)]
struct Sat {
    /// Time (s) and innovation (m) of the last epoch the satellite was seen.
    last: Option<(f64, f64)>,
    /// Standardised ρD history, newest last (at most `span` long).
    hist: VecDeque<f64>,
    /// z_k of the last search, the warm start of the next one.
    z: Option<Vec<f64>>,
    /// Healthy innovations, the base of a reconstruction (newest last).
    healthy_v: VecDeque<f64>,
    /// Under repair: offset `ρ̂_G − ρ_I` (m), its variance (m²) and the
    /// generated innovation of the λ input (m), eq. 12.
    repair: Option<(f64, f64, f64)>,
}

/// One satellite's result at an epoch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SatScore {
    /// Satellite id.
    pub prn: u8,
    /// Score of eq. (Score), or NaN while the window is filling.
    pub score: f64,
    /// Generated increment difference of the newest sample, m.
    pub generated: f64,
}

/// Runs the GAN detection function over every satellite of each epoch.
pub struct GanMonitor {
    /// The trained detector.
    pub model: GanDetectorModel,
    /// Longest gap (s) that keeps a satellite's history: one missed epoch
    /// at the 1 Hz the models are trained on. Below 0.4 Hz the windows never
    /// fill and only the λ test (if the model has it) runs.
    pub max_gap: f64,
    sats: BTreeMap<u8, Sat>,
    y: Vec<f64>,
    scratch: GanScratch,
}

/// Healthy innovations averaged into a reconstruction's starting offset: the
/// mean of the last few damps their white noise.
const BASE_EPOCHS: usize = 5;

impl GanMonitor {
    /// A monitor with no satellite history yet.
    pub fn new(model: GanDetectorModel) -> Self {
        GanMonitor { model, max_gap: 2.5, sats: BTreeMap::new(), y: Vec::new(), scratch: GanScratch::default() }
    }

    /// Detection threshold T2.
    pub fn t2(&self) -> f64 {
        self.model.gan.t2()
    }

    /// Feed the epoch's innovations `v_i = ρ_G − ρ_I` (m) at time `t` (s) and
    /// score every satellite whose window is full. Satellites under repair
    /// get the generated increment difference in their history in place of
    /// the measured one, so the generator keeps a fault-free context.
    /// `lam`: the normalised innovations λ of the same satellites, and `sd`
    /// the standard deviation of each predicted pseudo-range's innovation
    /// (√P_v,ii, m), used by the λ input.
    pub fn epoch(&mut self, t: f64, prns: &[u8], v: &[f64], lam: &[f64], sd: &[f64]) -> Result<Vec<SatScore>, TightError> {
        let model = &self.model;
        let span = model.span();
        let mut out = Vec::with_capacity(prns.len());
        self.sats.retain(|p, s| prns.contains(p) || s.last.is_some_and(|(lt, _)| t - lt <= self.max_gap));
        for (k, (&prn, &vi)) in prns.iter().zip(v).enumerate() {
            let s = self.sats.entry(prn).or_default();
            let rd = match s.last {
                Some((lt, lv)) if t - lt <= self.max_gap && t > lt => Some(match model.input {
                    GanInput::IncrementDifference => vi - lv,
                    GanInput::Innovation => lam.get(k).copied().unwrap_or(f64::NAN),
                }),
                _ => {
                    s.hist.clear();
                    s.z = None;
                    None
                }
            };
            s.last = Some((t, vi));
            let Some(rd) = rd.filter(|x| x.is_finite()) else {
                out.push(SatScore { prn, score: f64::NAN, generated: f64::NAN });
                continue;
            };
            s.hist.push_back((rd - model.mean) / model.scale);
            while s.hist.len() > span {
                s.hist.pop_front();
            }
            if !model.window_into(&s.hist, &mut self.y) {
                out.push(SatScore { prn, score: f64::NAN, generated: f64::NAN });
                continue;
            }
            let sc: Score = model.gan.score_with(&self.y, s.z.as_deref(), &mut self.scratch)?;
            let gen_std = sc.generated.last().copied().unwrap_or(0.0).clamp(-4.0, 4.0);
            let generated = model.mean + model.scale * gen_std;
            // Next epoch's window is this one shifted by one phase point:
            // shift z the same way as the warm start.
            s.z = Some(model.gan.shift_latent(&sc.z, 1)?);
            if let Some((off, var, gen)) = s.repair.as_mut() {
                match model.input {
                    // eq. 12: ρ̂_G(k) − ρ_I(k) = ρ̂_G(k−1) − ρ_I(k−1) + ρD_G(k).
                    GanInput::IncrementDifference => {
                        *off += generated;
                        let g = model.gen_rms * model.scale;
                        *var += g * g;
                    }
                    // The generated innovation, in metres, on top of the
                    // healthy offset.
                    GanInput::Innovation => {
                        *gen = generated * sd.get(k).copied().unwrap_or(0.0);
                    }
                }
                if let Some(last) = s.hist.back_mut() {
                    *last = gen_std;
                }
            }
            out.push(SatScore { prn, score: sc.score, generated });
        }
        Ok(out)
    }

    /// A measurement accepted as healthy: its innovation (m) is a base for
    /// later reconstructions.
    pub fn healthy(&mut self, prn: u8, v: f64) {
        if let Some(s) = self.sats.get_mut(&prn) {
            s.healthy_v.push_back(v);
            while s.healthy_v.len() > BASE_EPOCHS {
                s.healthy_v.pop_front();
            }
            s.repair = None;
        }
    }

    /// Start rebuilding `prn` from its healthy history (R: the measurement
    /// variance, m²). False when there is no healthy history.
    pub fn start_repair(&mut self, prn: u8, r: f64) -> bool {
        let Some(s) = self.sats.get_mut(&prn) else { return false };
        if s.repair.is_some() {
            return true;
        }
        if s.healthy_v.is_empty() {
            return false;
        }
        let n = s.healthy_v.len() as f64;
        let off = s.healthy_v.iter().sum::<f64>() / n;
        s.repair = Some((off, r / n, 0.0));
        true
    }

    /// The satellite is healthy again: drop its repair state.
    pub fn end_repair(&mut self, prn: u8) {
        if let Some(s) = self.sats.get_mut(&prn) {
            s.repair = None;
        }
    }

    /// The rebuilt pseudo-range of a satellite under repair, given the
    /// filter's predicted one (m).
    pub fn reconstruct(&self, prn: u8, predicted: f64) -> Option<Reconstruction> {
        let (off, var, gen) = self.sats.get(&prn)?.repair?;
        Some(Reconstruction { pr: predicted + off + gen, variance: var })
    }
}

#[cfg(all(test, not(target_arch = "wasm32")))]
mod tests {
    use super::*;

    #[test]
    fn embedded_models_load_and_round_trip() {
        let m = default_model().unwrap();
        assert_eq!(m.input, GanInput::Innovation);
        assert!(m.provenance.starts_with("navguard-gan train"), "{}", m.provenance);
        assert!(m.gan.t2().is_finite() && m.gan.t2() > 0.0);
        assert!(m.gan.lambda() > 0.0 && m.gan.lambda() < 1.0);
        let bytes = m.to_bytes().unwrap();
        let back = GanDetectorModel::from_bytes(&bytes).unwrap();
        assert_eq!(back.gan, m.gan);
        assert_eq!((back.tau, back.m, back.mean.to_bits(), back.scale.to_bits()), (m.tau, m.m, m.mean.to_bits(), m.scale.to_bits()));
        // Damaged bytes are errors, never panics.
        let e = GanDetectorModel::from_bytes(&bytes[..bytes.len() / 2]).unwrap_err();
        assert_eq!(e.field, "gan model");
        let mut bad = bytes.clone();
        bad[0] ^= 1;
        assert!(GanDetectorModel::from_bytes(&bad).unwrap_err().message.contains("magic"));
        assert!(GanDetectorModel::from_bytes(&[]).is_err());
        // The paper-faithful ρD model of `navguard-gan table5` loads too.
        let rhod = GanDetectorModel::from_bytes(include_bytes!("gan_rhod.bin")).unwrap();
        assert_eq!((rhod.input, rhod.lambda_test), (GanInput::IncrementDifference, false));
        // Well-formed bytes of a forged model: refused by the checks.
        let mut forged = m.clone();
        forged.tau = usize::MAX / 2;
        assert!(GanDetectorModel::from_bytes(&forged.to_bytes().unwrap()).unwrap_err().message.contains("tau"));
        let mut forged = m.clone();
        forged.m += 1;
        assert!(GanDetectorModel::from_bytes(&forged.to_bytes().unwrap()).is_err());
    }

    #[test]
    fn window_is_the_phase_space_of_the_last_span_samples() {
        let mut m = default_model().unwrap();
        m.tau = 2;
        let (w, dim) = (m.gan.config().window, m.m);
        let span = m.span();
        assert_eq!(span, w + (dim - 1) * 2);
        // Older samples than the span are ignored.
        let hist: VecDeque<f64> = (0..span + 3).map(|x| x as f64).collect();
        let mut y = Vec::new();
        assert!(m.window_into(&hist, &mut y));
        assert_eq!(y.len(), w * dim);
        for t in 0..w {
            for k in 0..dim {
                assert_eq!(y[t * dim + k], (3 + t + 2 * k) as f64, "t {t} k {k}");
            }
        }
        // The newest sample is the last coordinate of the last phase point.
        assert_eq!(*y.last().unwrap(), (span + 2) as f64);
        let short: VecDeque<f64> = (0..span - 1).map(|x| x as f64).collect();
        assert!(!m.window_into(&short, &mut y));
    }

    /// A satellite that keeps a 4σ offset is scored above T2 once its window
    /// is full; clean satellites stay below; a gap restarts the window.
    #[test]
    fn monitor_scores_a_level_shift_above_t2() {
        let model = default_model().unwrap();
        let span = model.span();
        let mut mon = GanMonitor::new(model);
        let mut rng = crate::rng::Rng::new(5);
        let mut last = Vec::new();
        for k in 0..(span + 5) {
            let lam: Vec<f64> = (0..4).map(|i| rng.normal() + if i == 2 && k > span / 2 { 4.0 } else { 0.0 }).collect();
            last = mon.epoch(k as f64, &[3, 5, 7, 9], &[0.0; 4], &lam, &[3.0; 4]).unwrap();
        }
        let t2 = mon.t2();
        assert!(last[2].score > t2, "shifted satellite score {} vs T2 {t2}", last[2].score);
        for i in [0, 1, 3] {
            assert!(last[i].score.is_finite() && last[i].score < last[2].score, "{:?}", last);
        }
        // After a 5 s gap the history restarts: no score until the window refills.
        let after = mon.epoch((span + 10) as f64, &[3, 5, 7, 9], &[0.0; 4], &[0.0; 4], &[3.0; 4]).unwrap();
        assert!(after.iter().all(|s| s.score.is_nan()));
    }

    #[test]
    fn repair_rebuilds_from_the_healthy_offset() {
        let mut mon = GanMonitor::new(default_model().unwrap());
        assert!(!mon.start_repair(4, 9.0), "no history, no repair");
        mon.epoch(0.0, &[4], &[2.0], &[0.5], &[3.0]).unwrap();
        for v in [1.0, 2.0, 3.0] {
            mon.healthy(4, v);
        }
        assert!(mon.start_repair(4, 9.0));
        let r = mon.reconstruct(4, 1000.0).unwrap();
        // Mean healthy innovation 2 m on top of the predicted range; variance R/n.
        assert!((r.pr - 1002.0).abs() < 1e-12 && (r.variance - 3.0).abs() < 1e-12, "{r:?}");
        mon.end_repair(4);
        assert!(mon.reconstruct(4, 1000.0).is_none());
    }
}
