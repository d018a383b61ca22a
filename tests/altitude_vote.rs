//! The GPS altitude judged by two of three vertical references
//! (`Consistency::altitude_vote` in detector/src/detector.rs): when the
//! baro and the GPS's own vertical velocity integrated both say the GPS
//! altitude moved, the same way, the GPS position is condemned; when both
//! say it came back, the filter re-anchors on it (issue 14: a 12 m vertical
//! step was flagged for 0% of it, the 6 m vertical step check passed 3/6).
#![cfg(not(target_arch = "wasm32"))]

mod common;

use common::flagged_after;
use navguard::battery::{self, Axis, Flight, Split};
use navguard::Config;

/// Share of the flight's `kind` event on `axis` that was flagged.
fn share(index: u64, kind: &str, axis: Axis) -> f64 {
    let f = Flight::draw(Split::Tune, index);
    let r = battery::run(&f, &Config::default()).unwrap();
    let e = r.events.iter().find(|e| e.fault.kind.name() == kind && e.fault.axis == axis).expect("the flight has that fault");
    e.share
}

/// Regression: tune #157 (aggressive, 2 Hz GPS, white σ 0.89 m): an
/// 11.9 m vertical step for 4 s was flagged for 0% of it; the position
/// group's R (the three axes' RMS) stayed at 1.8–2.1.
#[test]
fn a_12_m_vertical_step_is_flagged() {
    let s = share(157, "step", Axis::Vertical);
    assert!(s >= 0.8, "{:.0}% of the step flagged", 100.0 * s);
}

/// Regression: tune #214 (fixed-wing, 5 Hz GPS, Gauss–Markov σ 0.70 m,
/// consumer IMU with 4.9 m/s² of vibration): a 6.1 m vertical step for 27 s,
/// 0% flagged before.
#[test]
fn a_6_m_vertical_step_is_flagged() {
    let s = share(214, "step", Axis::Vertical);
    assert!(s >= 0.8, "{:.0}% of the step flagged", 100.0 * s);
}

/// Regression: tune #229 (survey, 2 Hz GPS): a 1.0 m/s vertical ramp of the
/// GPS altitude alone for 41 s, 0% flagged before; its end (the altitude
/// back onto the baro and the Doppler) re-anchors the filter instead of
/// opening a fault of its own.
#[test]
fn a_vertical_ramp_is_flagged_and_its_end_opens_no_interval() {
    let s = share(229, "ramp", Axis::Vertical);
    assert!(s >= 0.5, "{:.0}% of the ramp flagged", 100.0 * s);
    let (n, of) = flagged_after(&Flight::draw(Split::Tune, 229), 30.0);
    assert!(of > 50 && n * 20 <= of, "{n} of {of} epochs flagged in the 30 s after the ramp");
}
