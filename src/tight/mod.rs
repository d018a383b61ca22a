//! Tightly coupled GNSS/INS with per-satellite fault detection and system
//! reconfiguration, after Shen et al. 2022, "GAN-FDSR"
//! (`../shared/papers/shen2022_gan_fdsr.txt`), with the GAN in [`gan`].
//!
//! * [`constellation`]: GPS-like MEO constellation, site frame, visibility, DOP.
//! * [`tc_ekf`]: 17-state error-state EKF (attitude, velocity, position, gyro
//!   and accelerometer biases, receiver clock bias and drift; paper eqs. 1–9)
//!   whose measurements are per-satellite pseudo-ranges.
//! * [`fdi`]: the per-measurement normalized-innovation test (Appendix A),
//!   fault isolation (Appendix B), fault adaptation (Appendix C), RDPOP
//!   (eq. 26) and the RDPOP switch between isolation and reconstruction.
//! * [`scenario`]: the observation environments of Table 3, the fault types
//!   of Table 4, a pseudo-range/IMU simulator and the evaluation loop.
//! * [`chaos`]: chaos analysis of the pseudo-range increment difference
//!   (§2.2, eqs. 10–16, Table 1): mutual-information delay, Cao embedding
//!   dimension, phase-space reconstruction, FFT mean period and the
//!   Rosenstein largest Lyapunov exponent.
//! * [`gan`]: the GRU GAN detector of §3.1–3.2 (training, latent search,
//!   `Score(y)`, threshold `T2`), hand-written over `f64`.
//! * [`gan_fdsr`]: the runtime GAN-FDSR monitor per satellite: ρD windows
//!   scored against T2, the flagged satellite rebuilt from the generator
//!   (eq. 12); the embedded default model.
//! * [`gan_fdsr_train`]: the model training pipeline (needs the simulator).
//! * [`predict`]: pseudo-range reconstruction from a predictor (eq. 12).
//! * [`stats`]: normal and chi-square quantiles.
//! * [`rows`]: the per-epoch row types and the CSV reader and writer for the
//!   `pr_<prn>` row format.
//! * [`stream`]: [`stream::TightDetector`], the streaming API over raw
//!   per-epoch rows.
//!
//! Imports run one way: `stream` → `fdi` → `gan_fdsr` → `gan` → `stats`;
//! `scenario` (the simulator) → `fdi`, `rows`; `gan_fdsr_train` →
//! `scenario`. The reconfigurator is handed its GAN model; only `stream` and
//! `scenario` load the embedded default.
//!
//! Frames and units: the navigation frame is a local NED tangent frame fixed
//! at the site (metres); the body frame is forward-right-down. Angles are in
//! radians inside the library, times in seconds, clock terms in metres
//! (bias) and metres per second (drift).

pub mod chaos;
pub mod constellation;
pub mod fdi;
pub mod gan;
pub mod gan_fdsr;
pub mod gan_fdsr_train;
pub mod predict;
pub mod rows;
pub mod scenario;
pub mod stats;
pub mod stream;
pub mod tc_ekf;

use core::fmt;

/// An error on an input path: names the field and the bad value.
#[derive(Clone, Debug, PartialEq)]
pub struct TightError {
    /// Which field, column or parameter was bad (e.g. `"pr_7"`, `"alpha"`).
    pub field: String,
    /// What was wrong, including the offending value.
    pub message: String,
}

impl TightError {
    /// An error on `field`.
    pub fn new(field: impl Into<String>, message: impl Into<String>) -> Self {
        TightError { field: field.into(), message: message.into() }
    }
}

impl fmt::Display for TightError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.field, self.message)
    }
}

impl std::error::Error for TightError {}

/// Finite check with a named error.
pub(crate) fn finite(field: &str, v: f64) -> Result<f64, TightError> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(TightError::new(field, format!("must be finite, got {v}")))
    }
}
