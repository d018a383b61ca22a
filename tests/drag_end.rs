//! The end of a horizontal drag-off confirmed over the seconds after the
//! jump (detector/src/dragend.rs): the filter re-anchors on the returned
//! fix instead of judging it as a step until the episode coasts out
//! (issue 14: 38% of the false-positive epochs on the evaluation split lay
//! within 20 s after a fault, most after drag-offs).
#![cfg(not(target_arch = "wasm32"))]

mod common;

use common::flagged_after;
use navguard::battery::{Axis, Flight, Split};

/// Regression: tune #58 (aggressive, 5 Hz Gauss–Markov receiver σ 2.6 m,
/// consumer IMU): a 0.58 m/s drag-off for 23 s (13 m) ends with a 0.58 m/s
/// velocity jump, under 3σ of one epoch's velocity noise, so the jump was
/// read as a step's onset and the 60 s after it were flagged.
#[test]
fn the_end_of_a_horizontal_drag_off_is_confirmed_and_re_anchored() {
    let f = Flight::draw(Split::Tune, 58);
    assert_eq!((f.faults[0].kind.name(), f.faults[0].axis), ("drag-off", Axis::Horizontal));
    let (n, of) = flagged_after(&f, 30.0);
    assert!(of > 100 && n * 10 <= of, "{n} of {of} epochs flagged in the 30 s after the drag-off");
}
