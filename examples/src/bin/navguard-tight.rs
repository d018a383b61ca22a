//! navguard-tight: reproduces the tightly coupled GNSS/INS experiments of
//! Shen et al. 2022 (`../shared/papers/shen2022_gan_fdsr.txt`) without the
//! GAN: Table 3 environments (Figures 7–8), Table 4 fault types
//! (Figures 11–12), FDI naming the faulty satellite.
//!
//! Usage: `navguard-tight [--out DIR] [--seed N] [--runs N] [--eta X]`.
//! Tables are means over `--runs` Monte Carlo runs (seeds `seed..seed+runs`);
//! figures show the first run. Figures go to `--out` (default `docs/figures`).

use std::fmt::Write as _;
use std::process::ExitCode;

use navguard::tight::fdi::{FdsrConfig, Strategy};
use navguard::tight::scenario::{environments, run, run_case, CaseResult, FaultSpec, FaultType, RunSpec, SimConfig, World};

/// RDPOP threshold η. The paper uses 0.1 for its vehicle data; RDPOP scales
/// with how much the filter leans on one epoch of pseudo-ranges versus the
/// INS prediction, so η is set for this simulated UAV filter between the
/// good-geometry (Env 1, 3) and poor-geometry (Env 2, 4) values.
const DEFAULT_ETA: f64 = 0.035;
const LABELS: [&str; 4] = ["FF", "FDI", "FDA", "RDPOP-switch"];

fn main() -> ExitCode {
    match real_main() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("navguard-tight: {e}");
            ExitCode::FAILURE
        }
    }
}

fn real_main() -> Result<(), String> {
    let mut out_dir = "docs/figures".to_string();
    let mut seed = 1u64;
    let mut eta = DEFAULT_ETA;
    let mut n_runs = 5u64;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--out" => out_dir = args.next().ok_or("--out needs a directory")?,
            "--seed" => {
                let v = args.next().ok_or("--seed needs a number")?;
                seed = v.parse().map_err(|_| format!("--seed: not an integer: {v:?}"))?;
            }
            "--runs" => {
                let v = args.next().ok_or("--runs needs a number")?;
                n_runs = v.parse().map_err(|_| format!("--runs: not an integer: {v:?}"))?;
                if n_runs == 0 {
                    return Err("--runs: must be >= 1, got 0".into());
                }
            }
            "--eta" => {
                let v = args.next().ok_or("--eta needs a number")?;
                eta = v.parse().map_err(|_| format!("--eta: not a number: {v:?}"))?;
                if !(eta.is_finite() && eta >= 0.0) {
                    return Err(format!("--eta: must be finite and >= 0, got {eta}"));
                }
            }
            "-h" | "--help" => {
                println!("navguard-tight [--out DIR] [--seed N] [--runs N] [--eta X]");
                return Ok(());
            }
            other => return Err(format!("unknown argument {other:?}")),
        }
    }
    let cfg = SimConfig::default();
    let world = World::new(&cfg).map_err(|e| e.to_string())?;
    let envs = environments(&world, &cfg).map_err(|e| e.to_string())?;
    println!("# Tightly coupled GNSS/INS, Shen et al. 2022 without the GAN");
    println!(
        "constellation: {} satellites, 6 planes; site {:?}; start t0 = {} s; seeds {seed}..={}; T1 = {:.3} (alpha 0.001), eta = {eta}",
        cfg.n_sats,
        cfg.site,
        world.t0,
        seed + n_runs - 1,
        navguard::tight::fdi::threshold_t1(0.001).map_err(|e| e.to_string())?
    );
    println!();
    println!("## Environments (Table 3)");
    println!("| env | satellites | faulty | fault section (s) | PDOP | PDOP without faulty | description |");
    println!("|---|---|---|---|---|---|---|");
    for e in &envs {
        println!(
            "| {} | {} ({:?}) | G{} | {:.0}-{:.0} | {:.2} | {:.2} | {} |",
            e.name,
            e.prns.len(),
            e.prns,
            e.faulty_prn,
            e.fault_start,
            e.fault_end,
            e.pdop,
            e.pdop_without_faulty,
            e.description
        );
    }

    // Table 3 runs: 20 m step on the faulty satellite; Table 4 runs in Env 5.
    let e5 = envs.iter().find(|e| e.id == 5).ok_or("no Env 5")?;
    let mut t3: Vec<Vec<CaseResult>> = Vec::new();
    let mut t4: Vec<Vec<CaseResult>> = Vec::new();
    for e in envs.iter().filter(|e| e.id <= 4) {
        let mut v = Vec::new();
        for sd in seed..seed + n_runs {
            v.push(run_case(&world, &cfg, e, FaultType::Step20, eta, sd, &e.name).map_err(|e| e.to_string())?);
        }
        t3.push(v);
    }
    for k in FaultType::ALL {
        let mut v = Vec::new();
        for sd in seed..seed + n_runs {
            v.push(run_case(&world, &cfg, e5, k, eta, sd, k.name()).map_err(|e| e.to_string())?);
        }
        t4.push(v);
    }
    println!();
    println!("## Figures 7 and 8: 20 m step, positioning error during the fault section (m), mean of {n_runs} runs");
    print_cases(&t3);
    println!();
    println!("## Figure 11: fault types of Table 4 on G{} in {} (m), mean of {n_runs} runs", e5.faulty_prn, e5.name);
    print_cases(&t4);
    println!();
    println!("## Figure 12: mean positioning error relative to fault-free during 300-360 s (m), mean of {n_runs} runs");
    println!("| fault | FDI | FDA | RDPOP-switch |");
    println!("|---|---|---|---|");
    let mut bars = Vec::new();
    for (k, runs) in t4.iter().enumerate() {
        let mut line = format!("| {} |", runs[0].label);
        let mut v = Vec::new();
        for l in &LABELS[1..] {
            let mut acc = 0.0;
            for c in runs {
                let ff = c.record("FF").ok_or("no FF run")?;
                let r = c.record(l).ok_or("missing run")?;
                acc += rel_error(ff, r, c.fault.start, c.fault.end);
            }
            let d = acc / runs.len() as f64;
            let _ = write!(line, " {d:.2} |");
            v.push(d);
        }
        println!("{line}");
        bars.push((format!("Type {}", k + 1), v));
    }
    // Table 5 analogue: FDI detection delay and missed-alarm rate per fault
    // type, in good geometry (Env 1 satellites) and in Env 5.
    println!();
    println!("## Table 5 analogue: FDI detection delay (s, per run) and missed-alarm rate in 300-360 s, {n_runs} runs");
    println!("| fault | Env 1 satellites (G{}) delay | Env 1 missed | {} (G{}) delay | {} missed |", envs[0].faulty_prn, e5.name, e5.faulty_prn, e5.name);
    println!("|---|---|---|---|---|");
    let mut e1b = envs[0].clone();
    e1b.fault_start = 300.0;
    e1b.fault_end = 360.0;
    for k in FaultType::ALL {
        let mut line = format!("| {} |", k.name());
        for e in [&e1b, e5] {
            let fault = FaultSpec { prn: e.faulty_prn, kind: k, start: e.fault_start, end: e.fault_end };
            let mut delays = Vec::new();
            let mut missed = 0.0;
            for sd in seed..seed + n_runs {
                let spec = RunSpec {
                    world: &world,
                    cfg: &cfg,
                    prns: &e.prns,
                    watch_prn: e.faulty_prn,
                    fault: Some(fault),
                    fdsr: FdsrConfig { strategy: Strategy::Fdi, alpha: 0.001, eta },
                    seed: sd,
                    gan: None,
                };
                let r = run(&spec).map_err(|e| e.to_string())?;
                delays.push(r.detection_delay(e.faulty_prn, fault.start, fault.end).map_or("-".to_string(), |d| format!("{d:.0}")));
                missed += 1.0 - r.flag_rate(e.faulty_prn, fault.start, fault.end);
            }
            let _ = write!(line, " {} | {:.0}% |", delays.join(","), 100.0 * missed / n_runs as f64);
        }
        println!("{line}");
    }
    let t3: Vec<CaseResult> = t3.into_iter().filter_map(|v| v.into_iter().next()).collect();
    let t4: Vec<CaseResult> = t4.into_iter().filter_map(|v| v.into_iter().next()).collect();

    // Figures.
    std::fs::create_dir_all(&out_dir).map_err(|e| format!("{out_dir}: {e}"))?;
    let fig8: Vec<Panel> = t3.iter().map(|c| panel(c, c.fault.start - 20.0, c.fault.end + 30.0, &format!("{}: {} satellites, G{} +20 m", c.label, c.env.prns.len(), c.fault.prn))).collect();
    write_svg(&out_dir, "tight_fig8_env_errors.svg", "Figure 8: positioning error, 20 m step (FI = FDI, FA = FDA)", &fig8)?;
    let fig11: Vec<Panel> = t4.iter().map(|c| panel(c, 280.0, 400.0, &format!("{} on G{}", c.label, c.fault.prn))).collect();
    write_svg(&out_dir, "tight_fig11_fault_types.svg", &format!("Figure 11: positioning error per fault type ({})", e5.name), &fig11)?;
    let fig7: Vec<Panel> = vec![Panel {
        title: format!("RDPOP of the faulty satellite (fault-free run), eta = {eta}"),
        x_label: "time (s)".into(),
        y_label: "RDPOP".into(),
        series: t3
            .iter()
            .filter_map(|c| {
                let r = c.record("FF")?;
                Some((format!("{} (G{})", c.label, c.fault.prn), r.t.iter().zip(&r.rdpop_faulty).filter(|(t, v)| **t >= 20.0 && v.is_finite()).map(|(t, v)| (*t, *v)).collect()))
            })
            .collect(),
        hline: Some(eta),
        shade: None,
    }];
    write_svg(&out_dir, "tight_fig7_rdpop.svg", "Figure 7: RDPOP per environment", &fig7)?;
    write_bars(&out_dir, "tight_fig12_relative_error.svg", &format!("Figure 12: mean positioning error relative to fault-free, 300-360 s (m), {n_runs} runs"), &LABELS[1..], &bars)?;
    println!();
    println!("figures written to {out_dir}/tight_fig{{7,8,11,12}}_*.svg");
    Ok(())
}

const COLORS: [&str; 4] = ["#222222", "#d62728", "#1f77b4", "#2ca02c"];

struct Panel {
    title: String,
    x_label: String,
    y_label: String,
    series: Vec<(String, Vec<(f64, f64)>)>,
    hline: Option<f64>,
    /// Shaded x interval (the fault section).
    shade: Option<(f64, f64)>,
}

fn panel(c: &CaseResult, a: f64, b: f64, title: &str) -> Panel {
    let names = ["FF", "FDI (FI)", "FDA (FA)", "RDPOP switch"];
    Panel {
        title: title.to_string(),
        x_label: "time (s)".into(),
        y_label: "position error (m)".into(),
        series: LABELS
            .iter()
            .zip(names)
            .filter_map(|(l, n)| {
                let r = c.record(l)?;
                Some((n.to_string(), r.t.iter().zip(&r.pos_err).filter(|(t, _)| **t >= a && **t <= b).map(|(t, e)| (*t, *e)).collect()))
            })
            .collect(),
        hline: None,
        shade: Some((c.fault.start, c.fault.end)),
    }
}

/// A "nice" tick step for a range.
fn tick_step(span: f64) -> f64 {
    let raw = span / 5.0;
    let mag = 10f64.powf(raw.log10().floor());
    let f = raw / mag;
    mag * if f < 1.5 { 1.0 } else if f < 3.5 { 2.0 } else if f < 7.5 { 5.0 } else { 10.0 }
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

/// Hand-written SVG: panels stacked in a grid of two columns.
fn write_svg(dir: &str, name: &str, title: &str, panels: &[Panel]) -> Result<(), String> {
    let (pw, ph) = (460.0, 260.0);
    let cols = if panels.len() > 1 { 2 } else { 1 };
    let rows = panels.len().div_ceil(cols);
    let (w, h) = (pw * cols as f64 + 20.0, ph * rows as f64 + 40.0);
    let mut s = String::new();
    let _ = writeln!(s, r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="sans-serif" font-size="11">"#);
    let _ = writeln!(s, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let _ = writeln!(s, r#"<text x="{}" y="22" text-anchor="middle" font-size="14">{}</text>"#, w / 2.0, esc(title));
    for (k, p) in panels.iter().enumerate() {
        let (ox, oy) = (10.0 + pw * (k % cols) as f64, 36.0 + ph * (k / cols) as f64);
        let (l, r, t, b) = (ox + 55.0, ox + pw - 15.0, oy + 22.0, oy + ph - 40.0);
        let pts = p.series.iter().flat_map(|(_, v)| v.iter());
        let (mut x0, mut x1, mut y1) = (f64::INFINITY, f64::NEG_INFINITY, 0.0f64);
        for &(x, y) in pts {
            x0 = x0.min(x);
            x1 = x1.max(x);
            y1 = y1.max(y);
        }
        if let Some(hl) = p.hline {
            y1 = y1.max(hl * 1.1);
        }
        if !(x1 > x0) {
            continue;
        }
        let ys = tick_step(y1.max(1e-9));
        let y1 = (y1 / ys).ceil() * ys;
        let sx = |x: f64| l + (x - x0) / (x1 - x0) * (r - l);
        let sy = |y: f64| b - y / y1 * (b - t);
        let _ = writeln!(s, r#"<text x="{}" y="{}" text-anchor="middle" font-size="12">{}</text>"#, (l + r) / 2.0, oy + 14.0, esc(&p.title));
        let _ = writeln!(s, r##"<rect x="{l}" y="{t}" width="{}" height="{}" fill="none" stroke="#888"/>"##, r - l, b - t);
        let mut y = 0.0;
        while y <= y1 + 1e-9 {
            let _ = writeln!(s, r##"<line x1="{l}" y1="{0:.1}" x2="{r}" y2="{0:.1}" stroke="#ddd"/><text x="{1}" y="{2:.1}" text-anchor="end">{3}</text>"##, sy(y), l - 4.0, sy(y) + 4.0, fmt_tick(y, ys));
            y += ys;
        }
        let xs = tick_step(x1 - x0);
        let mut x = (x0 / xs).ceil() * xs;
        while x <= x1 + 1e-9 {
            let _ = writeln!(s, r##"<line x1="{0:.1}" y1="{b}" x2="{0:.1}" y2="{1}" stroke="#888"/><text x="{0:.1}" y="{2}" text-anchor="middle">{3}</text>"##, sx(x), b + 4.0, b + 16.0, fmt_tick(x, xs));
            x += xs;
        }
        let _ = writeln!(s, r#"<text x="{}" y="{}" text-anchor="middle">{}</text>"#, (l + r) / 2.0, b + 30.0, esc(&p.x_label));
        let _ = writeln!(s, r#"<text x="{0}" y="{1}" text-anchor="middle" transform="rotate(-90 {0} {1})">{2}</text>"#, ox + 14.0, (t + b) / 2.0, esc(&p.y_label));
        if let Some((a, b2)) = p.shade {
            let (xa, xb) = (sx(a.max(x0)), sx(b2.min(x1)));
            let _ = writeln!(s, r##"<rect x="{xa:.1}" y="{t}" width="{:.1}" height="{}" fill="#f3e0e0"/>"##, (xb - xa).max(0.0), b - t);
        }
        if let Some(hl) = p.hline {
            let _ = writeln!(s, r##"<line x1="{l}" y1="{0:.1}" x2="{r}" y2="{0:.1}" stroke="#999" stroke-dasharray="4 3"/>"##, sy(hl));
        }
        for (i, (name, v)) in p.series.iter().enumerate() {
            let c = COLORS[i % COLORS.len()];
            let pts: Vec<String> = v.iter().map(|&(x, y)| format!("{:.1},{:.1}", sx(x), sy(y.min(y1)))).collect();
            let _ = writeln!(s, r#"<polyline fill="none" stroke="{c}" stroke-width="1.4" points="{}"/>"#, pts.join(" "));
            let _ = writeln!(s, r#"<line x1="{0}" y1="{1}" x2="{2}" y2="{1}" stroke="{c}" stroke-width="2"/><text x="{3}" y="{4}">{5}</text>"#, l + 8.0, t + 12.0 + 13.0 * i as f64, l + 24.0, l + 28.0, t + 16.0 + 13.0 * i as f64, esc(name));
        }
    }
    s.push_str("</svg>\n");
    let path = format!("{dir}/{name}");
    std::fs::write(&path, s).map_err(|e| format!("{path}: {e}"))
}

fn fmt_tick(v: f64, step: f64) -> String {
    if step >= 1.0 {
        format!("{v:.0}")
    } else if step >= 0.1 {
        format!("{v:.1}")
    } else {
        format!("{v:.2}")
    }
}

/// Grouped bar chart.
fn write_bars(dir: &str, name: &str, title: &str, series: &[&str], groups: &[(String, Vec<f64>)]) -> Result<(), String> {
    let (w, h) = (640.0, 340.0);
    let (l, r, t, b) = (60.0, w - 20.0, 50.0, h - 40.0);
    let y1 = groups.iter().flat_map(|(_, v)| v.iter()).fold(1e-9f64, |m, &x| m.max(x));
    let y0 = groups.iter().flat_map(|(_, v)| v.iter()).fold(0.0f64, |m, &x| m.min(x));
    let ys = tick_step(y1 - y0);
    let (y0, y1) = ((y0 / ys).floor() * ys, (y1 / ys).ceil() * ys);
    let sy = |y: f64| b - (y - y0) / (y1 - y0) * (b - t);
    let mut s = String::new();
    let _ = writeln!(s, r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="sans-serif" font-size="11">"#);
    let _ = writeln!(s, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let _ = writeln!(s, r#"<text x="{}" y="22" text-anchor="middle" font-size="13">{}</text>"#, w / 2.0, esc(title));
    let mut y = y0;
    while y <= y1 + 1e-9 {
        let _ = writeln!(s, r##"<line x1="{l}" y1="{0:.1}" x2="{r}" y2="{0:.1}" stroke="#ddd"/><text x="{1}" y="{2:.1}" text-anchor="end">{3}</text>"##, sy(y), l - 4.0, sy(y) + 4.0, fmt_tick(y, ys));
        y += ys;
    }
    let gw = (r - l) / groups.len().max(1) as f64;
    let bw = gw * 0.8 / series.len().max(1) as f64;
    for (g, (label, vals)) in groups.iter().enumerate() {
        let gx = l + gw * g as f64 + gw * 0.1;
        for (i, v) in vals.iter().enumerate() {
            let (ya, yb) = (sy(v.max(0.0)), sy(v.min(0.0)));
            let _ = writeln!(s, r#"<rect x="{:.1}" y="{ya:.1}" width="{:.1}" height="{:.1}" fill="{}"/>"#, gx + bw * i as f64, bw - 2.0, (yb - ya).max(0.5), COLORS[(i + 1) % COLORS.len()]);
        }
        let _ = writeln!(s, r#"<text x="{:.1}" y="{}" text-anchor="middle">{}</text>"#, gx + gw * 0.4, b + 16.0, esc(label));
    }
    for (i, n) in series.iter().enumerate() {
        let _ = writeln!(s, r#"<rect x="{}" y="{}" width="12" height="10" fill="{}"/><text x="{}" y="{}">{}</text>"#, l + 10.0 + 120.0 * i as f64, 32.0, COLORS[(i + 1) % COLORS.len()], l + 26.0 + 120.0 * i as f64, 41.0, esc(n));
    }
    let _ = writeln!(s, r##"<line x1="{l}" y1="{0:.1}" x2="{r}" y2="{0:.1}" stroke="#444"/>"##, sy(0.0));
    s.push_str("</svg>\n");
    let path = format!("{dir}/{name}");
    std::fs::write(&path, s).map_err(|e| format!("{path}: {e}"))
}

fn rel_error(ff: &navguard::tight::scenario::RunRecord, r: &navguard::tight::scenario::RunRecord, a: f64, b: f64) -> f64 {
    let d: Vec<f64> = r.pos_err.iter().zip(&ff.pos_err).map(|(x, y)| x - y).collect();
    r.mean_of(&d, a, b)
}

fn print_cases(cases: &[Vec<CaseResult>]) {
    println!("| case | faulty | RDPOP | FF rms/max | FDI (FI) rms/max | FDA (FA) rms/max | switch rms/max | FDI flags the faulty satellite at onset | FDI flag rate in section | flags naming another satellite |");
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for runs in cases {
        let Some(c0) = runs.first() else { continue };
        let n = runs.len() as f64;
        let (a, b) = (c0.fault.start, c0.fault.end);
        let mut line = format!("| {} | G{} |", c0.label, c0.fault.prn);
        let rd = runs.iter().filter_map(|c| c.record("FF")).map(|r| r.mean_of(&r.rdpop_faulty, a, b)).sum::<f64>() / n;
        let _ = write!(line, " {rd:.3} |");
        for l in LABELS {
            let recs: Vec<_> = runs.iter().filter_map(|c| c.record(l)).collect();
            let rms = recs.iter().map(|r| r.rms(a, b)).sum::<f64>() / n;
            let max = recs.iter().map(|r| r.max(a, b)).sum::<f64>() / n;
            let _ = write!(line, " {rms:.2}/{max:.2} |");
        }
        let fdi: Vec<_> = runs.iter().filter_map(|c| c.record("FDI")).collect();
        let at_once = fdi.iter().filter(|r| r.detection_delay(c0.fault.prn, a, b) == Some(0.0)).count();
        let delays: Vec<String> = fdi.iter().map(|r| r.detection_delay(c0.fault.prn, a, b).map_or("-".to_string(), |d| format!("{d:.0}"))).collect();
        let rate = fdi.iter().map(|r| r.flag_rate(c0.fault.prn, a, b)).sum::<f64>() / n;
        let wrong: usize = fdi.iter().map(|r| r.wrong_flags(c0.fault.prn, a, b)).sum();
        let _ = write!(line, " {at_once}/{} (delays s: {}) | {rate:.2} | {wrong} |", fdi.len(), delays.join(","));
        println!("{line}");
    }
}
