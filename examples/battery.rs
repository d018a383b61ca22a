//! Run a detector over the randomised battery (src/battery.rs) and print the
//! issue 14 acceptance figures, per-condition tables and specific checks.
//!
//! `cargo run --release -p navguard-examples --example battery -- [--split eval|tune] [--flights N]
//!  [--start I] [--method M] [--config CFG.json] [--checks N] [--imu-flights N]
//!  [--threads T] [--json] [--verbose] [--write DIR] [--sacc] [--reconciled]`
//!
//! `--sacc`: the same flights with receivers that report their speed
//! accuracy (`Flight::with_speed_claims`).
//!
//! `--reconciled`: score the whole-flight reconciled verdicts (what
//! `audit` reports as `reconciled`, `FlightResult::reconciled`) instead of
//! the causal ones.
//!
//! Defaults: eval split, 240 flights, the default detector, 6 instances per
//! specific check, 6 flights for IMU-rate invariance, 2 threads.
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use navguard::battery::{self, Flight, FlightResult, GroupRow, Split, CHECKS};
use navguard::{Config, ConfigInput};

struct Args {
    split: Split,
    flights: u64,
    start: u64,
    cfg: Config,
    checks: u64,
    imu_flights: u64,
    threads: usize,
    json: bool,
    verbose: bool,
    write: Option<String>,
    sacc: bool,
    reconciled: bool,
}

fn parse() -> Result<Args, String> {
    let mut a = Args { split: Split::Eval, flights: 240, start: 0, cfg: Config::default(), checks: 6, imu_flights: 6, threads: 2, json: false, verbose: false, write: None, sacc: false, reconciled: false };
    let mut it = std::env::args().skip(1);
    let num = |v: Option<String>, name: &str| -> Result<u64, String> { v.ok_or(format!("{name}: missing value"))?.parse().map_err(|e| format!("{name}: {e}")) };
    let mut method: Option<String> = None;
    let mut cfg_text: Option<String> = None;
    while let Some(k) = it.next() {
        match k.as_str() {
            "--split" => a.split = Split::parse(&it.next().unwrap_or_default())?,
            "--flights" => a.flights = num(it.next(), "--flights")?,
            "--start" => a.start = num(it.next(), "--start")?,
            "--checks" => a.checks = num(it.next(), "--checks")?,
            "--imu-flights" => a.imu_flights = num(it.next(), "--imu-flights")?,
            "--threads" => a.threads = num(it.next(), "--threads")?.max(1) as usize,
            "--method" => method = it.next(),
            "--config" => {
                let p = it.next().ok_or("--config: missing path")?;
                cfg_text = Some(std::fs::read_to_string(&p).map_err(|e| format!("{p}: {e}"))?);
            }
            "--json" => a.json = true,
            "--verbose" => a.verbose = true,
            "--write" => a.write = it.next(),
            "--sacc" => a.sacc = true,
            "--reconciled" => a.reconciled = true,
            other => return Err(format!("unknown argument {other}")),
        }
    }
    a.cfg = ConfigInput::from_json(cfg_text.as_deref().unwrap_or(""))?;
    if let Some(m) = method {
        a.cfg.method = navguard::methods::Method::parse(&m)?;
    }
    Ok(a)
}

/// Run every flight on `threads` threads; results in flight order.
fn run_all(flights: &[Flight], cfg: &Config, threads: usize, reconciled: bool) -> Result<Vec<FlightResult>, String> {
    let next = AtomicUsize::new(0);
    let out: Mutex<Vec<Option<Result<FlightResult, String>>>> = Mutex::new(vec![None; flights.len()]);
    std::thread::scope(|s| {
        for _ in 0..threads {
            s.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                let Some(f) = flights.get(i) else { break };
                let r = battery::run(f, cfg).map(|r| if reconciled { r.reconciled() } else { r });
                if let Ok(mut o) = out.lock() {
                    o[i] = Some(r);
                }
            });
        }
    });
    out.into_inner().map_err(|e| e.to_string())?.into_iter().map(|r| r.unwrap_or_else(|| Err("flight not run".into()))).collect()
}

fn pct(x: f64) -> String {
    if x.is_nan() {
        "–".into()
    } else {
        format!("{:.1}%", 100.0 * x)
    }
}

fn row_md(r: &GroupRow) -> String {
    let m = &r.metrics;
    format!(
        "| {} | {} | {} | {:.3} | {:.3} | {:.3} | {}/{} | {} | {} | {} |",
        r.key,
        r.flights,
        m.tp + m.fp + m.tn + m.r#fn,
        m.accuracy,
        m.false_alarm_rate,
        m.misdetection_rate,
        r.events_flagged,
        r.events,
        pct(r.mean_event_share),
        if r.median_delay.is_nan() { "–".into() } else { format!("{:.1} s", r.median_delay) },
        if r.clean_epochs == 0 { "–".into() } else { format!("{:.2}% ({})", r.clean_pct(), r.clean_flights) },
    )
}

const HEAD: &str = "| | flights | GPS epochs | accuracy | false alarm | misdetection | events flagged | mean share of event flagged | median delay | clean flights: epochs flagged (flights) |\n|---|---|---|---|---|---|---|---|---|---|";

fn main() -> Result<(), String> {
    let a = parse()?;
    let t0 = std::time::Instant::now();
    let flights: Vec<Flight> = (a.start..a.start + a.flights).map(|i| Flight::draw(a.split, i)).map(|f| if a.sacc { f.with_speed_claims() } else { f }).collect();
    if let Some(dir) = &a.write {
        std::fs::create_dir_all(dir).map_err(|e| format!("{dir}: {e}"))?;
        for f in &flights {
            let path = format!("{dir}/{}-{:06}.csv", a.split.name(), f.index);
            std::fs::write(&path, battery::to_csv(f, &battery::simulate(f))).map_err(|e| format!("{path}: {e}"))?;
        }
        eprintln!("wrote {} flights to {dir}", flights.len());
    }
    let results = run_all(&flights, &a.cfg, a.threads, a.reconciled)?;
    let overall = battery::group_row("all", &results.iter().collect::<Vec<_>>(), &|_| true);
    // The same flights' whole-log reconciled verdicts (what `audit` lists as
    // `reconciled`), beside the causal ones.
    let reconciled: Vec<FlightResult> = results.iter().map(|r| r.reconciled()).collect();
    let overall_rec = battery::group_row("all", &reconciled.iter().collect::<Vec<_>>(), &|_| true);
    let tables = battery::tables(&results);

    // Specific checks.
    let mut check_rows = vec![];
    for (c, spec) in CHECKS.iter().enumerate() {
        let fl: Vec<Flight> = (0..a.checks).map(|i| spec.flight(c, i)).collect();
        let rs = run_all(&fl, &a.cfg, a.threads, a.reconciled)?;
        let evs: Vec<battery::EventResult> = rs.iter().filter_map(|r| r.events.first().cloned()).collect();
        check_rows.push((spec, evs));
    }
    let mut imu_rows = vec![];
    for i in 0..a.imu_flights {
        let fl = battery::imu_rate_flights(i);
        let rs = run_all(&fl, &a.cfg, a.threads, a.reconciled)?;
        let pcts: Vec<f64> = rs.iter().map(|r| r.flagged_pct()).collect();
        imu_rows.push((fl[0].describe().replace("IMU 50 Hz", "IMU 50-400 Hz"), pcts));
    }
    let secs = t0.elapsed().as_secs_f64();
    let rows: u64 = results.iter().map(|r| r.rows).sum();

    if a.json {
        let checks: Vec<serde_json::Value> = check_rows
            .iter()
            .map(|(s, evs)| serde_json::json!({ "check": s, "events": evs, "passed": evs.iter().filter(|e| s.passes(e)).count() }))
            .collect();
        let imu: Vec<serde_json::Value> = imu_rows
            .iter()
            .map(|(d, p)| serde_json::json!({ "flight": d, "rates": battery::IMU_RATES, "flaggedPct": p, "spread": battery::spread(p) }))
            .collect();
        let events: Vec<serde_json::Value> = results
            .iter()
            .flat_map(|r| r.events.iter().map(move |e| serde_json::json!({ "flight": r.flight.index, "seed": r.flight.seed, "event": e })))
            .collect();
        // Per flight: the confusion counts over its labelled GPS epochs, so
        // two runs can be compared flight by flight.
        let per_flight: Vec<serde_json::Value> = results
            .iter()
            .map(|r| {
                let count = |flagged: bool, faulty: bool| r.epochs.iter().filter(|e| !e.label.is_nan() && (e.status != 0) == flagged && (e.label != 0.0) == faulty).count();
                serde_json::json!({ "flight": r.flight.index, "tp": count(true, true), "fp": count(true, false), "fn": count(false, true), "tn": count(false, false) })
            })
            .collect();
        let v = serde_json::json!({
            "split": a.split.name(), "start": a.start, "flights": a.flights, "method": a.cfg.method.name(),
            "overall": overall, "overallReconciled": overall_rec, "tables": tables, "events": events, "checks": checks, "imuRate": imu,
            "rows": rows, "seconds": secs, "perFlight": per_flight,
        });
        println!("{v}");
        return Ok(());
    }

    let (m, mr) = (&overall.metrics, &overall_rec.metrics);
    let first = if a.reconciled { "reconciled" } else { "causal (push)" };
    println!("## Battery: {} split, flights {}..{}, method {}\n", a.split.name(), a.start, a.start + a.flights, a.cfg.method.name());
    println!("| figure | {first} | reconciled (audit, whole log) | target |\n|---|---|---|---|");
    println!("| accuracy | {:.3} | {:.3} | ≥ 0.97 |", m.accuracy, mr.accuracy);
    println!("| false alarm FP/(TP+FP) | {:.3} | {:.3} | ≤ 0.05 |", m.false_alarm_rate, mr.false_alarm_rate);
    println!("| misdetection FN/(TP+FN) | {:.3} | {:.3} | ≤ 0.10 |", m.misdetection_rate, mr.misdetection_rate);
    println!("| F2 | {:.3} | {:.3} | |", m.f2, mr.f2);
    println!("| events flagged / events | {}/{} | {}/{} | all |", overall.events_flagged, overall.events, overall_rec.events_flagged, overall_rec.events);
    println!(
        "| clean flights: GPS epochs flagged | {:.2}% of {} epochs ({} flights) | {:.2}% | ≤ 0.2% |",
        overall.clean_pct(),
        overall.clean_epochs,
        overall.clean_flights,
        overall_rec.clean_pct()
    );
    println!("| median detection delay | {:.1} s | (a dated onset is no detection) | |", overall.median_delay);
    println!("\nThe specific checks and the tables below score the {first} verdict.");
    println!("\n{} flights, {} rows, {:.0} s ({:.2} M rows/s incl. simulation, {} threads)\n", results.len(), rows, secs, rows as f64 / secs / 1e6, a.threads);

    println!("### Specific checks ({} instances each, eval-split flights)\n", a.checks);
    println!("| check | criterion | passed | mean share flagged | median first flag | new run after end | mean flagged in 20 s after end |\n|---|---|---|---|---|---|---|");
    for (s, evs) in &check_rows {
        let n = evs.len().max(1) as f64;
        let mut d: Vec<f64> = evs.iter().filter(|e| e.detected()).map(|e| e.delay).collect();
        d.sort_by(|x, y| x.total_cmp(y));
        let med = d.get(d.len() / 2).map_or("never".to_string(), |x| format!("{x:.1} s"));
        println!(
            "| {} | {} | {}/{} | {:.1}% | {} | {}/{} | {:.1} s |",
            s.name,
            s.criterion,
            evs.iter().filter(|e| s.passes(e)).count(),
            evs.len(),
            100.0 * evs.iter().map(|e| e.share).sum::<f64>() / n,
            med,
            evs.iter().filter(|e| e.after_new_interval).count(),
            evs.len(),
            evs.iter().map(|e| e.after_flagged_s).sum::<f64>() / n
        );
    }
    println!("\n### IMU-rate invariance (GPS epochs flagged at IMU 50/100/200/400 Hz; pass: spread ≤ 0.2 points)\n");
    println!("| flight | 50 Hz | 100 Hz | 200 Hz | 400 Hz | spread | pass |\n|---|---|---|---|---|---|---|");
    for (d, p) in &imu_rows {
        let sp = battery::spread(p);
        let cells: Vec<String> = p.iter().map(|x| format!("{x:.2}%")).collect();
        println!("| {} | {} | {:.2} | {} |", d, cells.join(" | "), sp, if sp <= 0.2 { "yes" } else { "no" });
    }
    for t in &tables {
        println!("\n### By {}\n\n{HEAD}", t.name);
        for r in &t.rows {
            println!("{}", row_md(r));
        }
    }
    print_fp_sources(&results);
    if a.verbose {
        let mut by_fp: Vec<(usize, &FlightResult)> = results.iter().map(|r| (r.epochs.iter().filter(|e| e.status != 0 && e.label == 0.0).count(), r)).collect();
        by_fp.sort_by(|x, y| y.0.cmp(&x.0));
        println!("\n### Flights with the most false-positive epochs\n");
        for (n, r) in by_fp.iter().take(25) {
            println!("- {n} FP: {}", r.flight.describe());
        }
        println!("\n### Flights\n");
        for r in &results {
            let ev: Vec<String> = r.events.iter().map(|e| format!("{} {:.0}% d={:.1}", battery::kind_key(&e.fault), 100.0 * e.share, e.delay)).collect();
            println!("- {} → flagged {:.2}% [{}]", r.flight.describe(), r.flagged_pct(), ev.join(", "));
        }
    }
    Ok(())
}

/// Where the false-positive epochs lie: on clean flights, before a faulty
/// flight's first fault, within `AFTER_WINDOW` s after a fault ends, or
/// later. Says which mechanism the false-alarm rate is made of.
fn print_fp_sources(results: &[FlightResult]) {
    let mut n = [0u64; 4];
    // After-fault FPs by the kind of the last fault that ended before them.
    let mut by_kind: std::collections::BTreeMap<&'static str, [u64; 2]> = Default::default();
    let only_true = std::env::var("FP_TRUE_CLOCK").is_ok();
    // FPs in the first `EARLY_S` s of the log, where σ is still being learnt.
    const EARLY_S: f64 = 30.0;
    let mut early = 0u64;
    for r in results.iter().filter(|r| !only_true || r.flight.clock.rate == 1.0) {
        let f = &r.flight;
        let t0 = r.epochs.first().map_or(0.0, |e| e.t);
        for e in r.epochs.iter().filter(|e| e.status != 0 && e.label == 0.0) {
            early += u64::from(e.t - t0 < EARLY_S);
            let last = f.faults.iter().filter(|ft| e.t >= ft.end_log).max_by(|a, b| a.end_log.total_cmp(&b.end_log));
            let slot = if f.faults.is_empty() {
                0
            } else if f.faults.iter().all(|ft| e.t < ft.start_log) {
                1
            } else if last.is_some_and(|ft| e.t < ft.end_log + battery::AFTER_WINDOW * f.clock.rate) {
                2
            } else {
                3
            };
            n[slot] += 1;
            if let (Some(ft), 2 | 3) = (last, slot) {
                by_kind.entry(ft.kind.name()).or_default()[slot - 2] += 1;
            }
        }
    }
    let total = n.iter().sum::<u64>().max(1) as f64;
    println!("\n### False-positive epochs by where they lie\n\n| clean flights | before the first fault | ≤ {} s after a fault | later | total |\n|---|---|---|---|---|", battery::AFTER_WINDOW);
    let cell = |k: u64| format!("{k} ({:.0}%)", 100.0 * k as f64 / total);
    println!("| {} | {} | {} | {} | {} |", cell(n[0]), cell(n[1]), cell(n[2]), cell(n[3]), n.iter().sum::<u64>());
    println!("\nIn the first {EARLY_S} s of the log (any column): {}", cell(early));
    println!("\nAfter a fault, by the kind of the fault that ended last (≤ {} s / later): {}", battery::AFTER_WINDOW, by_kind.iter().map(|(k, v)| format!("{k} {}/{}", v[0], v[1])).collect::<Vec<_>>().join(", "));
}
