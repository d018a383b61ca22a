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
pub mod barojump;
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

/// `f64::max` and `f64::min` as wasm32 runs them, written out so that the
/// compiler inlines them. On wasm32 std's `max`/`min` are calls to
/// compiler-builtins' `fmax`/`fmin` (wasm's `f64.max` propagates NaN, std's
/// returns the other operand); these are the same expressions: the
/// first operand NaN gives the second, else the larger (smaller) with the
/// first kept on a tie, so every result is bit for bit the call's. The
/// core module's wasm-opt then need not inline small functions everywhere
/// to keep them off the row path (`-fimfs=10`, .ci/build). Other targets
/// keep std's.
pub(crate) trait MinMax {
    /// `self.max(other)`.
    fn fmax(self, other: f64) -> f64;
    /// `self.min(other)`.
    fn fmin(self, other: f64) -> f64;
}

impl MinMax for f64 {
    #[inline(always)]
    fn fmax(self, other: f64) -> f64 {
        #[cfg(target_arch = "wasm32")]
        {
            if self.is_nan() || self < other {
                other
            } else {
                self
            }
        }
        #[cfg(not(target_arch = "wasm32"))]
        {
            self.max(other)
        }
    }

    #[inline(always)]
    fn fmin(self, other: f64) -> f64 {
        #[cfg(target_arch = "wasm32")]
        {
            if other.is_nan() || self < other {
                self
            } else {
                other
            }
        }
        #[cfg(not(target_arch = "wasm32"))]
        {
            self.min(other)
        }
    }
}
