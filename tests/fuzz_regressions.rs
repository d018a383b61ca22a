//! Regressions found by the cargo-fuzz targets (see docs/fuzzing.md), plus a
//! check that the committed fuzz seeds stay meaningful inputs.
//!
//! Each bug has a test named after it; the minimized input is in
//! `tests/fuzz-regressions/<name>.bin` or inlined when tiny.

use navguard::logs::{csv, dataflash, read_any, ulog};

fn seed(path: &str) -> Vec<u8> {
    let p = format!("{}/fuzz/seeds/{path}", env!("CARGO_MANIFEST_DIR"));
    std::fs::read(&p).unwrap_or_else(|e| panic!("{p}: {e}"))
}

#[allow(dead_code)]
fn regression(name: &str) -> Vec<u8> {
    let p = format!("{}/tests/fuzz-regressions/{name}.bin", env!("CARGO_MANIFEST_DIR"));
    std::fs::read(&p).unwrap_or_else(|e| panic!("{p}: {e}"))
}

/// The synthetic seeds exercise the mapped paths (rows of every sensor), so
/// the fuzzers start from deep inside the readers, not from "bad magic".
#[test]
fn fuzz_seeds_parse_into_rows_of_every_sensor() {
    let d = csv::read_csv(&seed("csv/full.csv")).expect("full.csv");
    assert_eq!(d.samples.len(), 40);
    assert!(d.missing.is_empty(), "{:?}", d.missing);
    let d = csv::read_csv(&seed("csv/ned_unknown_cols.csv")).expect("ned_unknown_cols.csv");
    assert!(d.warnings.iter().any(|w| w.contains("foo")), "{:?}", d.warnings);
    assert!(csv::read_csv(&seed("csv/errors.csv")).unwrap_err().contains("line 3"));

    for f in ["ulog/synthetic.ulg", "ulog/synthetic_v0_noflags.ulg"] {
        let d = ulog::read_ulog(&seed(f)).unwrap_or_else(|e| panic!("{f}: {e}"));
        assert!(d.missing.is_empty(), "{f}: missing {:?}, warnings {:?}", d.missing, d.warnings);
        assert!(d.samples.iter().any(|s| s.has_fix()), "{f}: no fix: {:?} {:?} {:?}", d.warnings, d.topic_counts, d.samples.iter().find(|s| !s.fix.is_nan()));
        assert!(d.samples.iter().any(|s| s.has_attitude() && s.has_accel()), "{f}: no IMU+attitude row");
    }
    let d = ulog::read_ulog(&seed("ulog/synthetic_cut.ulg")).expect("cut ulog reads partially");
    assert!(d.warnings.iter().any(|w| w.contains("truncated")), "{:?}", d.warnings);

    for f in ["dataflash/synthetic_timeus.bin", "dataflash/synthetic_timems.bin"] {
        let d = dataflash::read_dataflash(&seed(f)).unwrap_or_else(|e| panic!("{f}: {e}"));
        assert!(d.samples.iter().any(|s| s.has_fix()), "{f}: no fix: {:?} {:?} {:?}", d.warnings, d.topic_counts, d.samples.iter().find(|s| !s.fix.is_nan()));
        assert!(d.samples.iter().any(|s| s.has_attitude() && s.has_accel()), "{f}: no IMU+attitude row");
    }
    let d = read_any(&seed("dataflash/synthetic_cut.bin")).expect("cut dataflash reads partially");
    assert!(d.warnings.iter().any(|w| w.contains("truncated")), "{:?}", d.warnings);
}
