//! Real-log summary for tuning: flagged share of GPS epochs and the fault
//! intervals (kind, driver, duration) per log under the given paths; with
//! `-r`, each log's causal and reconciled interval counts and the
//! reconciled intervals (start, end, s) instead.
//! `cargo run --release -p navguard-examples --example reallogs -- ../shared/data/*/* [-v] [-r]`
use navguard::{audit::audit, config::Config, logs::read_any};

fn main() {
    let verbose = std::env::args().any(|a| a == "-v");
    let reconciled = std::env::args().any(|a| a == "-r");
    for path in std::env::args().skip(1).filter(|a| a != "-v" && a != "-r") {
        let Ok(bytes) = std::fs::read(&path) else { continue };
        let Ok(log) = read_any(&bytes) else { continue };
        let Ok((rep, _)) = audit(&log, &Config::default()) else { continue };
        let name = path.rsplit('/').next().unwrap_or(&path);
        if reconciled {
            let ivs: Vec<String> = rep.reconciled.iter().map(|f| format!("({:.1}, {:.1}) {}", f.start, f.end, f.kind)).collect();
            println!("{name} {} {} [{}]", rep.faults.len(), rep.reconciled.len(), ivs.join(", "));
            continue;
        }
        let mut by: std::collections::BTreeMap<String, (usize, f64)> = Default::default();
        for f in &rep.faults {
            let e = by.entry(format!("{}/{}", f.kind, f.driver)).or_default();
            e.0 += 1;
            e.1 += f.end - f.start;
        }
        let parts: Vec<String> = by.iter().map(|(k, (n, d))| format!("{k} {n}x {d:.1}s")).collect();
        println!("{name:48} flagged {:6.2}%  {}", 100.0 * rep.flagged_gps_epoch_fraction, parts.join(", "));
        if verbose {
            for f in &rep.faults {
                println!("    {:8.2}-{:8.2} {:10} {:13} F {:.2}", f.start, f.end, f.kind, f.driver, f.peak_f);
            }
        }
    }
}
