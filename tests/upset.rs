//! A vehicle upset (tilted past 90°: a crash or a flip) is reported as such
//! (`kind::UPSET`, status 0, an audit warning), not as GPS or baro faults:
//! the strapdown prediction cannot judge the sensors then (issue 14: the
//! crashes of Loiter_RTL and 8-10 were 2.2% and 3.8% of their GPS epochs
//! flagged outside known events).
#![cfg(not(target_arch = "wasm32"))]

mod common;

use common::data;

use navguard::audit::audit;
use navguard::detector::kind;
use navguard::logs::read_any;
use navguard::sim::{simulate, Scenario, Trajectory};
use navguard::{Config, Detector};

/// A survey flight whose attitude reads upside down (roll 180°) from 60 to 63 s:
/// its GPS epochs are "upset" until 5 s after the last such sample, then
/// judged again, and none is flagged; the epochs before it are as without
/// the flip.
#[test]
fn a_flip_suspends_verdicts_for_its_span_and_five_seconds_after() {
    let clean = simulate(&Scenario::clean(Trajectory::Survey, 11, 120.0)).unwrap();
    let mut flipped = clean.clone();
    for s in flipped.iter_mut().filter(|s| s.t >= 60.0 && s.t < 63.0 && !s.qw.is_nan()) {
        // q ⊗ (roll 180°): (w, x, y, z) ⊗ (0, 1, 0, 0).
        let (w, x, y, z) = (s.qw, s.qx, s.qy, s.qz);
        (s.qw, s.qx, s.qy, s.qz) = (-x, w, z, -y);
    }
    let (mut a, mut b) = (Detector::new(Config::default()).unwrap(), Detector::new(Config::default()).unwrap());
    let (mut upset, mut after) = (0, 0);
    for (s0, s1) in clean.iter().zip(&flipped) {
        let (o0, o1) = (a.push(s0).unwrap(), b.push(s1).unwrap());
        if !o1.gps_epoch {
            continue;
        }
        if s1.t < 60.0 {
            assert_eq!(o0, o1, "before the flip, at {} s", s1.t);
        } else if s1.t < 67.9 {
            assert_eq!((o1.kind, o1.status), (kind::UPSET, 0), "at {} s", s1.t);
            upset += 1;
        } else if s1.t >= 68.1 {
            assert_eq!((o1.kind, o1.status), (kind::NORMAL, 0), "at {} s", s1.t);
            after += 1;
        }
    }
    assert!(upset >= 70 && after >= 400, "{upset} upset epochs, {after} after");
}

/// Loiter_RTL: the vehicle tumbles from 47.7 s and lies upside down from
/// 49.3 s until the logging pause at 51.6 s (ATT roll 155–178°, CRASH_CHECK
/// at 51.56 s). That span is reported as an upset, and only the tumble
/// before it (tilt up to 29°, accelerometer spread 5–13 m/s²) is flagged.
#[test]
fn the_loiter_crash_is_an_upset_not_a_sensor_fault() {
    let log = read_any(&data("ardupilot/Loiter_RTL.bin")).unwrap();
    let (rep, _) = audit(&log, &Config::default()).unwrap();
    let w = rep.warnings.iter().find(|w| w.starts_with("vehicle upset")).unwrap_or_else(|| panic!("{:?}", rep.warnings));
    assert!(w.contains("from 49.") && w.contains("to 51."), "{w}");
    let flagged: f64 = rep.faults.iter().filter(|f| f.start < 52.0 && f.end > 45.0).map(|f| f.end - f.start).sum();
    assert!(flagged <= 1.5, "{flagged:.2} s flagged around the crash: {:?}", rep.faults);
    assert!(rep.faults.iter().all(|f| !(f.start >= 49.3 && f.start < 52.0)), "{:?}", rep.faults);
}
