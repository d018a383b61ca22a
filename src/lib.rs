//! navguard: UAV navigation-sensor fault detection.
//!
//! A pure-Rust core (this crate's modules) implementing the online KF–ANFIS
//! detector of Sun et al. 2017, with a thin wasm-bindgen facade in
//! [`wasm`] (compiled for `wasm32` only).

pub mod audit;
// The detector and everything its row path runs: crate `navguard-detector`
// (built at opt-level 3 in the core wasm module while this crate is built
// for size), re-exported module by module.
pub use navguard_detector::{anfis, codec, config, detector, drift, error, filter, frames, indicators, methods, model, ramp, rng, snapshot, thresholds, track, window};
pub mod battery;
pub mod calibrate;
pub mod compare;
pub mod metrics;
pub mod sim;
pub mod tight;

#[cfg(target_arch = "wasm32")]
pub mod wasm;

/// The log readers (crate `navguard-logs`, built for size in the core wasm
/// module).
pub use navguard_logs as logs;
pub use navguard_logs::sample;

pub use config::{Config, ConfigError, ConfigInput};
pub use detector::{Detector, InputError, Output};
pub use model::Model;
pub use sample::Sample;
