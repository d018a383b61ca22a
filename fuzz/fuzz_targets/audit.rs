//! End to end: `read_any` (format by content) then `audit::audit` with the
//! default config; and the streaming audit (`StreamAudit`, both passes for
//! ULog) over the same bytes in input-chosen chunks gives the same report
//! and outputs, or the same error.
#![no_main]

use libfuzzer_sys::fuzz_target;
use navguard::{audit, logs, Config};

fuzz_target!(|data: &[u8]| {
    let step = 1 + usize::from(data.last().copied().unwrap_or(0) % 64);
    let s = audit::audit_chunks(data, &Config::default(), true, step);
    let Ok(log) = logs::read_any(data) else {
        // A CSV error may come later in the stream than in the whole read
        // (rows before it are audited), but it must come.
        assert!(s.is_err(), "whole read failed, stream did not");
        return;
    };
    let (report, cols) = audit::audit(&log, &Config::default()).expect("default config builds a detector");
    assert_eq!(cols.t.len(), report.rows);
    let json = serde_json::to_string(&report).expect("report serialises");
    let (rs, cs) = s.expect("whole read worked, stream must too");
    assert_eq!(json, serde_json::to_string(&rs).unwrap());
    let b = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(b(&cols.f), b(&cs.f));
    assert_eq!(cols.status, cs.status);
});
