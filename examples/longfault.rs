//! Long-fault probe (issue 14 mechanisms 1 and 3): flagged share inside the
//! fault and flagged rows after it, per kind and length.
//! `cargo run --release -p navguard-examples --example longfault`
use navguard::{config::Config, detector::Detector, sim::*};

fn main() {
    let cases: &[(FaultKind, f64, f64)] = &[
        (FaultKind::Step, 10.0, 60.0),
        (FaultKind::Step, 5.0, 30.0),
        (FaultKind::Frozen, 0.0, 60.0),
        (FaultKind::Ramp, 0.3, 60.0),
        (FaultKind::Ramp, 1.0, 60.0),
    ];
    for &(kind, mag, len) in cases {
        for seed in 1..=3u64 {
            let sc = Scenario::with_fault(kind, mag, 100.0, len, seed);
            let rows = simulate(&sc).unwrap();
            let mut det = Detector::new(Config::default()).unwrap();
            let (mut inside, mut inside_flag, mut after_flag, mut first) = (0, 0, 0, f64::NAN);
            let mut clean_flag = 0;
            for s in &rows {
                let o = det.push(s).unwrap();
                if !o.gps_epoch {
                    continue;
                }
                let in_fault = s.t >= 100.0 && s.t < 100.0 + len;
                if in_fault {
                    inside += 1;
                    if o.status == 1 {
                        inside_flag += 1;
                        if first.is_nan() {
                            first = s.t - 100.0;
                        }
                    }
                } else if o.status == 1 {
                    if s.t >= 100.0 + len && s.t < 100.0 + len + 30.0 {
                        after_flag += 1;
                    } else {
                        clean_flag += 1;
                    }
                }
            }
            println!(
                "{:10} {:5} {:4}s seed {seed}: flagged {:5.1}% of fault epochs, first after {:5.2} s, {:3} flagged epochs in the 30 s after, {:3} elsewhere",
                kind.name(), mag, len, 100.0 * inside_flag as f64 / inside as f64, first, after_flag, clean_flag
            );
        }
    }
}
