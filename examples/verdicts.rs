//! Fingerprints of the detector's verdicts, to prove a refactor changed none.
//!
//! `cargo run --release -p navguard-examples --example verdicts -- FILE...`: the native audit of
//! each file: rows, flagged rows, and an FNV-1a hash over every row's status
//! and F bits. The Node test `tests/node/determinism.test.mjs` compares it
//! with the wasm build's.
//!
//! `cargo run --release -p navguard-examples --example verdicts -- --sim`: every preset scenario
//! and every case of the comparison battery over seeds 1..=3, under every
//! `config.method` (and the ANFIS with a short retraining cycle, so online
//! learning runs often), plus a model trained on oracle runs. One line per
//! run: rows, flagged rows, and an FNV-1a hash over every row's whole
//! output (status, kind, driver, F, R, C bits), its residuals, and the final
//! counters and filter state. Diff two runs' output to find the first run a
//! change moved.
use navguard::audit::audit;
use navguard::compare::battery;
use navguard::config::Config;
use navguard::detector::Detector;
use navguard::logs::read_any;
use navguard::methods::Method;
use navguard::sim::{preset_names, simulate, Scenario};

struct Fnv(u64);

impl Fnv {
    fn new() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
    fn byte(&mut self, b: u8) {
        self.0 ^= b as u64;
        self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
    }
    fn f64(&mut self, v: f64) {
        for b in v.to_bits().to_le_bytes() {
            self.byte(b);
        }
    }
    fn str(&mut self, s: &str) {
        for b in s.bytes() {
            self.byte(b);
        }
    }
}

fn files(paths: impl Iterator<Item = String>) {
    for path in paths {
        let Ok(bytes) = std::fs::read(&path) else {
            println!("{path}\terror\tunreadable");
            continue;
        };
        let log = match read_any(&bytes) {
            Ok(l) => l,
            Err(e) => {
                println!("{path}\terror\t{e}");
                continue;
            }
        };
        let Ok((_, cols)) = audit(&log, &Config::default()) else {
            println!("{path}\terror\taudit");
            continue;
        };
        let mut h = Fnv::new();
        for (s, f) in cols.status.iter().zip(&cols.f) {
            h.byte(*s);
            h.f64(*f);
        }
        let flagged = cols.status.iter().filter(|s| **s == 1).count();
        println!("{path}\t{}\t{flagged}\t{:016x}", cols.t.len(), h.0);
    }
}

/// One detector run over `rows`, fingerprinted row by row.
fn run(name: &str, cfg: &Config, rows: &[navguard::Sample]) {
    let mut det = match Detector::new(cfg.clone()) {
        Ok(d) => d,
        Err(e) => {
            println!("{name}\terror\t{e}");
            return;
        }
    };
    let mut h = Fnv::new();
    let mut flagged = 0;
    for (i, s) in rows.iter().enumerate() {
        let o = match det.push(s) {
            Ok(o) => o,
            Err(e) => {
                println!("{name}\terror\trow {i}: {e}");
                return;
            }
        };
        flagged += o.status as usize;
        for b in [o.status, o.kind, o.driver, o.gps_epoch as u8] {
            h.byte(b);
        }
        for v in [o.t, o.f, o.r, o.c] {
            h.f64(v);
        }
        for v in det.residuals() {
            h.f64(v);
        }
    }
    h.str(&format!("{:?}", det.stats()));
    for v in [det.position(), det.velocity(), det.accel_bias()].into_iter().flatten() {
        for a in 0..3 {
            h.f64(v[a]);
        }
    }
    h.str(&format!("{:?}", det.anfis()));
    println!("{name}\t{}\t{flagged}\t{:016x}", rows.len(), h.0);
}

fn sim() -> Result<(), String> {
    let seeds = [1u64, 2, 3];
    let mut configs: Vec<(String, Config)> =
        Method::ALL.iter().map(|&m| (m.name().to_string(), Config { method: m, ..Config::default() })).collect();
    configs.push(("anfis-tc20".into(), Config { tc: 20, ..Config::default() }));
    let mut cases: Vec<(String, Scenario)> = vec![];
    for &seed in &seeds {
        for p in preset_names() {
            cases.push((format!("preset {p} seed {seed}"), Scenario::preset(p, seed)?));
        }
        for c in battery(&[seed]) {
            if let navguard::compare::CaseFlight::Scenario(sc) = c.flight {
                cases.push((format!("battery {} seed {seed}", c.label), sc));
            }
        }
    }
    let mut streams = vec![];
    for (label, sc) in &cases {
        let rows = simulate(sc)?;
        for (cname, cfg) in &configs {
            run(&format!("{label} / {cname}"), cfg, &rows);
        }
        if label.starts_with("preset paper seed") {
            streams.push(rows);
        }
    }
    // Oracle runs: the trainer drives the detector with decisions forced to
    // the labels.
    let refs: Vec<&[navguard::Sample]> = streams.iter().map(|r| r.as_slice()).collect();
    let model = navguard::calibrate::train_model(&refs, &Config::default(), 7)?;
    let mut h = Fnv::new();
    h.str(&format!("{:?}", model));
    println!("trained model\t{}\t{}\t{:016x}", model.d1.len(), model.d2.len(), h.0);
    Ok(())
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().map(String::as_str) == Some("--sim") {
        if let Err(e) = sim() {
            eprintln!("verdicts --sim: {e}");
            std::process::exit(1);
        }
        return;
    }
    files(args.into_iter());
}
