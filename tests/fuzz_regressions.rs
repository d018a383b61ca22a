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
    let e = csv::read_csv(&seed("csv/errors.csv")).unwrap_err();
    assert_eq!(e.line(), Some(3), "{e}");
    assert!(e.to_string().starts_with("line 3"), "{e}");

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

/// The `audit` fuzz target (streamed against whole-bytes audit) found that
/// a CSV whose every row is rejected (here `gz` renamed, so each IMU row
/// has `gx` without `gz`) reported no missing inputs on the whole-bytes
/// path, counted from the parsed rows, but all four on the streaming path,
/// counted from the rows audited. Both now count the rows audited.
#[test]
fn a_csv_whose_rows_are_all_rejected_reports_the_same_missing_inputs_both_ways() {
    let text = "t,lat,lon,alt,ax,ay,az,gx,gy,ncgz,qw,qx,qy,qz,baro\n\
                0.00,47.39,8.54,488.0,0.01,-0.02,-9.81,0.001,0.002,-0.001,1,0,0,0,488.2\n\
                0.02,,,,0.01,-0.02,-9.81,0.001,0.002,-0.001,1,0,0,0,488.3\n";
    let cfg = navguard::Config::default();
    let log = read_any(text.as_bytes()).unwrap();
    let (whole, _) = navguard::audit::audit(&log, &cfg).unwrap();
    let (streamed, _) = navguard::audit::audit_chunks(text.as_bytes(), &cfg, true, 7).unwrap();
    assert_eq!(whole.rows, 0);
    assert_eq!(whole.missing, ["gps", "imu", "attitude", "baro"]);
    assert_eq!(streamed.missing, whole.missing);
    assert_eq!(streamed.warnings, whole.warnings);
}
