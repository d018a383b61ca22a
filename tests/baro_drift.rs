//! The baro's drift judged against both GPS references over 30 s
//! (detector/src/drift.rs): a drift that starts before the baro's levels
//! have learnt their baseline is still flagged, and a GPS vertical
//! drag-off, which moves both references like a baro drift, ends with the
//! filter re-anchored on the returned GPS, not with a new position fault
//! (issue 14: baro faults were 43% of the missed fault epochs).
#![cfg(not(target_arch = "wasm32"))]

mod common;

use common::flagged_after;
use navguard::battery::{self, Flight, Split};
use navguard::Config;

fn share(split: Split, index: u64, kind: &str) -> f64 {
    let f = Flight::draw(split, index);
    assert_eq!(f.faults[0].kind.name(), kind);
    battery::run(&f, &Config::default()).unwrap().events[0].share
}

/// Regression: tune #2 (survey, 10 Hz GPS): a 0.43 m/s baro drift from
/// 7.4 s to 96 s (38 m) was flagged for 0% of it: the baro's levels learnt
/// it as their own wander before their baseline had lived 30 s.
#[test]
fn a_drift_from_the_first_seconds_of_a_flight_is_flagged() {
    let s = share(Split::Tune, 2, "baro-drift");
    assert!(s >= 0.6, "{:.0}% of the drift flagged", 100.0 * s);
}

/// Regression: tune #126 (hover, 5 Hz GPS, white σ 1.15 m): a 0.32 m/s
/// drift for 102 s from 12.7 s, 0% flagged. The GPS altitude's own noise
/// (1.7 m a fix) once ended the drift's episode as soon as it began; the
/// levels are smoothed over 2 s.
#[test]
fn a_slow_drift_under_a_noisy_gps_altitude_is_flagged() {
    let s = share(Split::Tune, 126, "baro-drift");
    assert!(s >= 0.6, "{:.0}% of the drift flagged", 100.0 * s);
}

/// Regression: tune #60 (aggressive, a 0.46 m/s vertical drag-off for
/// 79 s): both GPS references left the baro, the drift was flagged, and
/// the GPS's return onto the baro's level ends it with a re-anchoring.
#[test]
fn the_end_of_a_vertical_drag_off_opens_no_interval() {
    let f = Flight::draw(Split::Tune, 60);
    assert_eq!((f.faults[0].kind.name(), f.faults[0].axis), ("drag-off", battery::Axis::Vertical));
    let (n, of) = flagged_after(&f, 30.0);
    assert!(of > 50 && n * 20 <= of, "{n} of {of} epochs flagged in the 30 s after the drag-off");
}

/// Regression: tune #1471 (fixed wing, 10 Hz white receiver σ 1.12 m) and
/// #1580 (aggressive, 10 Hz Gauss–Markov σ 1.02 m): baro drifts of 0.37 m/s
/// for 68 s and 0.30 m/s for 53 s. #1471's was flagged for 1% of its
/// epochs, with 52 false-positive epochs after it (now 54%, none); #1580
/// missed 400 epochs in all, with 67 false positives (now 283 and 1, 46%
/// of the drift). The GPS
/// altitude's σ was never taken below the receiver's vertical claim (about
/// 3 m here), above the 30 s change of its smoothed altitude; the claim is
/// now only the prior the flight's own changes replace.
#[test]
fn a_drift_is_judged_against_the_flights_own_gps_altitude_wander() {
    for (i, at_least) in [(1471, 0.5), (1580, 0.45)] {
        let f = Flight::draw(Split::Tune, i);
        let k = f.faults.iter().position(|x| x.kind.name() == "baro-drift").unwrap();
        let r = battery::run(&f, &Config::default()).unwrap();
        let fp = r.epochs.iter().filter(|e| e.label == 0.0 && e.status != 0).count();
        let share = r.events[k].share;
        eprintln!("#{i}: {:.0}% of the drift flagged, {fp} false-positive epochs", 100.0 * share);
        assert!(share >= at_least && fp <= 5, "#{i}: {:.0}% of the drift flagged, {fp} false-positive epochs", 100.0 * share);
    }
}

/// Regression: tune #1207 (fixed wing, 10 Hz white receiver σ 0.51 m,
/// industrial IMU): no baro fault, but its static-port error (−0.015 m
/// per (m/s)² of airspeed squared, which its ground speed does not show)
/// moved about 5 m in 10 s at 124 s and then held. The drift test called
/// it and held the baro for 79 s (780 epochs), though its levels saw it
/// within 2σ. A drift whose statistic stopped growing for 30 s is now
/// released when the levels see the baro near them (`drift::PLATEAU_S`,
/// `PLATEAU_HELD`): 36 s flagged.
#[test]
fn a_baro_error_that_moved_and_held_is_not_judged_as_a_drift_for_long() {
    let fp = common::false_positives(Split::Tune, 1207, "step");
    assert!(fp <= 400, "{fp} false-positive epochs (826 before)");
}

/// Regression: tune #1608 (survey, 10 Hz white receiver σ 0.98 m): a
/// 11.9 m baro step from 12.9 s to 67 s, flagged for its first 6 s, before
/// the levels could judge it. Its end, the baro jumping back, was then
/// judged as a drift and held for 53 s (517 false-positive epochs); it was
/// released 30 s after the statistic stopped growing, the levels seeing the
/// baro on them (324 epochs). Since session 16 the step is held by its
/// jump (`barojump`) to its end, which undoes it, and stays withheld when
/// a GPS return ends the episode 22 s in (`Withheld::release_unless_baro_off`):
/// 8 false-positive epochs (506 before that last rule).
#[test]
fn a_drift_plateau_after_an_early_baro_step_is_released() {
    let fp = common::false_positives(Split::Tune, 1608, "baro-step");
    assert!(fp <= 30, "{fp} false-positive epochs (517, then 324, before)");
}

/// Regression: tune #1427 (survey, 10 Hz Gauss–Markov receiver σ 1.52 m,
/// consumer IMU): a 0.41 m/s vertical drag-off from 13.7 s to 39.8 s,
/// before the baro's levels could judge it. Its end, the GPS altitude
/// dropping 11 m back onto the baro while the Doppler integral kept what
/// the dragged velocity integrated, was judged as a vertical step and
/// flagged for the 60 s coast limit (605 false-positive epochs). The GPS
/// altitude's level against the baro coming back with the Doppler level
/// unmoved is now the GPS's return (`Consistency::vertical_return`): the
/// detector re-anchors on it.
#[test]
fn a_gps_altitude_back_on_the_baro_after_an_early_drag_off_is_its_return() {
    let f = Flight::draw(Split::Tune, 1427);
    assert_eq!((f.faults[0].kind.name(), f.faults[0].axis), ("drag-off", battery::Axis::Vertical));
    assert!(f.faults[0].start < 20.0);
    let (n, of) = common::flagged_after_fault(&f, 0, 60.0);
    assert!(of > 500 && n <= 5, "{n} of {of} epochs flagged in the 60 s after the drag-off");
}

/// Regression: tune #1513 (hover, 10 Hz white receiver σ 0.93 m; a 0.25
/// m/s drift for 96 s from 8.8 s) and #1365 (aggressive, 5 Hz white σ
/// 0.66 m; 0.21 m/s for 111 s from 60 s): none of their 962 and 544
/// epochs flagged (now 634 and 427). Both references saw the drift, but the
/// GPS altitude's 30 s change had to reach 3σ too; it now confirms a drift
/// the Doppler integral shows at 3σ from 1.5σ of the same sign.
#[test]
fn a_drift_the_doppler_integral_sees_is_flagged_on_a_gps_altitude_that_confirms_it() {
    for (i, at_least) in [(1513, 0.6), (1365, 0.7)] {
        let s = share(Split::Tune, i, "baro-drift");
        assert!(s >= at_least, "tune #{i}: {:.0}% of the drift flagged", 100.0 * s);
    }
}

/// Regression: tune #827 (fixed wing, 10 Hz receiver σ 0.42 m, healthy
/// after a 6 s degraded fix at 36 s): with the GPS altitude only
/// confirming, its turns read as baro drifts (572 false-positive epochs),
/// since the static port's error follows the airspeed, which a turn at
/// constant ground speed changes in wind. The allowance bounds that share
/// (3 m/s of wind): 7, as before.
#[test]
fn a_fixed_wings_turns_in_wind_are_no_baro_drift() {
    let fp = common::false_positives(Split::Tune, 827, "degraded");
    assert!(fp <= 20, "{fp} false-positive epochs");
}
