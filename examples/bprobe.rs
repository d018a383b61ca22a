//! Trace one battery flight: `bprobe tune|eval INDEX [IMU_HZ]` prints each
//! GPS epoch, ending with the filter's accelerometer-bias estimate (`ab`,
//! body frame, m/s²) (optionally with the flight's IMU at another rate);
//! `bprobe check C I` traces instance `I` of the specific check `C`
//! (`battery::CHECKS`). With `BPROBE_BARO=1` the baro rows too; with
//! `BPROBE_RETRO=1` only the spans the detector dates for the reconciled
//! verdict, with the healthy, faulty and causally flagged epochs in each.
use navguard::{battery, config::Config, detector::Detector};

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let mut f = if a[1] == "check" {
        let c: usize = a[2].parse().unwrap();
        battery::CHECKS[c].flight(c, a[3].parse().unwrap())
    } else {
        battery::Flight::draw(battery::Split::parse(&a[1]).unwrap(), a[2].parse().unwrap())
    };
    if let Some(hz) = a.get(3).filter(|_| a[1] != "check") {
        f = f.with_imu_rate(hz.parse().unwrap());
    }
    println!("# {}\n# {:?}", f.describe(), f.baro);
    let rows = battery::simulate(&f);
    // BPROBE_BARO=1: also print every baro row (t, value).
    let baro = std::env::var("BPROBE_BARO").is_ok();
    let mut det = Detector::new(Config::default()).unwrap();
    // BPROBE_RETRO=1: only the dated spans, with the GPS epochs in each
    // that are healthy (label 0) and faulty, and the causal status there.
    let retro_only = std::env::var("BPROBE_RETRO").is_ok();
    let mut seen: Vec<(f64, f64, u8)> = Vec::new();
    for s in &rows {
        let o = det.push(s).unwrap();
        if o.gps_epoch {
            seen.push((s.t, s.label, o.status));
        }
        if let Some(since) = det.retro_since() {
            let inside = seen.iter().filter(|e| e.0 >= since && e.0 < s.t);
            let (mut ok, mut bad, mut flagged) = (0, 0, 0);
            for e in inside {
                if e.1 == 0.0 { ok += 1 } else { bad += 1 }
                flagged += u32::from(e.2 != 0);
            }
            println!("{:8.2} retro since {since:.2} group {} healthy {ok} faulty {bad} flagged {flagged}", s.t, det.retro_group());
        }
        if retro_only {
            continue;
        }
        if baro && s.baro.is_finite() {
            println!("{:8.2} baro {:.4}", s.t, s.baro);
        }
        if o.gps_epoch {
            let i = det.indicators();
            let b = det.accel_bias().map_or([f64::NAN; 3], |b| [b.x, b.y, b.z]);
            println!("{:8.2} lab {} st {} k {} drv {} f {:5.2} r {:6.2} rg {:6.2} {:6.2} {:6.2} imu {:5.2} rimu {:5.2} pv {:5.2} ab {:6.3} {:6.3} {:6.3}", s.t, s.label, o.status, o.kind, o.driver, o.f, o.r, i.r_group[0], i.r_group[1], i.r_group[2], i.imu, i.r_imu, i.pv, b[0], b[1], b[2]);
        }
    }
}
