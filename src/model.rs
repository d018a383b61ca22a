//! The trained model: ANFIS parameters plus the initial databases D1₀, D2₀
//! (Sun et al. 2017 §2.4), the model shipped in the crate and its checks.
//! Training lives in [`crate::calibrate`]; this module only holds and checks
//! models, so the detector can use one without pulling in the trainer.

use serde::{Deserialize, Serialize};

use crate::anfis::Anfis;

/// A trained model: ANFIS parameters plus the initial databases D1₀, D2₀.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Model {
    /// The trained ANFIS (eqs. 5–10).
    pub anfis: Anfis,
    /// Normal samples, ANFIS input space `[ln(1+R), C]`.
    pub d1: Vec<[f64; 2]>,
    /// Fault samples.
    pub d2: Vec<[f64; 2]>,
    /// How it was made (free text).
    #[serde(default)]
    pub provenance: String,
}

impl Model {
    /// The model shipped in the crate, made by `cargo run --release --bin navguard-train`.
    /// Parsed once per process (a few hundred µs), then cloned.
    pub fn embedded() -> Result<Model, String> {
        static EMBEDDED: std::sync::OnceLock<Result<Model, String>> = std::sync::OnceLock::new();
        EMBEDDED
            .get_or_init(|| {
                serde_json::from_str(include_str!("default_model.json")).map_err(|e| format!("embedded model: {e}"))
            })
            .clone()
    }

    /// Grid-initialised ANFIS with a plain R ramp, used only to drive the
    /// trainer's oracle runs (their decisions come from the labels).
    pub fn untrained() -> Model {
        Model {
            anfis: Anfis::init_grid([0.0, 0.0], [3.0, 1.0]),
            d1: vec![],
            d2: vec![],
            provenance: "untrained".into(),
        }
    }

    /// Finite ANFIS parameters with positive widths, finite database entries.
    pub fn check(&self) -> Result<(), String> {
        check_anfis(&self.anfis)?;
        if !self.d1.iter().chain(self.d2.iter()).flatten().all(|v| v.is_finite()) {
            return Err("database entries must be finite".into());
        }
        Ok(())
    }
}

/// A fault epoch carries a fault signature: its indicators left the region
/// clean data occupies (`R ≥ 3` or `C ≥ 0.7`). Used to clean the training
/// set and to admit online verdicts into D2.
pub fn has_signature(r: f64, c: f64) -> bool {
    r >= SIG_R || c >= SIG_C
}
const SIG_R: f64 = 3.0;
const SIG_C: f64 = 0.7;

/// Used by [`Model::check`] and by snapshot restore.
pub(crate) fn check_anfis(a: &Anfis) -> Result<(), String> {
    if a.is_finite() {
        Ok(())
    } else {
        Err("ANFIS parameters must be finite with positive widths".into())
    }
}

