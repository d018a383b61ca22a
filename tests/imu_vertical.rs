//! The IMU judged on the vertical axis too: the GPS vertical velocity
//! against the IMU's predicted vertical velocity changes, over 6 s, on its
//! own σ (`indicators::IndicatorEngine::observe_imu`). Before, a vertical
//! accelerometer bias was never flagged (battery tune: 0 of 5 events;
//! held-out eval misdetection 0.976 on those flights).
#![cfg(not(target_arch = "wasm32"))]

use navguard::battery::{self, Flight, Split};
use navguard::Config;

fn share(index: u64) -> (f64, f64) {
    let f = Flight::draw(Split::Tune, index);
    let r = battery::run(&f, &Config::default()).unwrap();
    let e = r.events.iter().find(|e| e.fault.kind.name() == "accel-bias").expect("the flight has an accelerometer bias");
    (e.share, e.delay)
}

/// Regression: tune #168 (hover, 0.82 m/s² for 73 s) and #26 (aggressive,
/// 1.49 m/s² for 22 s), both 0% flagged before.
#[test]
fn a_vertical_accelerometer_bias_is_flagged() {
    for i in [168, 26] {
        let (s, d) = share(i);
        assert!(s >= 0.95 && d <= 1.0, "tune #{i}: {:.0}% flagged, first flag after {d:.1} s", 100.0 * s);
    }
}
