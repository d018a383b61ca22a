//! Reproduce Baek & Jo 2018's Table 1 and Table 2 on the simulated Jackal
//! UGV (`../shared/papers/baek2018_adaptive_threshold.txt`, see
//! `docs/baek-jo.md`).
//!
//! `navguard-baek [--reps N] [--seed S] [--json]`: Markdown to stdout (or
//! the full report as JSON with `--json`).

use navguard_examples::ugv::{evaluate, EvalConfig, Report};

fn pair(p: (f64, f64)) -> String {
    format!("({:.6}, {})", p.0, fmt_sigma(p.1))
}

fn fmt_sigma(s: f64) -> String {
    if s.fract() == 0.0 {
        format!("{s:.0}")
    } else {
        format!("{s}")
    }
}

fn rates(f: f64, p: f64) -> String {
    format!("({f:.3}, {p:.3})")
}

fn markdown(r: &Report) -> String {
    let mut o = String::new();
    let c = &r.config;
    o += &format!(
        "Baek & Jo 2018 reproduced on the simulated Jackal UGV: w = {}, psi = {}, {} repetitions, {} training and {} test samples per run, {} faults per run, durations {:?}, seed {}.\n\n",
        c.fit.w, c.fit.psi, c.reps, c.train_len, c.test_len, c.occurrences, c.durations, c.seed
    );
    o += "### Table 1: thresholds per speed (paper | ours)\n\n";
    o += "| Velocity | AT (ρ, σ) paper | AT (ρ, σ) ours | KT (ρ, σ) paper | KT (ρ, σ) ours | RT mean RMS paper | RT mean RMS ours | AT x* / x_m |\n";
    o += "|---|---|---|---|---|---|---|---|\n";
    for t in &r.table1 {
        o += &format!(
            "| {:.1} m/s | {} | {} | {} | {} | {:.6} | {:.6} | {:.2} / {:.0}{} |\n",
            t.speed,
            pair(t.paper_at),
            pair(t.at),
            pair(t.paper_kt),
            pair(t.kt),
            t.paper_rt,
            t.rt_mean_rms,
            t.at_x_star,
            t.at_x_m,
            if t.at_clamped { " (clamped)" } else { "" }
        );
    }
    o += "\n### Table 2: mean (FNR, FPR) per speed and fault type (paper | ours)\n\n";
    o += "FPR as the paper uses it: FP/(TP+FP). Conventional FP/(FP+TN) in the last column (AT, KT, RT).\n\n";
    o += "| Velocity | Type | AT paper | AT ours | KT paper | KT ours | RT paper | RT ours | ours FP/(FP+TN) AT, KT, RT |\n";
    o += "|---|---|---|---|---|---|---|---|---|\n";
    for t in &r.table2 {
        let p = t.paper.unwrap_or([(f64::NAN, f64::NAN); 3]);
        o += &format!(
            "| {:.1} m/s | {} | {} | {} | {} | {} | {} | {} | {:.3}, {:.3}, {:.3} |\n",
            t.speed,
            t.fault.name(),
            rates(p[0].0, p[0].1),
            rates(t.ours[0].fnr, t.ours[0].fpr),
            rates(p[1].0, p[1].1),
            rates(t.ours[1].fnr, t.ours[1].fpr),
            rates(p[2].0, p[2].1),
            rates(t.ours[2].fnr, t.ours[2].fpr),
            t.ours[0].fpr_conventional,
            t.ours[1].fpr_conventional,
            t.ours[2].fpr_conventional,
        );
    }
    let g = &r.ordering;
    // Paper means over its 12 cells.
    let mut pf = [0.0; 3];
    let mut pp = [0.0; 3];
    let n = navguard_examples::ugv::PAPER_TABLE2.len() as f64 * 3.0;
    for (_, rows) in navguard_examples::ugv::PAPER_TABLE2.iter() {
        for row in rows {
            for m in 0..3 {
                pf[m] += row[m].0 / n;
                pp[m] += row[m].1 / n;
            }
        }
    }
    o += "\n### Ordering AT ≤ KT ≤ RT\n\n";
    o += "| | AT | KT | RT | AT ≤ KT ≤ RT (means) | cells where it holds |\n|---|---|---|---|---|---|\n";
    o += &format!("| mean FNR, paper | {:.3} | {:.3} | {:.3} | {} | |\n", pf[0], pf[1], pf[2], yes(pf[0] <= pf[1] && pf[1] <= pf[2]));
    o += &format!(
        "| mean FNR, ours | {:.3} | {:.3} | {:.3} | {} | {}/{} |\n",
        g.mean_fnr[0], g.mean_fnr[1], g.mean_fnr[2], yes(g.fnr_means_ordered), g.fnr_cells, g.cells
    );
    o += &format!("| mean FPR, paper | {:.3} | {:.3} | {:.3} | {} | |\n", pp[0], pp[1], pp[2], yes(pp[0] <= pp[1] && pp[1] <= pp[2]));
    o += &format!(
        "| mean FPR, ours | {:.3} | {:.3} | {:.3} | {} | {}/{} |\n",
        g.mean_fpr[0], g.mean_fpr[1], g.mean_fpr[2], yes(g.fpr_means_ordered), g.fpr_cells, g.cells
    );
    o
}

fn yes(b: bool) -> &'static str {
    if b {
        "yes"
    } else {
        "**no**"
    }
}

fn main() {
    let mut cfg = EvalConfig::default();
    let mut json = false;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut num = |name: &str| -> u64 {
            match args.next().map(|v| v.parse::<u64>()) {
                Some(Ok(v)) => v,
                _ => {
                    eprintln!("navguard-baek: {name} needs a non-negative integer");
                    std::process::exit(2);
                }
            }
        };
        match a.as_str() {
            "--json" => json = true,
            "--reps" => cfg.reps = num("--reps") as usize,
            "--seed" => cfg.seed = num("--seed"),
            "-h" | "--help" => {
                println!("navguard-baek [--reps N] [--seed S] [--json]: Baek & Jo 2018 Table 1 and Table 2 on the simulated Jackal UGV");
                return;
            }
            other => {
                eprintln!("navguard-baek: unknown argument {other:?} (try --help)");
                std::process::exit(2);
            }
        }
    }
    match evaluate(&cfg) {
        Ok(r) if json => match serde_json::to_string_pretty(&r) {
            Ok(s) => println!("{s}"),
            Err(e) => {
                eprintln!("navguard-baek: {e}");
                std::process::exit(1);
            }
        },
        Ok(r) => print!("{}", markdown(&r)),
        Err(e) => {
            eprintln!("navguard-baek: {e}");
            std::process::exit(1);
        }
    }
}
