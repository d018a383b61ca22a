//! GRU GAN fault detector of Shen et al. 2022, "GAN-FDSR" §3.1–3.2,
//! hand-written over plain `f64` slices (no ML dependency; builds for wasm32).
//!
//! Data layout: a window ("subsequence") `y` is `w` time steps × `m`
//! features, row-major and time-major (`y[t*m + k]`), length `w·m`. A
//! latent sequence `z` is `w × latent` (the paper takes `z` with the
//! dimension of `Y`).
//!
//! * [`subsequences`]: sliding windows over the `M × m` phase-space matrix.
//! * [`train`]: adversarial training (§3.1), then the fit statistics of §3.2
//!   (`R_G` min/max, `S_G`, `S_D`, `λ`).
//! * [`GanModel::score`]: latent search `min_z 1 − ρ(y, G(z))`, generation
//!   score, discrimination score and `Score(y)`; [`GanModel::calibrate`]
//!   sets `T2` from a false-alarm rate.
//!
//! Networks: see `net` (GRU generator with a per-step linear head; GRU
//! discriminator with mean pooling) and `gru` (gate convention).
//!
//! Deviations from the paper, each documented where it is made:
//! * `Cov` in Λ is the Pearson correlation (scale-free, bounded).
//! * The discrimination part of `Score` is `1 − D(y)`, so that both parts grow
//!   with abnormality (the paper writes `D(y)`, which would *lower* the score
//!   of a sequence the discriminator rejects).
//! * The latent search adds a Gaussian prior term `γ‖z‖²/(2·w·latent)`
//!   ([`GanConfig::z_prior`]) and keeps a warm start only when it beats the
//!   seeded cold draw: without these, warm-started chains drifted to
//!   `rms(z) ≈ 15`, far outside the training prior, and fitted worse.
//! * `R_G` is computed with the same latent search as at detection time
//!   (the paper's `G(z_s)` is ambiguous), so the normalisation matches.
//! * `T2 = max(μ + z_{1−α}σ, empirical (1−α) quantile)`, see [`Threshold`].

mod adam;
mod gru;
mod net;
mod score;
mod train;

#[cfg(all(test, not(target_arch = "wasm32")))]
mod tests;

use serde::{Deserialize, Serialize};

use super::TightError;

pub use score::{GanScratch, Score, Threshold};
pub use train::train;

/// Hyper-parameters. Sizes are capped (see [`GanConfig::check`]) so a damaged
/// model file cannot request huge allocations.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GanConfig {
    /// Window length `w` (rows per subsequence).
    pub window: usize,
    /// Sliding-window step `u` (rows); also the shift used for warm starts.
    pub step: usize,
    /// Features per row `m` (phase-space embedding dimension).
    pub dim: usize,
    /// Latent features per time step.
    pub latent: usize,
    /// GRU hidden size (generator and discriminator).
    pub hidden: usize,
    /// Passes over the training windows.
    pub epochs: usize,
    /// Minibatch size.
    pub batch: usize,
    /// Adam learning rate of the generator.
    pub lr_g: f64,
    /// Adam learning rate of the discriminator.
    pub lr_d: f64,
    /// Seed for init, shuffling, latent draws and cold-start latent search.
    pub seed: u64,
    /// Adam steps of the latent search per scored window.
    pub z_iters: usize,
    /// Adam learning rate of the latent search.
    pub z_lr: f64,
    /// Weight `γ` of the Gaussian prior term `γ·‖z‖²/(2·w·latent)` added to
    /// Λ in the latent search (not in the paper: without it warm-started
    /// searches drift to large `‖z‖`, outside what `G` was trained on).
    pub z_prior: f64,
}

impl Default for GanConfig {
    fn default() -> Self {
        GanConfig {
            window: 10,
            step: 1,
            dim: 5,
            latent: 5,
            hidden: 16,
            epochs: 30,
            batch: 32,
            lr_g: 2e-3,
            lr_d: 1e-3,
            seed: 1,
            z_iters: 30,
            z_lr: 0.1,
            z_prior: 0.1,
        }
    }
}

/// Upper bound on every size field.
pub const MAX_SIZE: usize = 4096;

impl GanConfig {
    /// Validates every field; the error names the field and its value.
    pub fn check(&self) -> Result<(), TightError> {
        let sizes = [
            ("window", self.window),
            ("step", self.step),
            ("dim", self.dim),
            ("latent", self.latent),
            ("hidden", self.hidden),
            ("epochs", self.epochs),
            ("batch", self.batch),
        ];
        for (name, v) in sizes {
            if v == 0 || v > MAX_SIZE {
                return Err(TightError::new(name, format!("must be in 1..={MAX_SIZE}, got {v}")));
            }
        }
        if self.z_iters > 100_000 {
            return Err(TightError::new("z_iters", format!("must be ≤ 100000, got {}", self.z_iters)));
        }
        for (name, v) in [("lr_g", self.lr_g), ("lr_d", self.lr_d), ("z_lr", self.z_lr)] {
            if !(v.is_finite() && v > 0.0 && v <= 1.0) {
                return Err(TightError::new(name, format!("must be in (0, 1], got {v}")));
            }
        }
        if !(self.z_prior.is_finite() && (0.0..=1e6).contains(&self.z_prior)) {
            return Err(TightError::new("z_prior", format!("must be in [0, 1e6], got {}", self.z_prior)));
        }
        Ok(())
    }

    /// Elements of one window, `w·m`.
    pub fn window_len(&self) -> usize {
        self.window * self.dim
    }

    /// Elements of one latent sequence, `w·latent`.
    pub fn latent_len(&self) -> usize {
        self.window * self.latent
    }
}

/// Sliding windows over the `M × m` row-major matrix `y`: window `w` rows,
/// step `u` rows, `n = ⌊(M − w)/u⌋ + 1` windows (§3.1; the paper's
/// `(M − w)/u` omits the first window). Each window is `w·m` long.
pub fn subsequences(y: &[f64], m: usize, w: usize, u: usize) -> Result<Vec<Vec<f64>>, TightError> {
    for (name, v) in [("m", m), ("w", w), ("u", u)] {
        if v == 0 {
            return Err(TightError::new(name, "must be ≥ 1, got 0"));
        }
    }
    if !y.len().is_multiple_of(m) {
        return Err(TightError::new("y", format!("length {} is not a multiple of m = {m}", y.len())));
    }
    if let Some(i) = y.iter().position(|v| !v.is_finite()) {
        return Err(TightError::new(format!("y[{i}]"), format!("must be finite, got {}", y[i])));
    }
    let rows = y.len() / m;
    if rows < w {
        return Err(TightError::new("y", format!("{rows} rows, fewer than the window w = {w}")));
    }
    let n = (rows - w) / u + 1;
    Ok((0..n).map(|s| y[s * u * m..(s * u + w) * m].to_vec()).collect())
}

/// Per-epoch training report (means over the epoch's minibatches).
#[derive(Clone, Debug, PartialEq)]
pub struct TrainProgress {
    /// 1-based epoch just finished.
    pub epoch: usize,
    /// Epochs in the whole training.
    pub epochs: usize,
    /// `−[log D(x) + log(1 − D(G(z)))]`.
    pub d_loss: f64,
    /// `−log D(G(z))` (non-saturating).
    pub g_loss: f64,
    /// Mean `D(x)` on real windows.
    pub d_real: f64,
    /// Mean `D(G(z))`.
    pub d_fake: f64,
}

/// A trained GAN with its detection statistics.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GanModel {
    pub(crate) cfg: GanConfig,
    /// Generator parameters (layout in `net`).
    pub(crate) g: Vec<f64>,
    /// Discriminator parameters.
    pub(crate) d: Vec<f64>,
    /// `λ = S_D / (S_G + S_D)`.
    pub(crate) lambda: f64,
    /// Min and max of `R_G` over the training windows.
    pub(crate) rg_min: f64,
    pub(crate) rg_max: f64,
    pub(crate) s_g: f64,
    pub(crate) s_d: f64,
    /// Detection threshold; `+∞` until [`GanModel::calibrate`].
    pub(crate) t2: f64,
}

impl GanModel {
    /// The settings it was trained with.
    pub fn config(&self) -> &GanConfig {
        &self.cfg
    }
    /// Weight of the generation score, in [0, 1].
    pub fn lambda(&self) -> f64 {
        self.lambda
    }
    /// `(S_G, S_D)`: dispersion of the normalised generation and
    /// discrimination errors on the training data.
    pub fn dispersions(&self) -> (f64, f64) {
        (self.s_g, self.s_d)
    }
    /// `(min R_G, max R_G)` over the training windows.
    pub fn rg_range(&self) -> (f64, f64) {
        (self.rg_min, self.rg_max)
    }
    /// Threshold `T2` (`+∞` before calibration).
    pub fn t2(&self) -> f64 {
        self.t2
    }
    /// Total trainable parameters (generator + discriminator).
    pub fn param_count(&self) -> usize {
        self.g.len() + self.d.len()
    }
}
