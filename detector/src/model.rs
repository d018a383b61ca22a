//! The trained model: ANFIS parameters plus the initial databases D1₀, D2₀
//! (Sun et al. 2017 §2.4), the model shipped in the crate and its checks.
//! Training lives in `navguard::calibrate` (the lab); this module only holds and checks
//! models, so the detector can use one without pulling in the trainer.

use serde::{Deserialize, Serialize};

use crate::anfis::Anfis;

/// The shipped model in [`crate::codec`] bytes (postcard's; every f64
/// bit-exact): the model that
/// serde_json reads from `detector/src/default_model.json` (what `navguard-train`
/// writes, readable and diffable), stored as binary so that a build without
/// serde_json (the core wasm module) carries 16 KB instead of 42 KB of JSON
/// and no JSON parser. `embedded_model_is_the_json_exactly` holds the two
/// files to each other; `navguard-train` writes both.
pub const EMBEDDED_MODEL: &[u8] = include_bytes!("default_model.bin");

/// The binary form of a model as shipped: the [`crate::codec`] bytes of
/// the model that `json` (a trained model, as `navguard-train` writes it)
/// parses to.
pub fn binary_of_json(json: &str) -> Result<Vec<u8>, String> {
    let m: Model = serde_json::from_str(json).map_err(|e| format!("model JSON: {e}"))?;
    Ok(crate::codec::to_bytes(&m))
}

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
    /// Decoded once per process from [`EMBEDDED_MODEL`], then cloned.
    #[inline]
    pub fn embedded() -> Result<Model, String> {
        static EMBEDDED: std::sync::OnceLock<Result<Model, String>> = std::sync::OnceLock::new();
        EMBEDDED.get_or_init(|| crate::codec::from_bytes(EMBEDDED_MODEL).map_err(|e| format!("embedded model: {e}"))).clone()
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
    /// `#[inline]`: cold (the config check), compiled where the config is
    /// read (the core wasm module builds that crate for size).
    #[inline]
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
#[inline]
pub(crate) fn check_anfis(a: &Anfis) -> Result<(), String> {
    if a.is_finite() {
        Ok(())
    } else {
        Err("ANFIS parameters must be finite with positive widths".into())
    }
}


#[cfg(test)]
mod tests {
    use super::*;

    /// The embedded binary is exactly what the JSON parses to (as the crate
    /// read it before the model shipped in binary), so the detector's
    /// verdicts did not move. `NAVGUARD_WRITE_MODEL=1 cargo test --release
    /// --lib embedded_model` rewrites `detector/src/default_model.bin` from the JSON.
    #[test]
    fn embedded_model_is_the_json_exactly() {
        let json = include_str!("default_model.json");
        let bytes = binary_of_json(json).unwrap();
        if std::env::var_os("NAVGUARD_WRITE_MODEL").is_some() {
            std::fs::write(concat!(env!("CARGO_MANIFEST_DIR"), "/src/default_model.bin"), &bytes).unwrap();
        }
        assert!(bytes == EMBEDDED_MODEL, "detector/src/default_model.bin differs from detector/src/default_model.json");
        // The codec writes postcard's bytes (the file's first writer).
        assert!(postcard::to_allocvec(&serde_json::from_str::<Model>(json).unwrap()).unwrap() == EMBEDDED_MODEL);
        let from_json: Model = serde_json::from_str(json).unwrap();
        let shipped = Model::embedded().unwrap();
        assert_eq!(shipped, from_json);
        // Bit for bit, not only ==: compare every f64's bits.
        let bits = |m: &Model| m.d1.iter().chain(m.d2.iter()).flatten().map(|v| v.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&shipped), bits(&from_json));
        assert_eq!(shipped.d1.len(), 500);
        assert!(shipped.check().is_ok());
    }
}

/// The snapshot codec of this file's state types ([`crate::codec`]): each
/// struct's fields in declaration order (a field left out does not compile;
/// `skip`: not saved, rebuilt on restore).
mod codec_impls {
    use super::*;
    use crate::codec::impl_codec;

    impl_codec!(Model { anfis, d1, d2, provenance });
}
