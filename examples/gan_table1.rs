//! Table 1 of Shen et al. 2022 on the simulated satellites, for both GAN
//! input series (the same analysis `navguard-gan train` prints):
//! `cargo run --release -p navguard-examples --example gan_table1`.
use navguard::tight::chaos::{analyze, table1_markdown, ChaosOptions};
use navguard::tight::gan_fdsr::GanInput;
use navguard::tight::gan_fdsr_train::input_series;
use navguard::tight::scenario::{environments, SimConfig, World};

fn main() -> Result<(), navguard::tight::TightError> {
    let sim = SimConfig::default();
    let world = World::new(&sim)?;
    let envs = environments(&world, &sim)?;
    let prns = &envs[0].prns;
    let opts = ChaosOptions { max_tau: 20, max_m: 9, ..ChaosOptions::default() };
    for input in [GanInput::IncrementDifference, GanInput::Innovation] {
        let mut rows = Vec::new();
        for (prn, r) in input_series(&world, &sim, prns, 101, 30.0, input)? {
            rows.push((format!("G{prn}"), analyze(&r, 1.0, &opts)?));
        }
        println!("{} series, seed 101, Env 1 satellites, 1 Hz:\n\n{}", input.name(), table1_markdown(&rows));
    }
    Ok(())
}
