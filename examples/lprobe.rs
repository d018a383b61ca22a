//! Trace a real log's GPS epochs: `lprobe FILE [T0 T1]` prints, for each GPS
//! epoch between T0 and T1 (s, the log's clock), the verdict and the group
//! R-indicators (position, velocity, baro), the IMU test and the receiver's
//! own claims (eph m, sats).
use navguard::{config::Config, detector::Detector, logs::read_any};

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let bytes = std::fs::read(&a[1]).expect("read the log");
    let log = read_any(&bytes).expect("a log navguard reads");
    let t0: f64 = a.get(2).map_or(f64::NEG_INFINITY, |s| s.parse().unwrap());
    let t1: f64 = a.get(3).map_or(f64::INFINITY, |s| s.parse().unwrap());
    let mut det = Detector::new(Config::default()).unwrap();
    for s in &log.samples {
        let Ok(o) = det.push(s) else { continue };
        if o.gps_epoch && (t0..=t1).contains(&s.t) {
            let i = det.indicators();
            println!(
                "{:8.2} st {} k {} drv {} f {:5.2} r {:6.2} rg {:6.2} {:6.2} {:6.2} imu {:5.2} rimu {:5.2} pv {:5.2} eph {:5.2} sats {}",
                s.t, o.status, o.kind, o.driver, o.f, o.r, i.r_group[0], i.r_group[1], i.r_group[2], i.imu, i.r_imu, i.pv, s.eph, s.sats
            );
        }
    }
}
