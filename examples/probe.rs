//! Tuning probe.
//!
//! `probe <preset> <seed> [oracle] [trace]`: metrics of one preset run.
//! `probe sweep [seeds]`: every preset over seeds 1..=seeds (default 5).
//! `probe heldout`: fault kinds at off-default magnitudes/starts, seeds 11..13.
//! `probe logs`: the real-log sanity checks.
//! `CFG` (JSON) sets the detector config (default: product defaults).
use navguard::{config::Config, detector::Detector, metrics, sim::*, Sample};

fn cfg() -> Config {
    navguard::config::ConfigInput::from_json(&std::env::var("CFG").unwrap_or_default()).unwrap()
}

/// Run, return (metrics, flagged share inside fault intervals, stats).
fn run(rows: &[Sample], oracle: bool, trace: bool) -> (metrics::Metrics, String) {
    let mut det = Detector::new(cfg()).unwrap();
    det.set_oracle(oracle);
    let (mut t, mut l, mut st) = (vec![], vec![], vec![]);
    for s in rows {
        let o = det.push(s).unwrap();
        if !s.label.is_nan() && trace && o.gps_epoch && ((s.t * 10.0).round() as i64 % 5 == 0 || s.label == 1.0 || o.status == 1) {
            let i = det.indicators();
            println!(
                "{:7.2} lab {} st {} k {} f {:6.3} r {:7.2} c {:5.2} pv {:5.2} bc {:5.2} im {:5.2} rg {:?} cg {:?} ig {:?}",
                s.t,
                s.label,
                o.status,
                o.kind,
                o.f,
                o.r,
                o.c,
                i.pv,
                i.baro_cons,
                i.imu,
                i.r_group.map(|v| (v * 100.0).round() / 100.0),
                i.c_group.map(|v| (v * 100.0).round() / 100.0),
                i.inc_group.map(|v| (v * 100.0).round() / 100.0)
            );
        }
        t.push(s.t);
        l.push(s.label);
        st.push(o.status);
    }
    let m = metrics::compute(&t, &l, &st);
    (m, format!("{:?}", det.stats()))
}

fn line(name: &str, seed: u64, m: &metrics::Metrics) -> String {
    format!(
        "{name:18} {seed:3} acc {:.4} far {:.4} mdr {:.4} tp {:5} fp {:4} fn {:5} tn {:5} det {}/{} delay {:.2}",
        m.accuracy, m.false_alarm_rate, m.misdetection_rate, m.tp, m.fp, m.r#fn, m.tn, m.detected_intervals, m.fault_intervals, m.mean_detection_delay
    )
}

fn logs() {
    let files = [
        "../shared/data/csv/ansfl_phantom4_rtk_clean.csv",
        "../shared/data/ardupilot/Loiter_RTL.bin",
        "../shared/data/px4/sample_px4_events.ulg",
    ];
    for f in files {
        let Ok(bytes) = std::fs::read(f) else {
            println!("{f}: unreadable");
            continue;
        };
        let data = match navguard::logs::read_any(&bytes) {
            Ok(d) => d,
            Err(e) => {
                println!("{f}: {e}");
                continue;
            }
        };
        let mut det = Detector::new(cfg()).unwrap();
        let (mut gps, mut flag, mut out_gps, mut out_flag) = (0u64, 0u64, 0u64, 0u64);
        let mut first_in_outage: Option<f64> = None;
        let mut flagged_times = vec![];
        let mut in_gap = false;
        for s in &data.samples {
            let Ok(o) = det.push(s) else { continue };
            let outage = f.ends_with(".bin") && (97.0..103.4).contains(&s.t);
            let gap = f.ends_with(".bin") && (51.6..73.8).contains(&s.t);
            if outage && o.status == 1 && first_in_outage.is_none() {
                first_in_outage = Some(s.t);
            }
            if gap && o.status == 1 {
                in_gap = true;
            }
            if o.gps_epoch {
                gps += 1;
                flag += o.status as u64;
                if !outage {
                    out_gps += 1;
                    out_flag += o.status as u64;
                    if o.status == 1 && flagged_times.len() < 12 {
                        flagged_times.push(format!("{:.1}k{}d{}", s.t, o.kind, o.driver));
                    }
                }
            }
        }
        println!(
            "{f}: gps epochs {gps}, flagged {flag} ({:.2}%), outside outage {:.2}%, outage first flag {:?}, gap flagged {in_gap}, stats {:?} first flags {:?}",
            100.0 * flag as f64 / gps.max(1) as f64,
            100.0 * out_flag as f64 / out_gps.max(1) as f64,
            first_in_outage,
            det.stats(),
            flagged_times
        );
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let name = args.get(1).map(|s| s.as_str()).unwrap_or("paper");
    match name {
        "sweep" => {
            let n: u64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(5);
            for p in preset_names() {
                for seed in 1..=n {
                    let rows = simulate(&Scenario::preset(p, seed).unwrap()).unwrap();
                    let (m, _) = run(&rows, false, false);
                    println!("{}", line(p, seed, &m));
                }
            }
        }
        "heldout" => {
            let cases: &[(FaultKind, f64)] = &[
                (FaultKind::Step, 5.0),
                (FaultKind::Step, 20.0),
                (FaultKind::Ramp, 0.1),
                (FaultKind::Ramp, 1.0),
                (FaultKind::Noise, 2.0),
                (FaultKind::Noise, 10.0),
                (FaultKind::Frozen, 0.0),
                (FaultKind::ZeroVelocity, 0.0),
                (FaultKind::BaroStuck, 0.0),
                (FaultKind::AccelBias, 0.3),
                (FaultKind::AccelBias, 1.0),
            ];
            for (k, mag) in cases {
                for (seed, start) in [(11u64, 80.0), (12, 150.0), (13, 200.0)] {
                    let sc = Scenario::with_fault(*k, *mag, start, 15.0, seed);
                    let rows = simulate(&sc).unwrap();
                    let (m, _) = run(&rows, false, false);
                    println!("{}", line(&sc.name, seed, &m));
                }
            }
        }
        "logs" => logs(),
        "logtrace" => {
            let f = &args[2];
            let (a, b): (f64, f64) = (args[3].parse().unwrap(), args[4].parse().unwrap());
            let data = navguard::logs::read_any(&std::fs::read(f).unwrap()).unwrap();
            let mut det = Detector::new(cfg()).unwrap();
            for s in &data.samples {
                let Ok(o) = det.push(s) else { continue };
                if s.t >= a && s.t <= b && (o.gps_epoch || s.fix.is_finite()) {
                    let i = det.indicators();
                    let rd = |v: f64| (v * 100.0).round() / 100.0;
                    println!("{:8.2} fix {} st {} k {} f {:5.2} r {:6.2} c {:4.2} pv {:5.2} bc {:5.2} im {:5.2} rg {:?} cg {:?} ig {:?} nu {:?} sg {:?} clk {:.4}", s.t, s.fix, o.status, o.kind, o.f, o.r, o.c, rd(i.pv), rd(i.baro_cons), rd(i.imu), i.r_group.map(rd), i.c_group.map(rd), i.inc_group.map(rd), det.residuals().map(rd), core::array::from_fn::<f64, 7, _>(|a| rd(det.indicator_engine().sigma(a))), det.clock_rate());
                }
            }
        }
        _ => {
            let seed: u64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(1);
            let oracle = args.get(3).map(|s| s == "oracle").unwrap_or(false);
            let sc = Scenario::preset(name, seed).unwrap();
            let rows = simulate(&sc).unwrap();
            let (m, stats) = run(&rows, oracle, args.len() > 4);
            println!("{} stats {stats}", line(name, seed, &m));
        }
    }
}
