//! navguard's detector crate: the streaming detector and everything its row
//! path runs (the filter, the indicators, the ANFIS, the other decision
//! methods and their thresholds, the config, the embedded model and pools,
//! the snapshot codec). The `navguard` crate re-exports every module under
//! its own name (`navguard::detector`, `navguard::filter`, ...): use it
//! through there.
//!
//! A crate of its own so that the core wasm module can build the detector
//! at opt-level 3 and what sits above it (the wasm facade, the audit
//! summary, snapshot and restore) for size: cargo sets opt-levels per
//! crate (see `[profile.wasm-core]` in the workspace's `Cargo.toml`).
// Cold code compiled for size inside this opt-level-3 crate: the core
// wasm build (.ci/build) passes `--cfg navguard_cold_size` (its toolchain
// takes unstable features under RUSTC_BOOTSTRAP, as for -Z build-std);
// every other build compiles it as before.
#![cfg_attr(navguard_cold_size, feature(optimize_attribute))]

pub mod anfis;
pub mod codec;
pub mod config;
pub mod detector;
pub mod dragend;
pub mod drift;
pub mod error;
pub mod filter;
pub mod frames;
pub mod indicators;
pub mod methods;
pub mod model;
pub mod ramp;
pub mod rng;
pub mod snapshot;
pub mod thresholds;
pub mod track;
pub mod window;

pub use navguard_logs as logs;
pub use navguard_logs::sample;
