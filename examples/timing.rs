use navguard::{config::Config, detector::Detector, sim::*};
fn main() {
    let rows = simulate(&Scenario::paper(OutageMode::Degraded, 1)).unwrap();
    for retrain in [true, false] {
        let t0 = std::time::Instant::now();
        let reps: usize = std::env::args().nth(1).and_then(|s| s.parse().ok()).unwrap_or(20);
        for _ in 0..reps {
            let mut d = Detector::new(Config { retrain, ..Config::default() }).unwrap();
            for s in &rows { std::hint::black_box(d.push_valid(s)); }
        }
        let dt = t0.elapsed().as_secs_f64() / reps as f64;
        println!("retrain {retrain}: {:.2} ms per scenario, {:.0} rows/s", dt * 1e3, rows.len() as f64 / dt);
    }
    let t0 = std::time::Instant::now();
    for _ in 0..20 { std::hint::black_box(Detector::new(Config::default()).unwrap()); }
    println!("Detector::new: {:.3} ms", t0.elapsed().as_secs_f64() / 20.0 * 1e3);
}
