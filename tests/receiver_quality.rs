//! The receiver's own accuracy claim (eph) scales the measurement σ of the
//! fixes fed to the filter (issue 14, item 2). Only ratios to the receiver's
//! usual claim count, so a constant eph, any unit of it, or none at all
//! give the same verdicts; a degraded fix no longer drags the estimate, so
//! the good fix after it opens no interval.
#![cfg(not(target_arch = "wasm32"))]

use navguard::battery::{self, Flight, Split};
use navguard::{Config, Detector, Sample};

fn statuses(rows: &[Sample]) -> Vec<u8> {
    let mut det = Detector::new(Config::default()).unwrap();
    rows.iter().map(|s| det.push(s).unwrap().status).collect()
}

#[test]
fn only_the_ratio_of_eph_to_its_usual_level_counts() {
    // A clean flight: its eph is a constant times its sats factor.
    let f = Flight::draw(Split::Tune, 1);
    assert!(f.faults.is_empty());
    let rows = battery::simulate(&f);
    let with = |g: &dyn Fn(f64) -> f64| -> Vec<Sample> {
        rows.iter().map(|s| Sample { eph: g(s.eph), ..*s }).collect()
    };
    let none = statuses(&with(&|_| f64::NAN));
    let constant = statuses(&with(&|e| if e.is_nan() { e } else { 1.7 }));
    assert_eq!(none, constant, "a constant eph changed a verdict");
    let as_is = statuses(&rows);
    let tripled = statuses(&with(&|e| 3.0 * e));
    assert_eq!(as_is, tripled, "eph in other units changed a verdict");
}

/// Regression: battery tune #72 (true clock, fixed-wing, 10 Hz GPS): a
/// 16 s degraded fix (eph 5–10 m against a usual 1 m) ended with a jump of
/// 11 m back to the truth, and that jump was flagged as a 60 s step.
#[test]
fn the_good_fix_after_a_degraded_one_opens_no_interval() {
    let f = Flight::draw(Split::Tune, 72);
    let ft = f.faults[0];
    assert_eq!((ft.kind.name(), f.clock.rate), ("degraded", 1.0));
    let rows = battery::simulate(&f);
    let st = statuses(&rows);
    let after = rows
        .iter()
        .zip(&st)
        .filter(|(s, o)| !s.label.is_nan() && s.t >= ft.end_log + 2.0 && s.t < ft.end_log + 60.0 && **o != 0)
        .count();
    // 10 Hz: at most 2 s flagged in the 58 s after the fault (was 598 epochs).
    assert!(after <= 20, "{after} epochs flagged after the degraded fix");
}
