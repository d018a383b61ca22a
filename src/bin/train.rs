//! Regenerate the embedded default model, or train one from a labelled log.
//!
//! `cargo run --release --bin navguard-train` rewrites `detector/src/default_model.json`
//! from simulated flights (seeds 1000+, never the evaluation seeds), and
//! `detector/src/default_model.bin`, the binary form the crate embeds (postcard of
//! what the JSON parses to, see `navguard::model::EMBEDDED_MODEL`).
//! `cargo run --release --bin navguard-train -- --from FILE.csv [--out model.json]`
//! trains from your own labelled navlog CSV(s) (`label` column, 0/1).
//! `cargo run --release --bin navguard-train -- --battery N [--out model.json]`
//! trains from the randomised battery's tune flights 0..N (`navguard::battery`;
//! never its evaluation split), one flight in memory at a time.

use navguard::config::Config;
use navguard::logs::csv::read_csv;
use navguard::sim::{self, FaultKind, OutageMode, Scenario, Trajectory};
use navguard::Sample;

/// The training battery: outages (both modes), every fault kind at low,
/// middle and high magnitude, and clean flights of every trajectory.
fn battery() -> Vec<Scenario> {
    let mut v = vec![];
    let mut seed = 1000;
    let mut next = || {
        seed += 1;
        seed
    };
    for mode in [OutageMode::Degraded, OutageMode::Silent] {
        v.push(Scenario::paper(mode, next()));
    }
    let mags: &[(FaultKind, [f64; 3])] = &[
        (FaultKind::Step, [5.0, 10.0, 20.0]),
        (FaultKind::Ramp, [0.1, 0.5, 1.0]),
        (FaultKind::Noise, [2.0, 5.0, 10.0]),
        (FaultKind::Frozen, [0.0, 0.0, 0.0]),
        (FaultKind::ZeroVelocity, [0.0, 0.0, 0.0]),
        (FaultKind::BaroStuck, [0.0, 0.0, 0.0]),
        (FaultKind::AccelBias, [0.3, 0.6, 1.0]),
    ];
    for (kind, ms) in mags {
        for (i, m) in ms.iter().enumerate() {
            let start = [70.0, 130.0, 175.0][i];
            v.push(Scenario::with_fault(*kind, *m, start, 15.0, next()));
        }
    }
    for tr in [Trajectory::Paper, Trajectory::Aggressive, Trajectory::Survey] {
        v.push(Scenario::clean(tr, next(), 250.0));
    }
    let mut g = Scenario::paper(OutageMode::Degraded, next());
    g.imu_rate = 0.0;
    g.name = "gps-only".into();
    v.push(g);
    v
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut from = vec![];
    let mut battery_flights: Option<u64> = None;
    let mut out = String::from("detector/src/default_model.json");
    let mut i = 0;
    while i < args.len() {
        match args[i].as_str() {
            "--from" => {
                i += 1;
                from.push(args.get(i).cloned().unwrap_or_default());
            }
            "--battery" => {
                i += 1;
                battery_flights = args.get(i).and_then(|n| n.parse().ok());
                if battery_flights.is_none() {
                    eprintln!("navguard-train: --battery needs a number of tune flights");
                    std::process::exit(2);
                }
            }
            "--out" => {
                i += 1;
                out = args.get(i).cloned().unwrap_or(out);
            }
            "-h" | "--help" => {
                println!("usage: navguard-train [--from LABELLED.csv ... | --battery N] [--out model.json]");
                return;
            }
            other => {
                eprintln!("navguard-train: unknown argument {other}");
                std::process::exit(2);
            }
        }
        i += 1;
    }
    let cfg = Config::default();
    if let Some(n) = battery_flights {
        let mut ex = navguard::calibrate::Examples::default();
        for i in 0..n {
            let f = navguard::battery::Flight::draw(navguard::battery::Split::Tune, i);
            if let Err(e) = ex.add(&navguard::battery::simulate(&f), &cfg) {
                eprintln!("navguard-train: tune #{i}: {e}");
                std::process::exit(2);
            }
            if (i + 1) % 40 == 0 {
                eprintln!("navguard-train: {} of {n} tune flights", i + 1);
            }
        }
        let model = ex.fit(&cfg, 42).unwrap_or_else(|e| {
            eprintln!("navguard-train: {e}");
            std::process::exit(2)
        });
        write_model(&model, &out, true);
        return;
    }
    let streams: Vec<Vec<Sample>> = if from.is_empty() {
        battery()
            .iter()
            .map(|sc| {
                let mut rows = sim::simulate(sc).unwrap_or_else(|e| {
                    eprintln!("navguard-train: {e}");
                    std::process::exit(2)
                });
                // Baro-stuck and accel-bias epochs are not fault examples:
                // their R comes from a slow consistency test alone (the baro's
                // or the IMU's, 2-3 above clean at onset), and as D2 samples
                // they pull the decision boundary down into the range real GPS
                // logs reach. Both are detected by the same boundary without
                // being trained on (README, Known gaps). The IMU test's 3 s
                // window (and the bias the filter absorbed) also outlasts an
                // accel-bias fault by a few seconds: those epochs are neither
                // clean examples nor fault ones.
                for f in sc.faults.iter().filter(|f| matches!(f.kind, FaultKind::BaroStuck | FaultKind::AccelBias)) {
                    let tail = if f.kind == FaultKind::AccelBias { 10.0 } else { 0.0 };
                    for r in rows.iter_mut().filter(|r| r.label >= 0.5 || (r.t >= f.end && r.t < f.end + tail)) {
                        r.label = f64::NAN;
                    }
                }
                rows
            })
            .collect()
    } else {
        from.iter()
            .map(|f| {
                let bytes = std::fs::read(f).unwrap_or_else(|e| {
                    eprintln!("navguard-train: {f}: {e}");
                    std::process::exit(2)
                });
                read_csv(&bytes)
                    .unwrap_or_else(|e| {
                        eprintln!("navguard-train: {f}: {e}");
                        std::process::exit(2)
                    })
                    .samples
            })
            .collect()
    };
    let refs: Vec<&[Sample]> = streams.iter().map(|s| s.as_slice()).collect();
    let model = navguard::calibrate::train_model(&refs, &cfg, 42).unwrap_or_else(|e| {
        eprintln!("navguard-train: {e}");
        std::process::exit(2)
    });
    write_model(&model, &out, from.is_empty());
}

/// Write the model's JSON to `out`, and beside it (`.json` → `.bin`) the
/// binary form the crate embeds when `embedded`.
fn write_model(model: &navguard::model::Model, out: &str, embedded: bool) {
    let json = serde_json::to_string(model).unwrap_or_default();
    let json = json + "\n";
    if let Err(e) = std::fs::write(out, &json) {
        eprintln!("navguard-train: cannot write {out}: {e}");
        std::process::exit(2);
    }
    // The embedded binary is made from the JSON text, as its test checks.
    if let Some(stem) = out.strip_suffix(".json").filter(|_| embedded) {
        let bin = format!("{stem}.bin");
        let written = navguard::model::binary_of_json(&json).and_then(|b| std::fs::write(&bin, b).map_err(|e| e.to_string()));
        if let Err(e) = written {
            eprintln!("navguard-train: cannot write {bin}: {e}");
            std::process::exit(2);
        }
    }
    eprintln!("wrote {out}: {}", model.provenance);
}
