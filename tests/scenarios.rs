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
