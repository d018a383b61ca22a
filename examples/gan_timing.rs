//! Wall-clock timing of the GAN detector at the default sizes
//! (`cargo run --release -p navguard-examples --example gan_timing`). Prints, asserts nothing.

use std::time::Instant;

use navguard::sim::Rng;
use navguard::tight::gan::{subsequences, train, GanConfig, GanScratch};

fn main() {
    let cfg = GanConfig::default();
    let mut rng = Rng::new(1);
    // AR(1) with φ = 0.9, standardised, embedded with m = dim, delay 1.
    let n = 400 + cfg.dim;
    let mut s = vec![0.0f64; n];
    for t in 1..n {
        s[t] = 0.9 * s[t - 1] + (1.0f64 - 0.81).sqrt() * rng.normal();
    }
    let rows: Vec<f64> = (0..400).flat_map(|t| s[t..t + cfg.dim].to_vec()).collect();
    let windows = subsequences(&rows, cfg.dim, cfg.window, cfg.step).expect("windows");

    let t0 = Instant::now();
    let mut model = train(&windows, &cfg, &mut |_| true).expect("train");
    let secs = t0.elapsed().as_secs_f64();
    println!(
        "train: {} windows × {} epochs in {secs:.2} s = {:.0} window-epochs/s (incl. fit statistics); {} parameters",
        windows.len(),
        cfg.epochs,
        (windows.len() * cfg.epochs) as f64 / secs,
        model.param_count()
    );
    let th = model.calibrate(&windows, 0.01).expect("calibrate");
    println!("T2 {:.3} (normal {:.3}, empirical {:.3})", th.t2, th.t2_normal, th.t2_empirical);

    let reps = 2000;
    let mut scratch = GanScratch::default();
    let t0 = Instant::now();
    let mut acc = 0.0;
    let mut z: Option<Vec<f64>> = None;
    for i in 0..reps {
        let y = &windows[i % windows.len()];
        let sc = model.score_with(y, z.as_deref(), &mut scratch).expect("score");
        acc += sc.score;
        z = Some(model.shift_latent(&sc.z, cfg.step).expect("shift"));
    }
    let per = t0.elapsed().as_secs_f64() / reps as f64;
    println!("score (z_iters {}, warm start, scratch reused): {:.1} µs per window (checksum {acc:.3})", cfg.z_iters, per * 1e6);
    let t0 = Instant::now();
    for i in 0..reps {
        acc += model.score(&windows[i % windows.len()], None).expect("score").score;
    }
    let per = t0.elapsed().as_secs_f64() / reps as f64;
    println!("score (cold start, fresh buffers): {:.1} µs per window (checksum {acc:.3})", per * 1e6);
}
