//! Issue 14 mechanisms 1 and 3: a fault lasts as long as its evidence. A
//! persisting step or frozen GPS is flagged for its whole duration (no
//! fixed coast limit for a position-only episode), and when the GPS comes
//! back to the truth that return ends the episode instead of opening a new
//! one.
#![cfg(not(target_arch = "wasm32"))]

use navguard::{config::Config, detector::Detector, sim::*};

/// (share of the fault's GPS epochs flagged, flagged GPS epochs in the 30 s
/// after it, flagged GPS epochs elsewhere).
fn run(kind: FaultKind, magnitude: f64, length: f64, seed: u64) -> (f64, usize, usize) {
    let start = 100.0;
    let rows = simulate(&Scenario::with_fault(kind, magnitude, start, length, seed)).unwrap();
    let mut det = Detector::new(Config::default()).unwrap();
    let (mut inside, mut flagged, mut after, mut elsewhere) = (0, 0, 0, 0);
    for s in &rows {
        let o = det.push(s).unwrap();
        if !o.gps_epoch {
            continue;
        }
        if s.t >= start && s.t < start + length {
            inside += 1;
            flagged += o.status as usize;
        } else if s.t >= start + length && s.t < start + length + 30.0 {
            after += o.status as usize;
        } else {
            elsewhere += o.status as usize;
        }
    }
    (flagged as f64 / inside as f64, after, elsewhere)
}

#[test]
fn a_60_s_step_is_flagged_throughout_and_its_end_opens_no_new_interval() {
    for seed in 1..=3 {
        for (m, len) in [(10.0, 60.0), (5.0, 30.0)] {
            let (share, after, elsewhere) = run(FaultKind::Step, m, len, seed);
            assert!(share >= 0.99, "{m} m {len} s seed {seed}: {share}");
            assert!(after <= 10 && elsewhere <= 10, "{m} m {len} s seed {seed}: {after} after, {elsewhere} elsewhere");
        }
    }
}

#[test]
fn a_60_s_frozen_gps_is_flagged_for_90_percent_of_it() {
    for seed in 1..=3 {
        let (share, _, _) = run(FaultKind::Frozen, 0.0, 60.0, seed);
        assert!(share >= 0.90, "seed {seed}: {share}");
    }
}

#[test]
fn a_ramp_is_flagged_for_as_long_as_it_lasts() {
    for seed in 1..=3 {
        let (share, after, _) = run(FaultKind::Ramp, 1.0, 60.0, seed);
        assert!(share >= 0.95 && after <= 10, "1 m/s seed {seed}: {share}, {after} after");
    }
    // A 0.3 m/s ramp stays under the position–velocity test's threshold
    // here and is absorbed; its sudden end then opens an episode of its own
    // (a known gap, README "Known gaps").
}
