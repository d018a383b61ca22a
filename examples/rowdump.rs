use navguard::{config::Config, detector::Detector, sim::*};
fn main() {
    let sc = Scenario::with_fault(FaultKind::Ramp, 1.0, 100.0, 60.0, 1);
    let rows = simulate(&sc).unwrap();
    let mut det = Detector::new(Config::default()).unwrap();
    for s in &rows { let o = det.push(s).unwrap(); if o.gps_epoch { println!("{:.2} {} {:.4}", s.t, o.status, o.f); } }
}
