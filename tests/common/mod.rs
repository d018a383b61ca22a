//! Helpers shared by the battery regression tests (native only).
use navguard::battery::{self, Flight};
use navguard::{Config, Detector};

/// GPS epochs flagged in the `len` s after the flight's first fault ends,
/// and the GPS epochs in that span (default config).
pub fn flagged_after(f: &Flight, len: f64) -> (usize, usize) {
    let ft = f.faults[0];
    let mut det = Detector::new(Config::default()).unwrap();
    let after: Vec<u8> = battery::simulate(f)
        .iter()
        .map(|s| (s, det.push(s).unwrap().status))
        .filter(|(s, _)| !s.label.is_nan() && s.t >= ft.end_log && s.t < ft.end_log + len)
        .map(|(_, st)| st)
        .collect();
    (after.iter().filter(|st| **st != 0).count(), after.len())
}
