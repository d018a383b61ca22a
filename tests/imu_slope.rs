//! The horizontal IMU test judges its window's least-squares slope, and
//! calls nothing on a window one level step explains better than a line
//! (issue 14: "indicators normalised per flight and per sensor"; session
//! 23, `LagTest::push_by_slope`).
//!
//! An accelerometer's bias ramps `z = v_gps − ΣΔv_IMU`. The change between
//! the window's two ends carries two entries' noise; the slope fitted on
//! all of them carries far less, so a slow bias is called. A step of `z`
//! is the GPS velocity's own jump (a drag-off's end, a frozen fix let go),
//! not the IMU's, and is left to the GPS tests.
#![cfg(not(target_arch = "wasm32"))]

mod common;

use common::{bias_share, flagged_after};
use navguard::battery::{Axis, Flight, Split};

/// Regression: tune #325 (a 0.31 m/s² horizontal bias for 87 s of an
/// aggressive flight; 5 Hz receiver with 1.3 m of white noise, 50 Hz
/// tactical IMU). Over 3 s the bias moves `z` by 0.9 m/s, under the call
/// of the window's ends: 17 of its 423 epochs flagged before the slope,
/// 393 with it.
#[test]
fn a_slow_accelerometer_bias_is_called_on_the_windows_slope() {
    let share = bias_share(&Flight::draw(Split::Tune, 325));
    assert!(share >= 0.85, "{:.0}% of the bias flagged", 100.0 * share);
}

/// Regression: tune #1144 (a 0.46 m/s² horizontal bias for 68 s of a
/// survey; 5 Hz receiver with 2.6 m of white noise, 100 Hz industrial
/// IMU): none of its 341 epochs flagged before the slope, 64 with it.
#[test]
fn a_bias_under_a_noisy_receiver_is_found() {
    let share = bias_share(&Flight::draw(Split::Tune, 1144));
    assert!(share >= 0.15, "{:.0}% of the bias flagged", 100.0 * share);
}

/// Regression: tune #560 (a 1.37 m/s² horizontal bias from 9 s to 93 s, a
/// hover). The bias began before the test armed, so neither version flags
/// it. The window's ends did not call it either, and the filter learnt it
/// as the sensor's bias; at its end that error was called for the next
/// minute (284 of the 307 epochs after it). The slope calls it while the
/// test is still unarmed, so the filter holds its estimate (session 19's
/// rule) and nothing is left to call at the end (0 of 307).
#[test]
fn a_bias_from_before_the_test_armed_leaves_no_episode_after_it() {
    let f = Flight::draw(Split::Tune, 560);
    assert_eq!((f.faults[0].kind.name(), f.faults[0].axis), ("accel-bias", Axis::Horizontal));
    let (n, of) = flagged_after(&f, 60.0);
    assert!(of > 250 && n * 20 <= of, "{n} of {of} epochs flagged in the 60 s after the bias");
}
