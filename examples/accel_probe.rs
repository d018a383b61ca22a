//! Accelerometer-bias tuning probe (the figures in `detector/src/indicators.rs`).
//!
//! `accel_probe sweep`: accel-bias of 0.2/0.3/0.5/1 m/s² on the three
//! trajectories, seeds 101–110, starts 40–200 s, plus 85,000 clean epochs
//! (`MISS=1` lists the misses).
//! `accel_probe fault MAG SEED [START]`, `accel_probe PRESET SEED` or
//! `accel_probe LOGFILE`: one line per GPS epoch: t, label, status, IMU
//! statistic, position and velocity innovations, bias estimate, velocity, R.
use navguard::{config::ConfigInput, detector::Detector, sim::*, Sample};
fn dump(rows: &[Sample]) {
    let mut det = Detector::new(ConfigInput::from_json("").unwrap()).unwrap();
    for s in rows {
        let Ok(o) = det.push(s) else { continue };
        if o.gps_epoch {
            let r = det.residuals();
            let i = det.indicators();
            let b = det.accel_bias().unwrap_or_default();
            let v = det.velocity().unwrap_or_default();
            println!("{:.2} {} {} {:.3} {:.4} {:.4} {:.4} {:.4} {:.4} {:.4} {:.4} {:.4} {:.4} {:.3} {:.3} {:.3} {:.3}", s.t, s.label, o.status, i.imu, r[0], r[1], r[2], r[3], r[4], r[5], b[0], b[1], b[2], v[0], v[1], v[2], o.r);
        }
    }
}
fn main() {
    let a: Vec<String> = std::env::args().collect();
    if a[1] == "sweep" {
        sweep();
        return;
    }
    if a[1].ends_with(".bin") || a[1].ends_with(".ulg") || a[1].ends_with(".csv") {
        let d = navguard::logs::read_any(&std::fs::read(&a[1]).unwrap()).unwrap();
        dump(&d.samples);
    } else if a[1] == "fault" {
        let mag: f64 = a[2].parse().unwrap();
        let seed: u64 = a[3].parse().unwrap();
        let start: f64 = a.get(4).map(|s| s.parse().unwrap()).unwrap_or(120.0);
        let sc = Scenario::with_fault(FaultKind::AccelBias, mag, start, 30.0, seed);
        dump(&simulate(&sc).unwrap());
    } else {
        let seed: u64 = a[2].parse().unwrap();
        dump(&simulate(&Scenario::preset(&a[1], seed).unwrap()).unwrap());
    }
}
#[allow(dead_code)]
pub fn sweep() {
    use navguard::metrics;
    let run = |rows: &[Sample]| {
        let mut det = Detector::new(ConfigInput::from_json("").unwrap()).unwrap();
        let (mut t, mut l, mut st) = (vec![], vec![], vec![]);
        for s in rows {
            let o = det.push(s).unwrap();
            if o.gps_epoch {
                t.push(s.t);
                l.push(s.label);
                st.push(o.status);
            }
        }
        metrics::compute(&t, &l, &st)
    };
    for mag in [0.2, 0.3, 0.5, 1.0] {
        let (mut det, mut n, mut delay) = (0, 0, vec![]);
        for seed in 1..=10u64 {
            let start = [40.0, 80.0, 120.0, 160.0, 200.0][seed as usize % 5];
            for traj in [
                Trajectory::Paper,
                Trajectory::Aggressive,
                Trajectory::Survey,
            ] {
                let mut sc = Scenario::clean(traj, seed + 100, 250.0);
                sc.faults.push(Fault {
                    kind: FaultKind::AccelBias,
                    start,
                    end: start + 30.0,
                    magnitude: mag,
                });
                let m = run(&simulate(&sc).unwrap());
                n += 1;
                if m.detected_intervals > 0 {
                    det += 1;
                    delay.push(m.mean_detection_delay);
                } else if std::env::var("MISS").is_ok() {
                    println!("  miss {mag} seed {} start {start} {:?}", seed + 100, traj);
                }
            }
        }
        delay.sort_by(|a, b| a.partial_cmp(b).unwrap());
        println!(
            "accel-bias {mag}: {det}/{n} median delay {:.1}",
            delay.get(delay.len() / 2).copied().unwrap_or(f64::NAN)
        );
    }
    for p in ["clean-aggressive", "clean-survey", "clean-paper"] {
        let (mut f, mut n) = (0, 0);
        for seed in 1..=10u64 {
            let m = run(&simulate(&Scenario::preset(p, seed + 100).unwrap()).unwrap());
            f += m.fp;
            n += m.fp + m.tn;
        }
        println!("{p}: {f}/{n} flagged");
    }
}
