//! End to end: `read_any` (format by content) then `audit::audit` with the
//! default config, as the wasm `audit` entry point does.
#![no_main]

use libfuzzer_sys::fuzz_target;
use navguard::{audit, logs, Config};

fuzz_target!(|data: &[u8]| {
    let Ok(log) = logs::read_any(data) else { return };
    let (report, cols) = audit::audit(&log, &Config::default()).expect("default config builds a detector");
    assert_eq!(cols.t.len(), report.rows);
    let _ = serde_json::to_string(&report).expect("report serialises");
});
