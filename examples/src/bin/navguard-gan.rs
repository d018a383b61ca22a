//! `navguard-gan`: trains the GAN-FDSR detector and reproduces Table 1 and
//! Table 5 of Shen et al. 2022 (see `docs/tight.md`).
//!
//! ```text
//! navguard-gan train  [--seeds A..=B] [--calib A..=B] [--epochs N] [--out FILE]
//! navguard-gan table5 [--runs N] [--seed S] [--env 1|5] [--model FILE] [--eta X]
//! ```
//! `train` writes the model (default `src/tight/gan_default.bin`, the one
//! embedded in the library) and prints Table 1 and the threshold;
//! `table5` prints detection delay and missing-alarm rate for FDI, FDA and
//! GAN-FDSR over the five fault types of Table 4, the positioning error
//! relative to fault-free (Figure 12) and the fault-free false-alarm rates.

use std::process::ExitCode;
use std::time::Instant;

use navguard::tight::chaos::table1_markdown;
use navguard::tight::fdi::{FdsrConfig, Strategy};
use navguard::tight::gan_fdsr::{default_model, GanDetectorModel, GanInput};
use navguard::tight::gan_fdsr_train::{train_detector, GanTrainOptions};
use navguard::tight::scenario::{environments, run, FaultSpec, FaultType, RunRecord, RunSpec, SimConfig, World};

fn main() -> ExitCode {
    match real_main() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("navguard-gan: {e}");
            ExitCode::from(2)
        }
    }
}

fn parse_range(v: &str, flag: &str) -> Result<Vec<u64>, String> {
    let (a, b) = v.split_once("..=").ok_or_else(|| format!("{flag}: expected A..=B, got {v:?}"))?;
    let a: u64 = a.parse().map_err(|_| format!("{flag}: not an integer: {a:?}"))?;
    let b: u64 = b.parse().map_err(|_| format!("{flag}: not an integer: {b:?}"))?;
    if b < a {
        return Err(format!("{flag}: empty range {v:?}"));
    }
    Ok((a..=b).collect())
}

fn num<T: std::str::FromStr>(args: &mut impl Iterator<Item = String>, flag: &str) -> Result<T, String> {
    let v = args.next().ok_or_else(|| format!("{flag} needs a value"))?;
    v.parse().map_err(|_| format!("{flag}: bad value {v:?}"))
}

fn real_main() -> Result<(), String> {
    let mut args = std::env::args().skip(1);
    let cmd = args.next().unwrap_or_default();
    match cmd.as_str() {
        "train" => train(args),
        "table5" => table5(args),
        _ => Err("usage: navguard-gan train [--seeds A..=B] [--calib A..=B] [--epochs N] [--out FILE] | table5 [--runs N] [--seed S] [--env 1|5] [--model FILE] [--eta X]".into()),
    }
}

fn train(mut args: impl Iterator<Item = String>) -> Result<(), String> {
    let mut opts = GanTrainOptions::default();
    let mut out = "src/tight/gan_default.bin".to_string();
    while let Some(a) = args.next() {
        match a.as_str() {
            "--seeds" => opts.train_seeds = parse_range(&args.next().unwrap_or_default(), "--seeds")?,
            "--calib" => opts.calib_seeds = parse_range(&args.next().unwrap_or_default(), "--calib")?,
            "--epochs" => opts.gan.epochs = num(&mut args, "--epochs")?,
            "--hidden" => opts.gan.hidden = num(&mut args, "--hidden")?,
            "--window" => opts.gan.window = num(&mut args, "--window")?,
            "--no-lambda-test" => opts.lambda_test = false,
            "--z-iters" => opts.gan.z_iters = num(&mut args, "--z-iters")?,
            "--input" => {
                (opts.input, opts.lambda_test) = match args.next().as_deref() {
                    Some("rhod") => (GanInput::IncrementDifference, false),
                    Some("lambda") => (GanInput::Innovation, true),
                    x => return Err(format!("--input: rhod or lambda, got {x:?}")),
                }
            }
            "--out" => out = args.next().ok_or("--out needs a file")?,
            x => return Err(format!("train: unknown argument {x:?}")),
        }
    }
    let sim = SimConfig::default();
    let world = World::new(&sim).map_err(|e| e.to_string())?;
    let envs = environments(&world, &sim).map_err(|e| e.to_string())?;
    let prns = envs.first().ok_or("no environment")?.prns.clone();
    let t0 = Instant::now();
    let mut last = Instant::now();
    let (model, report) = train_detector(&world, &sim, &prns, &opts, &mut |p| {
        if last.elapsed().as_secs_f64() > 2.0 || p.epoch == p.epochs {
            eprintln!("epoch {}/{}: D loss {:.4}, G loss {:.4}, D(real) {:.3}, D(fake) {:.3}", p.epoch, p.epochs, p.d_loss, p.g_loss, p.d_real, p.d_fake);
            last = Instant::now();
        }
        true
    })
    .map_err(|e| e.to_string())?;
    let secs = t0.elapsed().as_secs_f64();
    println!("### Table 1: chaos indices of the simulated satellites ({} series, seed {})\n", opts.input.name(), opts.train_seeds[0]);
    println!("{}", table1_markdown(&report.chaos));
    println!(
        "chosen tau {} s, m {} (medians); {} training windows, {} calibration windows; {} parameters",
        report.tau,
        report.m,
        report.train_windows,
        report.calib_windows,
        model.gan.param_count()
    );
    println!("lambda {:.4}; T2 {:?}", model.gan.lambda(), report.threshold);
    println!("training took {secs:.1} s natively");
    let bytes = model.to_bytes().map_err(|e| e.to_string())?;
    std::fs::write(&out, &bytes).map_err(|e| format!("{out}: {e}"))?;
    println!("model ({} bytes) written to {out}", bytes.len());
    Ok(())
}

/// The GAN trained on the paper's ρD series (`navguard-gan train --input rhod
/// --out src/tight/gan_rhod.bin`), for the paper-faithful column of Table 5.
const PAPER_MODEL: &[u8] = include_bytes!("../../../src/tight/gan_rhod.bin");

struct Cell {
    delays: Vec<Option<f64>>,
    missed: Vec<f64>,
    rel_err: Vec<f64>,
}

fn table5(mut args: impl Iterator<Item = String>) -> Result<(), String> {
    let (mut runs, mut seed, mut env_no, mut eta) = (10u64, 1u64, 1usize, 0.035f64);
    let (mut model_path, mut paper_path): (Option<String>, Option<String>) = (None, None);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--runs" => runs = num(&mut args, "--runs")?,
            "--seed" => seed = num(&mut args, "--seed")?,
            "--env" => env_no = num(&mut args, "--env")?,
            "--eta" => eta = num(&mut args, "--eta")?,
            "--model" => model_path = Some(args.next().ok_or("--model needs a file")?),
            "--paper-model" => paper_path = Some(args.next().ok_or("--paper-model needs a file")?),
            x => return Err(format!("table5: unknown argument {x:?}")),
        }
    }
    if runs == 0 {
        return Err("--runs: must be >= 1".into());
    }
    let read = |p: &str| -> Result<GanDetectorModel, String> {
        GanDetectorModel::from_bytes(&std::fs::read(p).map_err(|e| format!("{p}: {e}"))?).map_err(|e| format!("{p}: {e}"))
    };
    let ours = match &model_path {
        Some(p) => read(p)?,
        None => default_model().map_err(|e| e.to_string())?,
    };
    let paper = match &paper_path {
        Some(p) => read(p)?,
        None => GanDetectorModel::from_bytes(PAPER_MODEL).map_err(|e| format!("embedded rhoD model: {e} (run `navguard-gan train --input rhod --out src/tight/gan_rhod.bin`)"))?,
    };
    let sim = SimConfig::default();
    let world = World::new(&sim).map_err(|e| e.to_string())?;
    let envs = environments(&world, &sim).map_err(|e| e.to_string())?;
    let env = envs.get(env_no.wrapping_sub(1)).ok_or_else(|| format!("--env: 1..={}, got {env_no}", envs.len()))?;
    // The fault section of Section 4.2 (300–360 s) on the environment's faulty satellite.
    let (a, b) = (300.0, 360.0);
    let methods: [(&str, Strategy, Option<&GanDetectorModel>); 4] = [
        ("FDI", Strategy::Fdi, None),
        ("FDA", Strategy::Fda, None),
        ("GAN-FDSR (rhoD, paper)", Strategy::Gan, Some(&paper)),
        ("GAN-FDSR (lambda, ours)", Strategy::Gan, Some(&ours)),
    ];
    let seeds: Vec<u64> = (seed..seed + runs).collect();
    let t0 = Instant::now();
    let mut cells: Vec<Vec<Cell>> = Vec::new();
    let mut gan_secs = [0.0f64; 4];
    let mut gan_epochs = [0usize; 4];
    let spec = |strategy, fault, s, gan| RunSpec {
        world: &world,
        cfg: &sim,
        prns: &env.prns,
        watch_prn: env.faulty_prn,
        fault,
        fdsr: FdsrConfig { strategy, alpha: 0.001, eta },
        seed: s,
        gan,
    };
    for kind in FaultType::ALL {
        let mut row: Vec<Cell> = methods.iter().map(|_| Cell { delays: vec![], missed: vec![], rel_err: vec![] }).collect();
        for &s in &seeds {
            let fault = FaultSpec { prn: env.faulty_prn, kind, start: a, end: b };
            let ff = run(&spec(Strategy::None, None, s, None)).map_err(|e| e.to_string())?;
            for (k, (cell, (_, strategy, gan))) in row.iter_mut().zip(methods).enumerate() {
                let t = Instant::now();
                let r = run(&spec(strategy, Some(fault), s, gan)).map_err(|e| e.to_string())?;
                gan_secs[k] += t.elapsed().as_secs_f64();
                gan_epochs[k] += r.t.len();
                cell.delays.push(r.detection_delay(env.faulty_prn, a, b));
                cell.missed.push(1.0 - r.flag_rate(env.faulty_prn, a, b));
                cell.rel_err.push(rel_error(&ff, &r, a, b));
            }
        }
        eprintln!("{} done ({:.0} s)", kind.name(), t0.elapsed().as_secs_f64());
        cells.push(row);
    }
    println!(
        "### Table 5: detection delay (s) and missing-alarm rate, Env {env_no} ({} satellites, faulty G{}), fault 300-360 s, seeds {}..={}\n",
        env.prns.len(),
        env.faulty_prn,
        seeds[0],
        seeds[seeds.len() - 1]
    );
    let names: Vec<&str> = methods.iter().map(|m| m.0).collect();
    println!("Delay: mean over the runs that flagged the faulty satellite in the section (how many of {runs} did) / mean counting a miss as 60 s. Missed: fraction of fault epochs in which the faulty satellite is not flagged.\n");
    println!("| fault | {} | paper FDI/FDA/GAN-FDSR |", names.iter().map(|n| format!("{n} delay")).collect::<Vec<_>>().join(" | "));
    println!("|---|{}---|", "---|".repeat(names.len()));
    let paper_d = ["0/0/0", "60/60/0", "18/18/3", "34/34/6", "54/54/9"];
    let paper_m = ["0/0/0%", "100/100/0%", "30/30/5%", "57/57/10%", "90/90/15%"];
    for ((kind, row), p) in FaultType::ALL.iter().zip(&cells).zip(paper_d) {
        let d: Vec<String> = row.iter().map(|c| fmt_delay(&c.delays)).collect();
        println!("| {} | {} | {p} |", kind.name(), d.join(" | "));
    }
    println!("\n| fault | {} | paper FDI/FDA/GAN-FDSR |", names.iter().map(|n| format!("{n} missed")).collect::<Vec<_>>().join(" | "));
    println!("|---|{}---|", "---|".repeat(names.len()));
    for ((kind, row), p) in FaultType::ALL.iter().zip(&cells).zip(paper_m) {
        let m: Vec<String> = row.iter().map(|c| format!("{:.0}%", 100.0 * mean(&c.missed))).collect();
        println!("| {} | {} | {p} |", kind.name(), m.join(" | "));
    }
    println!("\n### Figure 12: mean positioning error relative to fault-free in 300-360 s (m)\n");
    println!("| fault | {} |", names.join(" | "));
    println!("|---|{}", "---|".repeat(names.len()));
    for (kind, row) in FaultType::ALL.iter().zip(&cells) {
        let e: Vec<String> = row.iter().map(|c| format!("{:.2}", mean(&c.rel_err))).collect();
        println!("| {} | {} |", kind.name(), e.join(" | "));
    }
    // Fault-free false alarms.
    println!("\n### Fault-free flights (same seeds, no fault, after 30 s)\n");
    println!("| method | epochs flagged | per epoch | per satellite-epoch (alpha = 0.001) | run time per GNSS epoch (ms, native) |");
    println!("|---|---|---|---|---|");
    for (k, (name, strategy, gan)) in methods.iter().enumerate() {
        let (mut flagged, mut n_ep, mut n_sat_ep) = (0usize, 0usize, 0usize);
        for &s in &seeds {
            let r = run(&spec(*strategy, None, s, *gan)).map_err(|e| e.to_string())?;
            let settled: Vec<usize> = (0..r.t.len()).filter(|&i| r.t[i] >= 30.0).collect();
            flagged += settled.iter().filter(|&&i| r.flagged_prn[i] != 0).count();
            n_ep += settled.len();
            n_sat_ep += settled.iter().map(|&i| r.ranges[i].len()).sum::<usize>();
        }
        println!(
            "| {name} | {flagged} / {n_ep} | {:.4} | {:.5} | {:.2} |",
            flagged as f64 / n_ep.max(1) as f64,
            flagged as f64 / n_sat_ep.max(1) as f64,
            1e3 * gan_secs[k] / gan_epochs[k].max(1) as f64
        );
    }
    println!(
        "\nGAN models: ours tau {} m {} (z search {} iterations), paper tau {} m {}; total {:.0} s",
        ours.tau,
        ours.m,
        ours.gan.config().z_iters,
        paper.tau,
        paper.m,
        t0.elapsed().as_secs_f64()
    );
    Ok(())
}

fn mean(v: &[f64]) -> f64 {
    let f: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    if f.is_empty() {
        f64::NAN
    } else {
        f.iter().sum::<f64>() / f.len() as f64
    }
}

/// "mean of detecting runs (k/n) / mean with misses as 60 s".
fn fmt_delay(d: &[Option<f64>]) -> String {
    let hit: Vec<f64> = d.iter().flatten().copied().collect();
    let all: Vec<f64> = d.iter().map(|x| x.unwrap_or(60.0)).collect();
    if hit.is_empty() {
        format!("- (0/{}) / 60", d.len())
    } else {
        format!("{:.1} ({}/{}) / {:.1}", mean(&hit), hit.len(), d.len(), mean(&all))
    }
}

fn rel_error(ff: &RunRecord, r: &RunRecord, a: f64, b: f64) -> f64 {
    let d: Vec<f64> = r.pos_err.iter().zip(&ff.pos_err).zip(&r.t).filter(|(_, &t)| t >= a && t < b).map(|((x, y), _)| x - y).collect();
    mean(&d)
}
