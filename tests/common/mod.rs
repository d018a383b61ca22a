//! Helpers shared by the native integration tests: the battery regression
//! tests and the real-log tests. Each test file uses some of them.
#![allow(dead_code)]
use navguard::battery::{self, Axis, Flight, FlightResult};
use navguard::Config;

/// GPS epochs flagged in the `len` s after the flight's first fault ends,
/// and the GPS epochs in that span (default config).
pub fn flagged_after(f: &Flight, len: f64) -> (usize, usize) {
    flagged_after_fault(f, 0, len)
}

/// As `flagged_after`, after the flight's fault `i`.
pub fn flagged_after_fault(f: &Flight, i: usize, len: f64) -> (usize, usize) {
    after_fault(&battery::run(f, &Config::default()).unwrap(), i, len)
}

/// In a run `r`: its GPS epochs flagged in the `len` s after fault `i`
/// ends, and its GPS epochs in that span.
pub fn after_fault(r: &FlightResult, i: usize, len: f64) -> (usize, usize) {
    let end = r.flight.faults[i].end_log;
    let after: Vec<u8> = r.epochs.iter().filter(|e| e.t >= end && e.t < end + len).map(|e| e.status).collect();
    (after.iter().filter(|st| **st != 0).count(), after.len())
}

/// The share of the flight's first fault flagged, and the epochs flagged
/// in the `len` s after it, of how many (default config, one run).
pub fn share_and_after(f: &Flight, len: f64) -> (f64, usize, usize) {
    let r = battery::run(f, &Config::default()).unwrap();
    let (n, of) = after_fault(&r, 0, len);
    (r.events[0].share, n, of)
}

/// The flight's first fault, checked to be a horizontal accelerometer
/// bias, run with the default config: the share of it flagged.
pub fn bias_share(f: &Flight) -> f64 {
    assert_eq!((f.faults[0].kind.name(), f.faults[0].axis), ("accel-bias", Axis::Horizontal));
    battery::run(f, &Config::default()).unwrap().events[0].share
}

/// The battery flight `index` of `split`, whose first fault is of kind
/// `kind`, run with the default config: its false-positive GPS epochs
/// (flagged, labelled healthy).
pub fn false_positives(split: battery::Split, index: u64, kind: &str) -> usize {
    let f = Flight::draw(split, index);
    assert_eq!(f.faults[0].kind.name(), kind);
    let r = battery::run(&f, &Config::default()).unwrap();
    r.epochs.iter().filter(|e| e.status != 0 && e.label == 0.0).count()
}

/// The bytes of a shared real log, `p` relative to `../shared/data`.
pub fn data(p: &str) -> Vec<u8> {
    let path = format!("{}/../shared/data/{p}", env!("CARGO_MANIFEST_DIR"));
    std::fs::read(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
}
