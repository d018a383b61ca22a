//! Training of the GAN-FDSR detector (Shen et al. 2022 §3.1–3.2) on
//! fault-free simulated flights: chaos analysis picks τ and m, the GRU GAN
//! learns the standardised windows, T2 is set on held-out flights. Kept apart
//! from the runtime monitor ([`super::gan_fdsr`]) because it needs the
//! simulator ([`super::scenario`]); the monitor only needs a model.

use std::collections::BTreeMap;

use super::chaos::{analyze, embed, ChaosIndices, ChaosOptions};
use super::fdi::{FdsrConfig, Strategy};
use super::gan::{subsequences, train as train_gan, GanConfig, Threshold, TrainProgress};
use super::gan_fdsr::{GanDetectorModel, GanInput};
use super::scenario::{run, RunSpec, SimConfig, World};
use super::TightError;

/// Training settings for [`train_detector`].
#[derive(Clone, Debug)]
pub struct GanTrainOptions {
    /// Seeds of the fault-free flights the GAN learns from.
    pub train_seeds: Vec<u64>,
    /// Seeds of other fault-free flights that set T2.
    pub calib_seeds: Vec<u64>,
    /// GAN architecture and training settings.
    pub gan: GanConfig,
    /// Which series the GAN learns.
    pub input: GanInput,
    /// See [`GanDetectorModel::lambda_test`].
    pub lambda_test: bool,
    /// False-alarm rate α of the detector (T2 alone, or T2 and T1 together).
    pub alpha: f64,
    /// Filter settling time left out of every series, s.
    pub skip_s: f64,
    /// Largest delay and embedding dimension searched.
    pub max_tau: usize,
    /// Largest embedding dimension searched.
    pub max_m: usize,
}

impl Default for GanTrainOptions {
    fn default() -> Self {
        GanTrainOptions {
            train_seeds: (101..=106).collect(),
            calib_seeds: (201..=206).collect(),
            // 20 epochs: the losses settle by then (D(real) ≈ D(fake) ≈ 0.5);
            // 10 warm-started latent steps per epoch and satellite keep
            // inference at a few ms per GNSS epoch.
            gan: GanConfig { epochs: 20, z_iters: 10, ..GanConfig::default() },
            input: GanInput::Innovation,
            lambda_test: true,
            alpha: 0.001,
            skip_s: 30.0,
            max_tau: 20,
            max_m: 9,
        }
    }
}

/// What training found and did.
#[derive(Clone, Debug)]
pub struct GanTrainReport {
    /// Chaos indices of every satellite of the first training flight (Table 1).
    pub chaos: Vec<(String, ChaosIndices)>,
    /// Delay τ chosen (median over satellites).
    pub tau: usize,
    /// Embedding dimension m chosen (median over satellites).
    pub m: usize,
    /// Training windows.
    pub train_windows: usize,
    /// Windows of the held-out flights that set T2.
    pub calib_windows: usize,
    /// The threshold T2 and how it was set.
    pub threshold: Threshold,
}

/// The input series (ρD in m, or λ) of every tracked satellite of a
/// fault-free flight with no detection, after `skip_s` seconds of settling.
pub fn input_series(world: &World, sim: &SimConfig, prns: &[u8], seed: u64, skip_s: f64, input: GanInput) -> Result<Vec<(u8, Vec<f64>)>, TightError> {
    let spec = RunSpec {
        world,
        cfg: sim,
        prns,
        watch_prn: prns.first().copied().unwrap_or(0),
        fault: None,
        fdsr: FdsrConfig { strategy: Strategy::None, alpha: 0.001, eta: 0.1 },
        seed,
        gan: None,
    };
    let rec = run(&spec)?;
    let mut series: BTreeMap<u8, (Vec<f64>, Option<f64>)> = BTreeMap::new();
    for (k, ep) in rec.ranges.iter().enumerate() {
        let t = rec.t.get(k).copied().unwrap_or(0.0);
        let seen: Vec<u8> = ep.iter().map(|x| x.0).collect();
        for s in series.iter_mut().filter(|(p, _)| !seen.contains(p)) {
            s.1 .1 = None;
        }
        let lams = rec.lambdas.get(k);
        for (j, &(prn, g, i)) in ep.iter().enumerate() {
            let e = series.entry(prn).or_insert((Vec::new(), None));
            let v = g - i;
            if let Some(lv) = e.1 {
                if t >= skip_s {
                    let x = match input {
                        GanInput::IncrementDifference => v - lv,
                        GanInput::Innovation => lams.and_then(|l| l.get(j)).copied().unwrap_or(f64::NAN),
                    };
                    if x.is_finite() {
                        e.0.push(x);
                    }
                }
            }
            e.1 = Some(v);
        }
    }
    Ok(series.into_iter().map(|(p, (s, _))| (p, s)).collect())
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

/// Train the GAN-FDSR detector on fault-free simulated flights over `prns`:
/// chaos analysis picks τ (mutual information) and m (Cao) as the medians
/// over the satellites, ρD is standardised, embedded and windowed, the GAN is
/// trained and T2 set on held-out flights at false-alarm rate α.
pub fn train_detector(
    world: &World,
    sim: &SimConfig,
    prns: &[u8],
    opts: &GanTrainOptions,
    progress: &mut dyn FnMut(&TrainProgress) -> bool,
) -> Result<(GanDetectorModel, GanTrainReport), TightError> {
    if opts.train_seeds.is_empty() || opts.calib_seeds.is_empty() {
        return Err(TightError::new("seeds", "need at least one training and one calibration seed"));
    }
    let mut train = Vec::new();
    for &s in &opts.train_seeds {
        train.extend(input_series(world, sim, prns, s, opts.skip_s, opts.input)?);
    }
    let mut calib = Vec::new();
    for &s in &opts.calib_seeds {
        calib.extend(input_series(world, sim, prns, s, opts.skip_s, opts.input)?);
    }
    // Chaos indices on the first flight's satellites (Table 1).
    let dt = 1.0 / sim.gnss_rate;
    let mut chaos = Vec::new();
    let n_first = input_series(world, sim, prns, opts.train_seeds[0], opts.skip_s, opts.input)?.len();
    for (prn, r) in train.iter().take(n_first) {
        let c = analyze(r, dt, &ChaosOptions { max_tau: opts.max_tau, max_m: opts.max_m, ..ChaosOptions::default() })?;
        chaos.push((format!("G{prn}"), c));
    }
    let mut taus: Vec<f64> = chaos.iter().map(|c| c.1.tau as f64).collect();
    let mut ms: Vec<f64> = chaos.iter().map(|c| c.1.m as f64).collect();
    let tau = (libm::round(median(&mut taus)) as usize).clamp(1, opts.max_tau);
    let m = (libm::round(median(&mut ms)) as usize).clamp(2, opts.max_m);

    let all: Vec<f64> = train.iter().flat_map(|s| s.1.iter().copied()).collect();
    let n = all.len() as f64;
    let mean = all.iter().sum::<f64>() / n;
    let scale = libm::sqrt(all.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1.0).max(1.0));
    let mut cfg = opts.gan.clone();
    cfg.dim = m;
    cfg.check()?;
    let windows = |set: &[(u8, Vec<f64>)], step: usize| -> Result<Vec<Vec<f64>>, TightError> {
        let mut out = Vec::new();
        for (_, r) in set {
            let z: Vec<f64> = r.iter().map(|x| (x - mean) / scale).collect();
            if z.len() < cfg.window + (m - 1) * tau {
                continue;
            }
            let ps = embed(&z, m, tau)?;
            out.extend(subsequences(&ps.data, m, cfg.window, step)?);
        }
        Ok(out)
    };
    let train_w = windows(&train, cfg.step)?;
    let calib_w = windows(&calib, 1)?;
    let mut gan = train_gan(&train_w, &cfg, progress)?;
    let threshold = gan.calibrate(&calib_w, if opts.lambda_test { opts.alpha / 2.0 } else { opts.alpha })?;
    // Generation error of the newest element (what eq. 12 accumulates).
    let mut se = 0.0;
    let mut k = 0usize;
    for y in calib_w.iter().step_by((calib_w.len() / 400).max(1)) {
        let s = gan.score(y, None)?;
        if let (Some(a), Some(b)) = (y.last(), s.generated.last()) {
            se += (a - b) * (a - b);
            k += 1;
        }
    }
    let gen_rms = libm::sqrt(se / (k.max(1) as f64));
    let provenance = format!(
        "navguard-gan train ({} input, lambda test {}): {} fault-free flights (seeds {:?}) over satellites {:?}, T2 from seeds {:?}; tau {tau}, m {m}; {:?}",
        opts.input.name(),
        opts.lambda_test,
        opts.train_seeds.len(),
        opts.train_seeds,
        prns,
        opts.calib_seeds,
        cfg
    );
    let model = GanDetectorModel { input: opts.input, lambda_test: opts.lambda_test, tau, m, mean, scale, gen_rms, gan, provenance };
    model.check()?;
    let report = GanTrainReport { chaos, tau, m, train_windows: train_w.len(), calib_windows: calib_w.len(), threshold };
    Ok((model, report))
}

