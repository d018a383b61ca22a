//! navguard: UAV navigation-sensor fault detection.
//!
//! A pure-Rust core (this crate's modules) implementing the online KF–ANFIS
//! detector of Sun et al. 2017, with a thin wasm-bindgen facade in
//! [`wasm`] (compiled for `wasm32` only).

pub mod anfis;
pub mod audit;
pub mod battery;
pub mod calibrate;
pub mod codec;
pub mod compare;
pub mod config;
pub mod detector;
pub mod error;
pub mod filter;
pub mod frames;
pub mod indicators;
pub mod methods;
pub mod metrics;
pub mod model;
pub mod rng;
pub mod sim;
pub mod thresholds;
pub mod tight;
pub mod track;
pub mod snapshot;

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
