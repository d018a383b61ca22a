//! Everything fitted offline, kept out of the detector's path: the ANFIS
//! model trainer ([`train_model`], run by `navguard-train`), the Baek & Jo
//! threshold pools ([`fit_pools`], shipped as `detector/src/default_pools.bin`) and
//! the Mahalanobis threshold ([`calibrate_mahalanobis`], shipped as
//! [`MAHA_D2`]). Each runs the detector over simulated or labelled flights,
//! so this module sits above [`crate::detector`] and [`crate::sim`]; the
//! detector only reads what it produced.

use nalgebra::Vector3;

use crate::anfis::{inputs, Anfis};
use crate::config::Config;
use crate::detector::{kind, Detector};
use crate::methods::{Method, PoolState, MAHA_D2, N_ALPHA_HALF};
use crate::model::{has_signature, Model};
use crate::rng::Rng;
use crate::sample::Sample;
use crate::sim::{simulate, Scenario, Trajectory};
use crate::thresholds::{AdaptiveConfig, Evaluator, Method as ThMethod, SpeedBands, ThresholdPool};

/// Train a model from labelled streams: run the detector with decisions
/// forced to the labels (so the filter gates as it would on a correct
/// verdict), collect `(R, C)` at labelled GPS epochs, clean, subsample
/// `q` per class with a seeded RNG, and fit the ANFIS by hybrid learning.
///
/// Cleaning: fault epochs whose indicators never left the clean region
/// (`R < 3` and `C < 0.7`, e.g. the first seconds of a slow ramp) are
/// dropped from D2: they carry no fault signature and would only teach the
/// model to alarm on clean data.
pub fn train_model(streams: &[&[Sample]], cfg: &Config, seed: u64) -> Result<Model, String> {
    let mut ex = Examples::default();
    for rows in streams {
        ex.add(rows, cfg)?;
    }
    ex.fit(cfg, seed)
}

/// The `(R, C)` examples of [`train_model`], gathered stream by stream, so
/// a battery of hundreds of flights need not be held in memory at once.
#[derive(Default)]
pub struct Examples {
    normal: Vec<[f64; 2]>,
    fault: Vec<[f64; 2]>,
    streams: usize,
}

impl Examples {
    /// Run one labelled stream with decisions forced to its labels and
    /// keep its labelled GPS epochs' inputs (fault epochs only with a fault
    /// signature, see [`train_model`]).
    pub fn add(&mut self, rows: &[Sample], cfg: &Config) -> Result<(), String> {
        let mut det = Detector::with_model(cfg.clone(), &Model::untrained());
        det.set_oracle(true);
        for (i, s) in rows.iter().enumerate() {
            let o = det.push(s).map_err(|e| format!("training stream, {e} (index {i})"))?;
            if !o.gps_epoch || s.label.is_nan() || o.kind == kind::NO_GPS {
                continue;
            }
            let x = inputs(o.r, o.c);
            if s.label >= 0.5 {
                if has_signature(o.r, o.c) {
                    self.fault.push(x);
                }
            } else {
                self.normal.push(x);
            }
        }
        self.streams += 1;
        Ok(())
    }

    /// Subsample `q` per class with a seeded RNG and fit the ANFIS.
    pub fn fit(self, cfg: &Config, seed: u64) -> Result<Model, String> {
        let Examples { mut normal, mut fault, streams } = self;
        if normal.len() < 10 || fault.len() < 10 {
            return Err(format!(
                "training needs at least 10 labelled normal and 10 fault GPS epochs with a fault signature; got {} and {}",
                normal.len(),
                fault.len()
            ));
        }
        let mut rng = Rng::new(seed);
        let pick = |v: &mut Vec<[f64; 2]>, n: usize, rng: &mut Rng| -> Vec<[f64; 2]> {
            // Partial Fisher–Yates: a seeded uniform subsample.
            let n = n.min(v.len());
            for i in 0..n {
                let j = i + (rng.next_u64() % (v.len() - i) as u64) as usize;
                v.swap(i, j);
            }
            v[..n].to_vec()
        };
        let d1 = pick(&mut normal, cfg.q, &mut rng);
        let d2 = pick(&mut fault, cfg.q, &mut rng);
        let mut xs = d1.clone();
        xs.extend_from_slice(&d2);
        let ys: Vec<f64> = d1.iter().map(|_| 0.0).chain(d2.iter().map(|_| 1.0)).collect();
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for x in &xs {
            for k in 0..2 {
                lo[k] = lo[k].min(x[k]);
                hi[k] = hi[k].max(x[k]);
            }
        }
        let mut anfis = Anfis::init_grid(lo, hi);
        let mse = anfis.train_hybrid(&xs, &ys, 200, 0.05);
        Ok(Model {
            anfis,
            d1,
            d2,
            provenance: format!(
                "navguard-train: {} streams, {} normal / {} fault epochs before subsampling, q={}, window={}, seed={}, training MSE {:.4}",
                streams,
                normal.len(),
                fault.len(),
                cfg.q,
                cfg.window,
                seed,
                mse
            ),
        })
    }
}


/// Run `method` over clean simulated flights (aggressive, survey and paper
/// trajectories, 300 s, seeds `seeds`) with verdicts forced normal, calling
/// `each(detector, score)` at every GPS epoch with a positive score.
fn clean_epochs(seeds: core::ops::Range<u64>, method: Method, mut each: impl FnMut(&Detector, f64)) -> Result<(), String> {
    for seed in seeds {
        for tr in [Trajectory::Aggressive, Trajectory::Survey, Trajectory::Paper] {
            let rows = simulate(&Scenario::clean(tr, seed, 300.0))?;
            let mut det = Detector::new(Config { method, ..Config::default() })?;
            det.set_oracle(true);
            for s in &rows {
                let o = det.push(s).map_err(|e| e.to_string())?;
                if o.gps_epoch && o.f > 0.0 {
                    each(&det, o.f);
                }
            }
        }
    }
    Ok(())
}

/// Collect (speed, largest γ) at every GPS epoch of clean flights, with the
/// verdicts forced normal, and fit RT, KT and AT pools over speed quartiles.
pub fn fit_pools(seeds: core::ops::Range<u64>) -> Result<[PoolState; 3], String> {
    let mut data: Vec<(f64, f64)> = vec![];
    clean_epochs(seeds, Method::Chi2, |det, f| {
        let v = det.velocity().unwrap_or_else(Vector3::zeros);
        data.push((v[0].hypot(v[1]), f * N_ALPHA_HALF));
    })?;
    let mut speeds: Vec<f64> = data.iter().map(|d| d.0).collect();
    speeds.sort_by(f64::total_cmp);
    let q = |p: f64| speeds[((speeds.len() as f64 * p) as usize).min(speeds.len().saturating_sub(1))];
    let mut edges = vec![q(0.25), q(0.5), q(0.75)];
    edges.dedup_by(|a, b| *a <= *b + 1e-6);
    let bands = SpeedBands::new(edges)?;
    let mut per: Vec<Vec<f64>> = vec![vec![]; bands.modes()];
    for (v, g) in &data {
        per[bands.mode_of(*v)?].push(*g);
    }
    let per_ref: Vec<&[f64]> = per.iter().map(|v| v.as_slice()).collect();
    let cfg = AdaptiveConfig::default();
    let fit = |m: ThMethod| -> Result<PoolState, String> {
        let pool = ThresholdPool::fit(m, &per_ref, &cfg)?;
        Ok(PoolState { bands: bands.clone(), eval: Evaluator::new(pool)? })
    };
    Ok([fit(ThMethod::Rt)?, fit(ThMethod::Kt)?, fit(ThMethod::At)?])
}

/// How [`MAHA_D2`] was set: the 99.9th percentile of the Mahalanobis d²
/// (per group, the larger) over every GPS epoch of clean simulated flights
/// (aggressive, survey and paper trajectories, seeds `seeds`), with the
/// verdicts forced to "normal" so every epoch enters the reference window.
pub fn calibrate_mahalanobis(seeds: core::ops::Range<u64>) -> Result<f64, String> {
    let mut d2 = vec![];
    clean_epochs(seeds, Method::Mahalanobis, |_, f| d2.push(f * MAHA_D2))?;
    if d2.is_empty() {
        return Err("calibrate_mahalanobis: no epochs".into());
    }
    d2.sort_by(f64::total_cmp);
    Ok(d2[((d2.len() as f64 * 0.999) as usize).min(d2.len() - 1)])
}


#[cfg(all(test, not(target_arch = "wasm32")))]
mod tests {
    use super::*;
    use crate::methods::{EMBEDDED_POOLS, POOL_SEEDS};

    #[test]
    fn mahalanobis_threshold_is_reproducible() {
        let q = calibrate_mahalanobis(1000..1004).unwrap();
        println!("calibrated d² threshold {q:.2} (shipped {MAHA_D2})");
        assert!((q - MAHA_D2).abs() <= 0.05 * MAHA_D2, "recalibrated {q:.2}, shipped {MAHA_D2}");
    }

    /// `navguard-train --battery N` gathers its examples flight by flight
    /// (`Examples`): the same model as `train_model` over the same streams,
    /// and the same bytes on a second run. A clean flight alone has no
    /// fault example, and the error says how many of each it found.
    #[test]
    fn battery_examples_train_the_same_model_as_the_streams_at_once() {
        use crate::battery::{simulate, Flight, Split};
        let cfg = Config::default();
        // Tune #11: a 16 m vertical step for 76 s; #17: a 16 m horizontal
        // step for 68 s and a baro drift; #4: clean.
        let rows: Vec<Vec<Sample>> = [11, 17, 4].iter().map(|&i| simulate(&Flight::draw(Split::Tune, i))).collect();
        let refs: Vec<&[Sample]> = rows.iter().map(|r| r.as_slice()).collect();
        let at_once = train_model(&refs, &cfg, 42).unwrap();
        let json = |m: &Model| serde_json::to_string(m).unwrap();
        for _ in 0..2 {
            let mut ex = Examples::default();
            for r in &rows {
                ex.add(r, &cfg).unwrap();
            }
            assert_eq!(json(&ex.fit(&cfg, 42).unwrap()), json(&at_once));
        }
        assert!(at_once.provenance.starts_with("navguard-train: 3 streams, "), "{}", at_once.provenance);
        let mut clean = Examples::default();
        clean.add(&rows[2], &cfg).unwrap();
        let (n, f) = (clean.normal.len(), clean.fault.len());
        assert!(n > 1000 && f == 0, "{n} normal, {f} fault examples on a clean flight");
        let e = clean.fit(&cfg, 42).unwrap_err();
        assert!(e.contains(&format!("got {n} and 0")), "{e}");
    }

    /// The shipped pools are exactly what the simulator gives, byte for
    /// byte. `NAVGUARD_WRITE_POOLS=1 cargo test --release --lib embedded_pools`
    /// rewrites `detector/src/default_pools.bin` after a deliberate change;
    /// then `NAVGUARD_WRITE_POOLS=1 cargo test --release -p navguard-detector
    /// --lib packed_pools` packs it into `default_pools.lz`, what the crate
    /// embeds.
    #[test]
    fn embedded_pools_are_reproduced_exactly() {
        let pools = fit_pools(POOL_SEEDS).unwrap();
        let bytes = postcard::to_allocvec(&pools).unwrap();
        // The codec the crate reads them with writes the same bytes.
        assert!(crate::codec::to_bytes(&pools) == bytes, "codec and postcard differ on the pools");
        if std::env::var_os("NAVGUARD_WRITE_POOLS").is_some() {
            std::fs::write(concat!(env!("CARGO_MANIFEST_DIR"), "/detector/src/default_pools.bin"), &bytes).unwrap();
        }
        assert_eq!(bytes.len(), EMBEDDED_POOLS.len(), "refitted pools differ in size from detector/src/default_pools.bin");
        assert!(bytes == EMBEDDED_POOLS, "refitted pools differ from detector/src/default_pools.bin");
        // And they decode to the same thresholds the detector uses.
        for (k, m) in [Method::Rms, Method::Knee, Method::Adaptive].into_iter().enumerate() {
            let shipped = crate::methods::default_pool(m).unwrap();
            assert_eq!(postcard::to_allocvec(&shipped).unwrap(), postcard::to_allocvec(&pools[k]).unwrap());
        }
    }
}
