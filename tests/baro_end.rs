//! The end of a baro fault: the baro back onto both its levels (against the
//! GPS altitude and the GPS vertical velocity integrated, `track`'s
//! `returned`). Its jump back is in the baro's 6 s windows and its Δr,
//! which a baro released during the fault had re-based on the faulty
//! level; the detector now restarts them instead of flagging the return.
#![cfg(not(target_arch = "wasm32"))]

mod common;

use common::{flagged_after, share_and_after};
use navguard::battery::{self, Flight, Split};
use navguard::Config;

/// Regression: tune #175 (hover, 1 Hz GPS): a 7.9 m baro step for 66 s,
/// flagged throughout; its end was flagged for the next 6 epochs (5.6 s).
#[test]
fn a_baro_step_that_ends_is_not_flagged_for_its_return() {
    let f = Flight::draw(Split::Tune, 175);
    assert_eq!(f.faults[0].kind.name(), "baro-step");
    let r = battery::run(&f, &Config::default()).unwrap();
    assert!(r.events[0].share >= 0.95, "{:.0}% of the step flagged", 100.0 * r.events[0].share);
    let (n, of) = flagged_after(&f, 20.0);
    assert!(of >= 18 && n == 0, "{n} of {of} epochs flagged in the 20 s after the step");
}

/// Regression: tune #232 (aggressive, 1 Hz GPS): a 9.4 m baro step whose
/// last 4 s passed as normal, so the baro's level against the Doppler
/// integral learnt the stepped level; its return jump (back onto the GPS
/// altitude) was flagged for the next 6 epochs.
#[test]
fn a_baro_step_return_is_recognised_on_the_gps_altitude_level() {
    let f = Flight::draw(Split::Tune, 232);
    assert_eq!(f.faults[0].kind.name(), "baro-step");
    let (n, of) = flagged_after(&f, 20.0);
    assert!(of >= 18 && n <= 1, "{n} of {of} epochs flagged in the 20 s after the step");
}

/// Regression: tune #270 (hover, 5 Hz white receiver σ 0.32 m): a 12.2 m
/// baro step from 8 s into the flight (log 13 s) to 107 s. It came while
/// the levels were learning their baseline and σ, so both learnt it, and
/// its end, the baro jumping back to where the levels began, was flagged
/// for the 88 s left of the flight (441 epochs). The levels now keep where
/// they began (`VelocityTrack::back_to_origin`), and a jump back there is
/// the fault's end; the drift test's window, whose start sat on the
/// stepped level, restarts with it.
#[test]
fn a_baro_step_from_the_first_seconds_ends_on_its_return_to_the_origin() {
    let f = Flight::draw(Split::Tune, 270);
    assert_eq!(f.faults[0].kind.name(), "baro-step");
    assert!(f.faults[0].start < 10.0, "starts at {:.1} s", f.faults[0].start);
    let (n, of) = flagged_after(&f, 60.0);
    assert!(of > 250 && n * 20 <= of, "{n} of {of} epochs flagged in the 60 s after the step");
}

/// Regression: tune #1513 (hover, 10 Hz white receiver σ 0.93 m, consumer
/// IMU): a baro drifting 0.25 m/s from 8.8 s into the flight for 96 s
/// (24 m). The drift test's σ and the levels' σ learnt it, and the
/// levels' baseline lagged it, so it was never flagged, and its end, the
/// baro jumping back to where the levels began, was flagged for the 89 s
/// left (888 epochs). The return is now measured on the level before the
/// jump (`VelocityTrack::back_to_origin`): 22 m back, 2.9 σ of the learnt
/// wander but dozens of σ of the level's epoch-to-epoch change.
#[test]
fn a_baro_drift_from_the_first_seconds_ends_on_its_return_to_the_origin() {
    let f = Flight::draw(Split::Tune, 1513);
    assert_eq!(f.faults[0].kind.name(), "baro-drift");
    assert!(f.faults[0].start < 10.0, "starts at {:.1} s", f.faults[0].start);
    let (n, of) = flagged_after(&f, 60.0);
    assert!(of > 550 && n * 20 <= of, "{n} of {of} epochs flagged in the 60 s after the drift");
}

/// Regression: tune #1224 (survey, 1 Hz Gauss–Markov receiver σ 1.94 m):
/// a 15 m baro step for 89 s was flagged for its first 8 s (10% of it),
/// then accepted: once the 6 s windows had passed its jump, its offset was
/// within 3σ of the GPS altitude's noise, though 15 m off the Doppler
/// integral. A withheld baro is now held while it stays `FAR` σ off the
/// Doppler level and `NEAR` σ off the GPS altitude.
#[test]
fn a_baro_step_is_held_while_it_stays_off_its_levels() {
    let f = Flight::draw(Split::Tune, 1224);
    assert_eq!(f.faults[0].kind.name(), "baro-step");
    let r = battery::run(&f, &Config::default()).unwrap();
    let fp = r.epochs.iter().filter(|e| e.label == 0.0 && e.status != 0).count();
    let share = r.events[0].share;
    eprintln!("{:.0}% of the step flagged, {fp} false-positive epochs", 100.0 * share);
    assert!(share >= 0.9 && fp <= 10, "{:.0}% of the step flagged, {fp} false-positive epochs", 100.0 * share);
}

/// The share of the flight's first fault flagged, and the false-positive
/// epochs, with the default config.
fn share_and_false_positives(split: Split, index: u64, kind: &str) -> (f64, usize) {
    let f = Flight::draw(split, index);
    assert_eq!(f.faults[0].kind.name(), kind);
    let r = battery::run(&f, &Config::default()).unwrap();
    let fp = r.epochs.iter().filter(|e| e.label == 0.0 && e.status != 0).count();
    (r.events[0].share, fp)
}

/// Regression: tune #1316 (hover, 10 Hz Gauss–Markov receiver σ 2.51 m):
/// a 9.2 m baro step for 60 s was flagged for 11 of its 554 epochs. The
/// GPS altitude's wander (`NEAR` σ of it is 15 m) hid it once the 6 s
/// windows had passed its jump, though the baro stayed 9 m off its Doppler
/// level. The step's jump is now remembered and holds the withheld baro
/// while the Doppler level keeps half of it (`barojump`).
#[test]
fn a_baro_step_under_a_wandering_gps_altitude_is_held_by_its_jump() {
    let (share, fp) = share_and_false_positives(Split::Tune, 1316, "baro-step");
    assert!(share >= 0.95 && fp <= 33, "{:.0}% of the step flagged (2% before), {fp} false-positive epochs", 100.0 * share);
}

/// Regression: tune #455 (fixed wing, 10 Hz white receiver σ 2.97 m): a
/// 9.9 m baro step from 28 s, before the levels had lived the 30 s they
/// judge from, was flagged for 1 of its 544 epochs. Its jump is judged
/// from the levels' first epochs (`barojump`).
#[test]
fn a_baro_step_before_the_levels_judge_is_held_by_its_jump() {
    let (share, fp) = share_and_false_positives(Split::Tune, 455, "baro-step");
    assert!(share >= 0.9 && fp <= 6, "{:.0}% of the step flagged (0% before), {fp} false-positive epochs", 100.0 * share);
}

/// Regression: tune #628 (aggressive, 2 Hz receiver): a 8.5 m baro step
/// moved the filter's climb before the baro was withheld; the GPS velocity
/// was withheld instead, and the Doppler level, integrating the filter's
/// climb, lost the step within 2 s. The step's return 59 s later was then
/// a jump away from that level: remembered as a new step, it was held for
/// 122 false-positive epochs. The Doppler level now integrates the GPS
/// velocity while a jump is remembered.
#[test]
fn a_baro_step_that_moved_the_filter_is_not_held_past_its_return() {
    let (share, fp) = share_and_false_positives(Split::Tune, 628, "baro-step");
    assert!(share >= 0.35 && fp <= 5, "{:.0}% of the step flagged (6% before), {fp} false-positive epochs", 100.0 * share);
}

/// Regression: tune #1379 (fixed wing, 5 Hz receiver): an 8.2 m baro step
/// from 9 s into the flight, on the ground, for 114 s. The step's jump was
/// held until its Doppler level had moved another 4 m during the take-off
/// roll (0 → 15 m/s: the static port's dynamic-pressure error), read as a
/// level that went on moving, and let go: 49 of 570 epochs flagged. The
/// level's change beyond the jump now counts net of what the motion may
/// move a healthy baro (`barojump::BaroJump::held`): held to its end.
#[test]
fn a_baro_step_on_the_ground_is_held_through_the_take_off_roll() {
    let f = Flight::draw(Split::Tune, 1379);
    assert_eq!(f.faults[0].kind.name(), "baro-step");
    let (share, n, of) = share_and_after(&f, 20.0);
    assert!(share >= 0.95, "{:.0}% of the step flagged", 100.0 * share);
    assert!(of >= 90 && n <= 2, "{n} of {of} epochs flagged in the 20 s after the step");
}
