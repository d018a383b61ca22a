//! The wasm-bindgen facade, split by domain as the npm package is: the core
//! module (feature `wasm-core`: [`detector`], [`read_log`]: what
//! `new Detector()` plus `readLog` need, and nothing else), the audit module
//! (feature `wasm-audit`: [`audit`], with its own copy of the detector and
//! the readers) and the lab module (feature `wasm-lab`: [`lab`], [`tight`]),
//! each built into its own .wasm by `.ci/build`; the package loads the audit
//! and lab modules on first use. [`interop`] holds every JS <-> Rust
//! conversion they share.
//! Everything `#[wasm_bindgen]` lives here; the core never sees a JS type.
//!
//! Results are plain JS objects (one naming rule: camelCase; the core
//! module's built field by field with `interop::Obj`, so it carries no
//! serde serializer; the lab's from `#[derive(Serialize)]` structs through
//! serde-wasm-bindgen) and typed arrays (no class handles to free in
//! loops). Errors are JS `Error`s naming the row and field; an object is
//! untouched by a rejected row or batch. Each file carries the TypeScript
//! declarations of what it exports (`typescript_custom_section`).

pub mod interop;

/// The core module's allocator (feature `talc-alloc`): talc, smaller than
/// std's dlmalloc. wasm32 here is single-threaded (no atomics).
#[cfg(feature = "talc-alloc")]
#[global_allocator]
static ALLOC: talc::wasm::WasmDynamicTalc = talc::wasm::new_wasm_dynamic_allocator();

#[cfg(feature = "wasm-audit")]
pub mod audit;
#[cfg(feature = "wasm-core")]
pub mod detector;
#[cfg(feature = "wasm-core")]
pub mod read_log;
#[cfg(feature = "wasm-lab")]
pub mod lab;
#[cfg(feature = "wasm-lab")]
pub mod tight;

#[cfg(feature = "wasm-audit")]
pub use audit::{audit_bytes, metrics, Auditor, StreamAuditor};
#[cfg(feature = "wasm-core")]
pub use read_log::read_log;
#[cfg(feature = "wasm-core")]
pub use detector::{column_names, scenario_names, snapshot_info, version, Detector, MAX_BATCH_ROWS};
#[cfg(feature = "wasm-lab")]
pub use lab::{simulate, simulate_scenario, train_from_csv, CompareRun};
#[cfg(feature = "wasm-lab")]
pub use tight::{tight_gan_train, tight_simulate, TightDetectorJs};
