//! Native scenario tests: the detector over simulated flights it was not
//! trained on (training uses seeds >= 1000; these use 1..=13 and magnitudes
//! and start times outside the training battery where noted).
#![cfg(not(target_arch = "wasm32"))]

use navguard::config::Config;
use navguard::detector::Detector;
use navguard::metrics::{self, Metrics};
use navguard::sim::{simulate, FaultKind, OutageMode, Scenario, Trajectory};

fn run(sc: &Scenario) -> Metrics {
    let rows = simulate(sc).unwrap();
    let mut det = Detector::new(Config::default()).unwrap();
    let (mut t, mut l, mut st) = (vec![], vec![], vec![]);
    for s in &rows {
        let o = det.push(s).unwrap();
        t.push(s.t);
        l.push(s.label);
        st.push(o.status);
    }
    metrics::compute(&t, &l, &st)
}

#[test]
fn paper_scenario_meets_our_target_on_five_seeds() {
    for seed in 1..=5 {
        let m = run(&Scenario::paper(OutageMode::Degraded, seed));
        assert!(m.accuracy >= 0.99 && m.false_alarm_rate <= 0.05 && m.misdetection_rate <= 0.02, "seed {seed}: {m:?}");
    }
}

#[test]
fn clean_flights_stay_under_one_percent() {
    for seed in 1..=5 {
        for tr in [Trajectory::Aggressive, Trajectory::Survey, Trajectory::Paper] {
            let m = run(&Scenario::clean(tr, seed, 300.0));
            let frac = m.fp as f64 / (m.fp + m.tn) as f64;
            assert!(frac < 0.01, "{tr:?} seed {seed}: {:.2}% flagged", 100.0 * frac);
        }
    }
}

#[test]
fn gps_faults_are_detected_at_held_out_magnitudes_and_times() {
    let cases = [
        (FaultKind::Step, 5.0),
        (FaultKind::Step, 20.0),
        (FaultKind::Noise, 2.0),
        (FaultKind::Noise, 10.0),
        (FaultKind::Ramp, 1.0),
        (FaultKind::Frozen, 0.0),
        (FaultKind::ZeroVelocity, 0.0),
    ];
    for (kind, mag) in cases {
        for (seed, start) in [(11u64, 80.0), (12, 150.0), (13, 200.0)] {
            let m = run(&Scenario::with_fault(kind, mag, start, 12.0, seed));
            assert_eq!(m.detected_intervals, 1, "{kind:?} {mag} seed {seed} at {start} s: {m:?}");
            assert!(m.mean_detection_delay <= 3.0, "{kind:?} {mag} seed {seed}: delay {}", m.mean_detection_delay);
        }
    }
}

/// Accelerometer bias (body frame, horizontal) on all three trajectories,
/// at seeds, start times and magnitudes outside the shipped battery: the
/// IMU–GPS velocity consistency test catches it once it has learnt the
/// flight's own level (20 s of flight).
#[test]
fn accel_bias_is_detected_on_every_trajectory_at_held_out_times() {
    let mut missed = vec![];
    for mag in [0.3, 0.5, 1.0] {
        for (seed, start) in [(21u64, 60.0), (22, 110.0), (23, 190.0)] {
            for tr in [Trajectory::Paper, Trajectory::Aggressive, Trajectory::Survey] {
                let mut sc = Scenario::clean(tr, seed, 250.0);
                sc.faults.push(navguard::sim::Fault {
                    kind: FaultKind::AccelBias,
                    start,
                    end: start + 20.0,
                    magnitude: mag,
                });
                let m = run(&sc);
                if m.detected_intervals != 1 || m.mean_detection_delay > 5.0 {
                    missed.push(format!("{mag} m/s² {tr:?} seed {seed} at {start} s: {m:?}"));
                }
            }
        }
    }
    // 0.3 m/s² is at the edge (the sweep in the README: 28 of 30); every
    // 0.5 and 1 m/s² bias must be caught.
    assert!(missed.iter().all(|m| m.starts_with("0.3")) && missed.len() <= 1, "{missed:#?}");
}

/// Regression: under the paper flight's noise fault (GPS noise of 5 m
/// from 120 to 135 s) the noisy altitude landed back on the baro's level
/// by chance and was taken for the GPS altitude's return
/// (`Consistency::vertical_return`): 16 re-anchorings on seed 2, two
/// epochs missed at each (20, 32 and 36 of 150 missed on seeds 1-3). The
/// return now needs the horizontal fix not to have jumped with it: 1, 0
/// and 1.
#[test]
fn a_noisy_receivers_altitude_is_no_return() {
    for seed in 1..=3 {
        let m = run(&Scenario::preset("noise", seed).unwrap());
        assert!(m.detected_intervals == 1 && m.r#fn <= 3, "seed {seed}: {m:?}");
    }
}

/// Regression: the IMU window once kept a zeroed GPS velocity (and an
/// outage's degraded one) for its 3 s after the fault, and flagged ~30
/// clean epochs per flight; a GPS-side episode now restarts it.
#[test]
fn the_imu_test_does_not_outlive_a_gps_fault() {
    for seed in 1..=3 {
        let m = run(&Scenario::preset("zero-velocity", seed).unwrap());
        assert!(m.detected_intervals == 1 && m.fp <= 10, "seed {seed}: {m:?}");
        let m = run(&Scenario::paper(OutageMode::Degraded, seed));
        assert!(m.fp <= 15, "paper seed {seed}: {m:?}");
    }
}

/// Regression: the filter once learnt part of a detected 1 m/s² bias into
/// its bias state, and the IMU test then flagged that learnt error for
/// 45 s after the fault ended (542 false alarms on this flight). The bias
/// estimate is now held while the IMU is the suspect. And the episode ends
/// on the last second of the IMU test, not after its whole 3 s window has
/// left the fault (25–28 false alarms per flight before, 13–17 after).
#[test]
fn a_detected_accel_bias_is_not_learnt_into_the_filter_and_ends_promptly() {
    for (seed, start) in [(11u64, 80.0), (12, 150.0), (13, 200.0)] {
        let m = run(&Scenario::with_fault(FaultKind::AccelBias, 1.0, start, 15.0, seed));
        assert!(m.detected_intervals == 1 && m.fp <= 20 && m.r#fn <= 10, "seed {seed} at {start} s: {m:?}");
    }
}

/// The audit names the IMU, not the GPS velocity, as what drove an
/// accelerometer-bias fault; a zeroed GPS velocity is still blamed on the
/// GPS velocity.
#[test]
fn the_audit_blames_the_imu_for_an_accel_bias_and_the_gps_for_zero_velocity() {
    use navguard::audit::audit;
    use navguard::logs::read_any;
    use navguard::sim::to_csv;
    for (preset, want) in [("accel-bias", "imu"), ("zero-velocity", "gps_velocity")] {
        let sc = Scenario::preset(preset, 4).unwrap();
        let csv = to_csv(&sc, &simulate(&sc).unwrap());
        let log = read_any(csv.as_bytes()).unwrap();
        let (report, _) = audit(&log, &Config::default()).unwrap();
        let inside: Vec<_> =
            report.faults.iter().filter(|f| f.kind == "residual" && f.end >= 120.0 && f.start <= 135.0).collect();
        assert!(!inside.is_empty() && inside.iter().all(|f| f.driver == want), "{preset}: {inside:?}");
    }
}
