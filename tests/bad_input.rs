//! The bad-input matrix (README "Bad input"): every row is a case here.
//! Each gets a clear error or a warning plus graceful handling, never a panic.
#![cfg(not(target_arch = "wasm32"))]

use navguard::config::{Config, ConfigInput};
use navguard::logs::read_any;
use navguard::sample::{Sample, COLUMNS};
use navguard::Detector;

fn det() -> Detector {
    Detector::new(Config::default()).unwrap()
}

fn fix(t: f64) -> Sample {
    let mut s = Sample::at(t);
    s.lat = 31.94;
    s.lon = 118.79;
    s.alt = 20.0;
    s
}

fn data(p: &str) -> Vec<u8> {
    std::fs::read(format!("{}/../shared/data/{p}", env!("CARGO_MANIFEST_DIR"))).unwrap()
}

#[test]
fn nan_and_infinities_in_every_column_are_errors_naming_the_field() {
    for (i, name) in COLUMNS.iter().enumerate() {
        for bad in [f64::INFINITY, f64::NEG_INFINITY] {
            let mut d = det();
            d.push(&fix(0.0)).unwrap();
            let mut s = fix(0.1);
            // Complete the group so only the infinity is wrong.
            for (j, v) in [(14, 0.0), (15, 0.0), (16, -9.8), (17, 0.0), (18, 0.0), (19, 0.0), (7, 0.0), (8, 0.0), (9, 0.0), (20, 1.0), (21, 0.0), (22, 0.0), (23, 0.0)] {
                s.set(j, v);
            }
            s.set(i, bad);
            let e = d.push(&s).unwrap_err();
            assert_eq!(e.field, *name, "{bad} in {name}: {e}");
            assert_eq!(e.row, 1);
            // Nothing lost: the detector goes on.
            assert!(d.push(&fix(0.2)).is_ok());
            assert_eq!(d.stats().rows, 2);
        }
    }
    // NaN is "absent", except where required (t) or where its group is partial.
    let mut d = det();
    assert_eq!(d.push(&Sample::at(f64::NAN)).unwrap_err().field, "t");
    let mut s = fix(0.0);
    s.lon = f64::NAN;
    assert_eq!(d.push(&s).unwrap_err().field, "lon");
}

#[test]
fn time_backwards_duplicates_and_hour_gaps() {
    let mut d = det();
    d.push(&fix(10.0)).unwrap();
    let e = d.push(&fix(9.0)).unwrap_err();
    assert!(e.field == "t" && e.reason.contains("backwards"), "{e}");
    // Duplicate timestamps are allowed (non-decreasing).
    d.push(&fix(10.0)).unwrap();
    // A gap of hours is a logging gap: no verdict carries across, no crash.
    let o = d.push(&fix(10.0 + 5.0 * 3600.0)).unwrap();
    assert_eq!(o.status, 0);
    assert_eq!(d.stats().data_gaps, 1);
}

#[test]
fn huge_values_and_out_of_range_latitude_are_errors() {
    let mut d = det();
    let mut s = fix(0.0);
    s.baro = 1e300;
    assert_eq!(d.push(&s).unwrap_err().field, "baro");
    let mut s = fix(0.0);
    s.lat = 91.0;
    assert_eq!(d.push(&s).unwrap_err().field, "lat");
    let mut s = fix(0.0);
    s.ax = 1e300;
    s.ay = 0.0;
    s.az = 0.0;
    assert_eq!(d.push(&s).unwrap_err().field, "ax");
    assert_eq!(d.stats().rows, 0);
}

#[test]
fn unreadable_files_give_one_line_reasons() {
    for (bytes, needle) in [
        (&b""[..], "no header"),
        (&b"t,lat,lon,alt\n"[..], ""),
        (&b"\x00\x01\x02garbage\xff\xfe"[..], "not a ULog or DataFlash"),
        (&b"t;lat;lon\n0;1;2\n"[..], "delimiter"),
        (&b"t,lat\n0,abc\n"[..], "line 2"),
    ] {
        match read_any(bytes) {
            Ok(log) => assert!(needle.is_empty() && log.samples.is_empty(), "{needle}: expected an error"),
            Err(e) => {
                let e = e.to_string();
                assert!(e.contains(needle), "{e} should mention {needle}");
                assert!(!e.contains('\n'), "one line: {e}");
            }
        }
    }
}

#[test]
fn truncated_and_corrupt_binary_logs_read_partially_with_warnings() {
    let ulg = data("px4/sample_px4_events.ulg");
    let cut = read_any(&ulg[..ulg.len() / 2]).unwrap();
    assert!(!cut.samples.is_empty());
    assert!(cut.warnings.iter().any(|w| w.to_lowercase().contains("truncat")), "{:?}", cut.warnings);
    // Corrupt the first format definition's text: still no panic.
    let mut bad = ulg.clone();
    if let Some(p) = bad.windows(2).position(|w| w == b"F\0".as_slice() || w[0] == b'F') {
        for b in bad.iter_mut().skip(p + 3).take(40) {
            *b = b'?';
        }
    }
    let _ = read_any(&bad);
    let bin = data("ardupilot/Loiter_RTL.bin");
    let cut = read_any(&bin[..bin.len() / 3 + 7]).unwrap();
    assert!(cut.warnings.iter().any(|w| w.contains("truncated")), "{:?}", cut.warnings);
    // Detection over a truncated log runs to the end.
    let (rep, _) = navguard::audit::audit(&cut, &Config::default()).unwrap();
    assert!(rep.rows > 1000);
}

#[test]
fn bad_config_fields_are_named() {
    for (json, needle) in [
        (r#"{"tcc": 5}"#, "tcc"),
        (r#"{"tc": -1}"#, "config.tc"),
        (r#"{"window": 1}"#, "config.window"),
        (r#"{"threshold": "high"}"#, "threshold"),
        (r#"{"gpsPosSigma": 0}"#, "config.gpsPosSigma"),
        (r#"{"maxCoast": 1e9}"#, "config.maxCoast"),
    ] {
        let e = ConfigInput::from_json(json).unwrap_err().to_string();
        assert!(e.contains(needle), "{json}: {e}");
    }
}
