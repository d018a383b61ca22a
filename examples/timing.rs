//! Native timing of the detector on the paper scenario (see README "Speed").
//! `cargo run --release -p navguard-examples --example timing [reps] [noretrain]`
use navguard::{config::Config, detector::Detector, sim::*};
fn main() {
    let rows = simulate(&Scenario::paper(OutageMode::Degraded, 1)).unwrap_or_default();
    let reps: usize = std::env::args().nth(1).and_then(|s| s.parse().ok()).unwrap_or(20);
    let only_no = std::env::args().nth(2).is_some();
    for retrain in [true, false] {
        if only_no && retrain {
            continue;
        }
        let t0 = std::time::Instant::now();
        for _ in 0..reps {
            let Ok(mut d) = Detector::new(Config { retrain, ..Config::default() }) else { return };
            for s in &rows {
                if let Ok(o) = d.push(s) {
                    std::hint::black_box(o);
                }
            }
        }
        let dt = t0.elapsed().as_secs_f64() / reps as f64;
        println!("retrain {retrain}: {:.2} ms per scenario, {:.0} rows/s", dt * 1e3, rows.len() as f64 / dt);
    }
}
