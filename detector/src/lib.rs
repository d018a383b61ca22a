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

pub mod anfis;
pub mod codec;
pub mod config;
pub mod detector;
pub mod dragend;
pub mod flatline;
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
