//! Detection function (§3.2): latent search, generation and discrimination
//! scores, `Score(y)`, the threshold `T2`, and model serialization.

use serde::{Deserialize, Serialize};

use super::adam::Adam;
use super::gru::sigmoid;
use super::net::{DiscNet, GenNet, NetWork};
use super::{GanConfig, GanModel};
use crate::rng::Rng;
use crate::tight::stats::normal_upper_quantile;
use crate::tight::TightError;

/// Detection result for one window.
#[derive(Clone, Debug, PartialEq)]
pub struct Score {
    /// Generation score `Gs = ‖y − G(z_k)‖` (Euclidean over all `w·m`).
    pub gs: f64,
    /// `Gs` min–max normalised with `R_G` of the training windows (not
    /// clipped: abnormal windows exceed 1).
    pub gs_norm: f64,
    /// `D(y)`, probability "real".
    pub d: f64,
    /// `λ·gs_norm + (1 − λ)·(1 − d)`.
    pub score: f64,
    /// Latent found by the search (`w × latent`); shift it with
    /// [`GanModel::shift_latent`] to warm-start the next window.
    pub z: Vec<f64>,
    /// `G(z_k)` (`w × m`).
    pub generated: Vec<f64>,
    /// Pearson correlation `ρ(y, G(z_k))`, so `Λ = 1 − corr`.
    pub corr: f64,
}

/// Threshold fitted by [`GanModel::calibrate`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Threshold {
    /// Tolerated false-alarm rate α.
    pub alpha: f64,
    /// Mean of the fault-free scores (the paper's H0: `Score ~ N(μ, σ)`).
    pub mu: f64,
    /// Sample standard deviation of the fault-free scores.
    pub sigma: f64,
    /// `μ + z_{1−α} σ`.
    pub t2_normal: f64,
    /// Empirical (1 − α) quantile of the fault-free scores.
    pub t2_empirical: f64,
    /// Stored threshold: the larger of the two, because the scores are
    /// bounded below and right-skewed, so the normal fit can undershoot the
    /// tail while the empirical quantile alone is noisy for small samples.
    pub t2: f64,
    /// Fraction of the calibration windows with `score > t2`.
    pub false_alarm: f64,
    /// Number of calibration windows.
    pub n: usize,
}

/// Reusable buffers for [`GanModel::score_with`] (avoids re-allocating the
/// network caches for every window).
#[derive(Clone, Debug, Default)]
pub struct GanScratch {
    gen: NetWork,
    disc: NetWork,
    adam: Option<Adam>,
    dg: Vec<f64>,
    dz: Vec<f64>,
}

const MAGIC: &[u8; 5] = b"NGGAN";
const VERSION: u8 = 1;
const HEADER: usize = 5 + 1 + 4 + 8;
const COLD_START_SALT: u64 = 0xC01D_5EED_0000_0001;

fn fnv1a(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in bytes {
        h ^= u64::from(*b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

/// Length and finiteness check of one input vector.
pub(crate) fn check_vec(field: &str, v: &[f64], len: usize) -> Result<(), TightError> {
    if v.len() != len {
        return Err(TightError::new(field, format!("length must be {len}, got {}", v.len())));
    }
    if let Some(i) = v.iter().position(|x| !x.is_finite()) {
        return Err(TightError::new(format!("{field}[{i}]"), format!("must be finite, got {}", v[i])));
    }
    Ok(())
}

/// Pearson correlation `ρ(y, g)` over all elements; writes `∂ρ/∂g` into
/// `grad` when given. With centred `a = y − ȳ`, `b = g − ḡ`:
/// `ρ = a·b / (‖a‖‖b‖)` and `∂ρ/∂g = a/(‖a‖‖b‖) − ρ b/‖b‖²` (the centring
/// terms vanish because `Σa = Σb = 0`). A (numerically) constant side
/// gives `ρ = 0` and a zero gradient.
pub(crate) fn correlation(y: &[f64], g: &[f64], grad: Option<&mut [f64]>) -> f64 {
    let n = y.len().max(1) as f64;
    let my = y.iter().sum::<f64>() / n;
    let mg = g.iter().sum::<f64>() / n;
    let (mut saa, mut sbb, mut sab) = (0.0, 0.0, 0.0);
    for (yi, gi) in y.iter().zip(g) {
        let (a, b) = (yi - my, gi - mg);
        saa += a * a;
        sbb += b * b;
        sab += a * b;
    }
    let tiny = 1e-24 * n;
    if saa <= tiny || sbb <= tiny {
        if let Some(gr) = grad {
            gr.fill(0.0);
        }
        return 0.0;
    }
    let den = libm::sqrt(saa * sbb);
    let rho = sab / den;
    if let Some(gr) = grad {
        for ((o, yi), gi) in gr.iter_mut().zip(y).zip(g) {
            *o = (yi - my) / den - rho * (gi - mg) / sbb;
        }
    }
    rho
}

fn sample_std(v: &[f64]) -> f64 {
    if v.len() < 2 {
        return 0.0;
    }
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    libm::sqrt(v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1.0))
}

/// Min–max normalisation followed by the sample std (§3.2 steps 2–3).
pub(crate) fn normalised_std(v: &[f64]) -> f64 {
    let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let range = hi - lo;
    if range.is_nan() || range <= 0.0 {
        return 0.0;
    }
    let l: Vec<f64> = v.iter().map(|x| (x - lo) / range).collect();
    sample_std(&l)
}

impl GanModel {
    pub(crate) fn gen_net(cfg: &GanConfig) -> GenNet {
        GenNet { latent: cfg.latent, hidden: cfg.hidden, dim: cfg.dim }
    }

    pub(crate) fn disc_net(cfg: &GanConfig) -> DiscNet {
        DiscNet { dim: cfg.dim, hidden: cfg.hidden }
    }

    /// `G(z)`: `z` is `w × latent`, output `w × m`.
    pub fn generate(&self, z: &[f64]) -> Result<Vec<f64>, TightError> {
        check_vec("z", z, self.cfg.latent_len())?;
        let mut work = NetWork::default();
        Self::gen_net(&self.cfg).forward(&self.g, z, &mut work);
        Ok(work.y)
    }

    /// `D(y)`, probability that the `w × m` window `y` is real (normal).
    pub fn discriminate(&self, y: &[f64]) -> Result<f64, TightError> {
        check_vec("y", y, self.cfg.window_len())?;
        let mut work = NetWork::default();
        Ok(sigmoid(Self::disc_net(&self.cfg).forward(&self.d, y, &mut work)))
    }

    /// Latent `z` shifted forward by `rows` time steps for warm-starting the
    /// next window: row `t` becomes old row `t + rows`, the missing tail rows
    /// repeat the old last row.
    pub fn shift_latent(&self, z: &[f64], rows: usize) -> Result<Vec<f64>, TightError> {
        check_vec("z", z, self.cfg.latent_len())?;
        let (w, l) = (self.cfg.window, self.cfg.latent);
        let mut out = vec![0.0; z.len()];
        for t in 0..w {
            let src = (t + rows).min(w - 1);
            out[t * l..(t + 1) * l].copy_from_slice(&z[src * l..(src + 1) * l]);
        }
        Ok(out)
    }

    /// Latent search `min_z Λ = 1 − ρ(y, G(z))` (§3.2) by `z_iters` Adam
    /// steps (β1 = 0.9, rate `z_lr`) with gradients backpropagated through
    /// `G` to its inputs. `Cov` of the paper is taken as the Pearson
    /// correlation: scale-free and bounded, so `z_lr` does not depend on the
    /// data scale. The objective adds the prior term `γ‖z‖²/(2·w·latent)`
    /// (`γ` = [`GanConfig::z_prior`]). Starts from a seeded `N(0, 1)` draw
    /// (same draw on every call, so scores are reproducible), or from `z0`
    /// (warm start) when `z0` has the lower objective. Returns the iterate
    /// with the lowest objective, `(z_k, G(z_k), ρ(y, G(z_k)))`.
    pub fn search_latent(&self, y: &[f64], z0: Option<&[f64]>) -> Result<(Vec<f64>, Vec<f64>, f64), TightError> {
        let mut s = GanScratch::default();
        check_vec("y", y, self.cfg.window_len())?;
        self.search_inner(y, z0, &mut s)
    }

    fn search_inner(
        &self,
        y: &[f64],
        z0: Option<&[f64]>,
        s: &mut GanScratch,
    ) -> Result<(Vec<f64>, Vec<f64>, f64), TightError> {
        let nz = self.cfg.latent_len();
        let gn = Self::gen_net(&self.cfg);
        let gamma = self.cfg.z_prior / nz as f64;
        let mut rng = Rng::new(self.cfg.seed ^ COLD_START_SALT);
        let mut z: Vec<f64> = (0..nz).map(|_| rng.normal()).collect();
        if let Some(z0) = z0 {
            check_vec("z0", z0, nz)?;
            // Keep the warm start only if it beats the cold draw.
            let obj = |z: &[f64], w: &mut NetWork| {
                gn.forward(&self.g, z, w);
                1.0 - correlation(y, &w.y, None) + 0.5 * gamma * z.iter().map(|v| v * v).sum::<f64>()
            };
            if obj(z0, &mut s.gen) <= obj(&z, &mut s.gen) {
                z.copy_from_slice(z0);
            }
        }
        let adam = s.adam.get_or_insert_with(|| Adam::new(0, 1.0, 0.9));
        adam.reset(nz, self.cfg.z_lr, 0.9);
        s.dg.resize(y.len(), 0.0);
        s.dz.resize(nz, 0.0);
        let mut best_z = z.clone();
        let mut best_g = vec![0.0; y.len()];
        let (mut best, mut best_obj) = (0.0, f64::INFINITY);
        for it in 0..=self.cfg.z_iters {
            gn.forward(&self.g, &z, &mut s.gen);
            let rho = correlation(y, &s.gen.y, Some(&mut s.dg));
            let obj = 1.0 - rho + 0.5 * gamma * z.iter().map(|v| v * v).sum::<f64>();
            if obj < best_obj {
                (best, best_obj) = (rho, obj);
                best_z.copy_from_slice(&z);
                best_g.copy_from_slice(&s.gen.y);
            }
            if it == self.cfg.z_iters {
                break;
            }
            // ∂Λ/∂g = −∂ρ/∂g
            for v in s.dg.iter_mut() {
                *v = -*v;
            }
            gn.backward(&self.g, &z, &mut s.gen, &s.dg, None, Some(&mut s.dz));
            for (d, zi) in s.dz.iter_mut().zip(&z) {
                *d += gamma * zi;
            }
            adam.step(&mut z, &s.dz);
        }
        Ok((best_z, best_g, best))
    }

    /// `Score(y) = λ·Gs_norm + (1 − λ)·(1 − D(y))` for one `w × m` window;
    /// `z0` warm-starts the latent search (e.g. the previous window's
    /// [`Score::z`] through [`GanModel::shift_latent`]).
    pub fn score(&self, y: &[f64], z0: Option<&[f64]>) -> Result<Score, TightError> {
        self.score_with(y, z0, &mut GanScratch::default())
    }

    /// [`GanModel::score`] with caller-owned buffers.
    pub fn score_with(&self, y: &[f64], z0: Option<&[f64]>, s: &mut GanScratch) -> Result<Score, TightError> {
        check_vec("y", y, self.cfg.window_len())?;
        let d = sigmoid(Self::disc_net(&self.cfg).forward(&self.d, y, &mut s.disc));
        let (z, generated, corr) = self.search_inner(y, z0, s)?;
        let gs = libm::sqrt(y.iter().zip(&generated).map(|(a, b)| (a - b) * (a - b)).sum::<f64>());
        let range = (self.rg_max - self.rg_min).max(1e-12);
        let gs_norm = (gs - self.rg_min) / range;
        let score = self.lambda * gs_norm + (1.0 - self.lambda) * (1.0 - d);
        Ok(Score { gs, gs_norm, d, score, z, generated, corr })
    }

    /// Scores consecutive windows (as [`super::subsequences`] produces them),
    /// warm-starting each latent search from the previous `z` shifted by
    /// `step` rows, the way a streaming caller would.
    pub fn score_stream(&self, windows: &[Vec<f64>]) -> Result<Vec<Score>, TightError> {
        let mut s = GanScratch::default();
        let mut out: Vec<Score> = Vec::with_capacity(windows.len());
        for (i, y) in windows.iter().enumerate() {
            let z0 = match out.last() {
                Some(prev) => Some(self.shift_latent(&prev.z, self.cfg.step)?),
                None => None,
            };
            let sc = self
                .score_with(y, z0.as_deref(), &mut s)
                .map_err(|e| TightError::new(format!("windows[{i}].{}", e.field), e.message))?;
            out.push(sc);
        }
        Ok(out)
    }

    /// Fault decision `Score > T2` (never true before [`GanModel::calibrate`]).
    pub fn is_fault(&self, s: &Score) -> bool {
        s.score > self.t2
    }

    /// Sets `T2` from the false-alarm rate `alpha` on fault-free windows
    /// (scored as a stream, see [`GanModel::score_stream`]): fits the H0
    /// normal `N(μ, σ)` and the empirical quantile; stores the larger (see
    /// [`Threshold::t2`]).
    pub fn calibrate(&mut self, fault_free: &[Vec<f64>], alpha: f64) -> Result<Threshold, TightError> {
        if !(alpha > 0.0 && alpha < 1.0) {
            return Err(TightError::new("alpha", format!("must be in (0, 1), got {alpha}")));
        }
        if fault_free.len() < 2 {
            return Err(TightError::new("fault_free", format!("need ≥ 2 windows, got {}", fault_free.len())));
        }
        let mut sc: Vec<f64> = self.score_stream(fault_free)?.iter().map(|s| s.score).collect();
        let n = sc.len();
        let mu = sc.iter().sum::<f64>() / n as f64;
        let sigma = sample_std(&sc);
        let t2_normal = mu + normal_upper_quantile(alpha)? * sigma;
        sc.sort_by(f64::total_cmp);
        let k = (libm::ceil((1.0 - alpha) * n as f64) as usize).clamp(1, n) - 1;
        let t2_empirical = sc[k];
        let t2 = t2_normal.max(t2_empirical);
        let false_alarm = sc.iter().filter(|&&v| v > t2).count() as f64 / n as f64;
        self.t2 = t2;
        Ok(Threshold { alpha, mu, sigma, t2_normal, t2_empirical, t2, false_alarm, n })
    }

    /// `"NGGAN"`, version byte, payload length (u32 LE), FNV-1a 64 of the
    /// payload (u64 LE), then the postcard payload.
    pub fn to_bytes(&self) -> Result<Vec<u8>, TightError> {
        let payload = postcard::to_allocvec(self).map_err(|e| TightError::new("model", format!("serialize: {e}")))?;
        let len = u32::try_from(payload.len())
            .map_err(|_| TightError::new("model", format!("payload too large: {} bytes", payload.len())))?;
        let mut out = Vec::with_capacity(HEADER + payload.len());
        out.extend_from_slice(MAGIC);
        out.push(VERSION);
        out.extend_from_slice(&len.to_le_bytes());
        out.extend_from_slice(&fnv1a(&payload).to_le_bytes());
        out.extend_from_slice(&payload);
        Ok(out)
    }

    /// Inverse of [`GanModel::to_bytes`]; damaged input gives an error
    /// (bad magic/version, wrong length, checksum, or weight shapes that do
    /// not match the stored config).
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, TightError> {
        let field = "bytes";
        if bytes.len() < HEADER {
            return Err(TightError::new(field, format!("{} bytes, shorter than the {HEADER}-byte header", bytes.len())));
        }
        let (head, payload) = bytes.split_at(HEADER);
        if &head[..5] != MAGIC {
            return Err(TightError::new(field, format!("bad magic {:?}", &head[..5])));
        }
        if head[5] != VERSION {
            return Err(TightError::new(field, format!("unsupported version {}, expected {VERSION}", head[5])));
        }
        let mut len4 = [0u8; 4];
        len4.copy_from_slice(&head[6..10]);
        let len = u32::from_le_bytes(len4) as usize;
        if payload.len() != len {
            return Err(TightError::new(field, format!("payload is {} bytes, header says {len}", payload.len())));
        }
        let mut sum8 = [0u8; 8];
        sum8.copy_from_slice(&head[10..18]);
        if fnv1a(payload) != u64::from_le_bytes(sum8) {
            return Err(TightError::new(field, "checksum mismatch (damaged payload)"));
        }
        let m: GanModel =
            postcard::from_bytes(payload).map_err(|e| TightError::new(field, format!("decode: {e}")))?;
        m.validate()?;
        Ok(m)
    }

    /// Shape and value checks of a deserialized model.
    pub(crate) fn validate(&self) -> Result<(), TightError> {
        self.cfg.check()?;
        check_vec("g", &self.g, Self::gen_net(&self.cfg).len())?;
        check_vec("d", &self.d, Self::disc_net(&self.cfg).len())?;
        if !(0.0..=1.0).contains(&self.lambda) {
            return Err(TightError::new("lambda", format!("must be in [0, 1], got {}", self.lambda)));
        }
        if !(self.rg_min.is_finite() && self.rg_max.is_finite() && self.rg_min <= self.rg_max) {
            return Err(TightError::new("rg_range", format!("bad range [{}, {}]", self.rg_min, self.rg_max)));
        }
        for (name, v) in [("s_g", self.s_g), ("s_d", self.s_d)] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(TightError::new(name, format!("must be finite and ≥ 0, got {v}")));
            }
        }
        if self.t2.is_nan() || self.t2 == f64::NEG_INFINITY {
            return Err(TightError::new("t2", format!("must be finite or +inf, got {}", self.t2)));
        }
        Ok(())
    }
}
