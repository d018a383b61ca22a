//! Native run of the method comparison (the CLI's `navguard compare` runs the
//! same core in wasm): `cargo run --release -p navguard-examples --example compare -- [SEEDS] [LOG...]`.
use std::sync::OnceLock;
use std::time::Instant;

fn clock() -> f64 {
    static T0: OnceLock<Instant> = OnceLock::new();
    T0.get_or_init(Instant::now).elapsed().as_secs_f64()
}

fn main() -> Result<(), String> {
    let mut args = std::env::args().skip(1);
    let n: u64 = args.next().map_or(Ok(5), |s| s.parse().map_err(|e| format!("seeds: {e}")))?;
    let seeds: Vec<u64> = (1..=n).collect();
    let mut run = navguard::compare::CompareRun::new(&seeds, &[], Some(clock))?;
    for path in args {
        let bytes = std::fs::read(&path).map_err(|e| format!("{path}: {e}"))?;
        let name = path.rsplit('/').next().unwrap_or(&path).to_string();
        run.add_log(&name, navguard::logs::read_any(&bytes)?);
    }
    let c = run.finish()?;
    println!("{}", navguard::compare::markdown(&c));
    Ok(())
}
