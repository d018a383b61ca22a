use approx::assert_relative_eq;

use super::gru::{sigmoid, Gru, GruCache};
use super::net::{DiscNet, GenNet, NetWork};
use super::score::correlation;
use super::train::softplus;
use super::*;
use crate::rng::Rng;

fn randv(n: usize, rng: &mut Rng) -> Vec<f64> {
    (0..n).map(|_| rng.normal()).collect()
}

/// ‖a − b‖ / (‖a‖ + ‖b‖): relative error of a gradient block.
fn rel_err(a: &[f64], b: &[f64]) -> f64 {
    let d = a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>().sqrt();
    let n = a.iter().map(|x| x * x).sum::<f64>().sqrt() + b.iter().map(|x| x * x).sum::<f64>().sqrt();
    assert!(n > 1e-8, "gradient block is zero: the check would be vacuous");
    d / n
}

/// Central differences of `f` over the coordinates `range` of `x`.
fn numeric(x: &mut [f64], range: core::ops::Range<usize>, f: &mut dyn FnMut(&[f64]) -> f64) -> Vec<f64> {
    let h = 1e-6;
    range
        .map(|i| {
            let x0 = x[i];
            x[i] = x0 + h;
            let fp = f(x);
            x[i] = x0 - h;
            let fm = f(x);
            x[i] = x0;
            (fp - fm) / (2.0 * h)
        })
        .collect()
}

#[test]
fn gru_backward_matches_finite_differences() {
    let gru = Gru { input: 3, hidden: 4 };
    let steps = 5;
    let mut rng = Rng::new(7);
    let mut p = vec![0.0; gru.len()];
    gru.init(&mut p, &mut rng);
    // Non-zero biases so every term is exercised.
    let nb = 3 * gru.hidden;
    let blen = p.len();
    for v in &mut p[blen - nb..] {
        *v = 0.3 * rng.normal();
    }
    let mut x = randv(steps * gru.input, &mut rng);
    let c = randv(steps * gru.hidden, &mut rng);
    let loss = |p: &[f64], x: &[f64]| {
        let mut cache = GruCache::default();
        gru.forward(p, x, &mut cache);
        super::gru::dot(cache.outputs(gru.hidden), &c)
    };
    let mut cache = GruCache::default();
    gru.forward(&p, &x, &mut cache);
    let mut grad = vec![0.0; gru.len()];
    let mut dx = vec![0.0; x.len()];
    gru.backward(&p, &x, &mut cache, &c, Some(&mut grad), Some(&mut dx));

    let (h, i) = (gru.hidden, gru.input);
    let groups = [
        ("W_z", 0, h * i),
        ("W_r", h * i, 2 * h * i),
        ("W_h", 2 * h * i, 3 * h * i),
        ("U_z", 3 * h * i, 3 * h * i + h * h),
        ("U_r", 3 * h * i + h * h, 3 * h * i + 2 * h * h),
        ("U_h", 3 * h * i + 2 * h * h, 3 * h * i + 3 * h * h),
        ("b", 3 * h * i + 3 * h * h, gru.len()),
    ];
    let xc = x.clone();
    for (name, a, b) in groups {
        let num = numeric(&mut p, a..b, &mut |pp| loss(pp, &xc));
        let e = rel_err(&grad[a..b], &num);
        println!("gru {name}: rel err {e:.2e}");
        assert!(e < 1e-5, "{name}: {e}");
    }
    let pc = p.clone();
    let n = x.len();
    let num = numeric(&mut x, 0..n, &mut |xx| loss(&pc, xx));
    let e = rel_err(&dx, &num);
    println!("gru dx: rel err {e:.2e}");
    assert!(e < 1e-5, "dx: {e}");
}

#[test]
fn generator_backward_matches_finite_differences() {
    let gn = GenNet { latent: 3, hidden: 4, dim: 2 };
    let steps = 5;
    let mut rng = Rng::new(11);
    let mut p = gn.init(&mut rng);
    let plen = p.len();
    for v in &mut p[plen - gn.dim..] {
        *v = 0.2 * rng.normal();
    }
    let mut z = randv(steps * gn.latent, &mut rng);
    let c = randv(steps * gn.dim, &mut rng);
    let loss = |p: &[f64], z: &[f64]| {
        let mut w = NetWork::default();
        gn.forward(p, z, &mut w);
        super::gru::dot(&w.y, &c)
    };
    let mut w = NetWork::default();
    gn.forward(&p, &z, &mut w);
    let mut grad = vec![0.0; p.len()];
    let mut dz = vec![0.0; z.len()];
    gn.backward(&p, &z, &mut w, &c, Some(&mut grad), Some(&mut dz));
    let gl = gn.gru().len();
    let zc = z.clone();
    for (name, a, b) in [("gru", 0, gl), ("W_o", gl, gl + gn.dim * gn.hidden), ("b_o", gl + gn.dim * gn.hidden, plen)] {
        let num = numeric(&mut p, a..b, &mut |pp| loss(pp, &zc));
        let e = rel_err(&grad[a..b], &num);
        println!("generator {name}: rel err {e:.2e}");
        assert!(e < 1e-5, "{name}: {e}");
    }
    let pc = p.clone();
    let n = z.len();
    let num = numeric(&mut z, 0..n, &mut |zz| loss(&pc, zz));
    let e = rel_err(&dz, &num);
    println!("generator dz: rel err {e:.2e}");
    assert!(e < 1e-5, "dz: {e}");
}

#[test]
fn discriminator_bce_backward_matches_finite_differences() {
    let dn = DiscNet { dim: 3, hidden: 4 };
    let steps = 5;
    let mut rng = Rng::new(13);
    let mut p = dn.init(&mut rng);
    let mut x = randv(steps * dn.dim, &mut rng);
    for real in [true, false] {
        // BCE: −log D(x) for a real label, −log(1 − D(x)) for a fake one.
        let loss = |p: &[f64], x: &[f64]| {
            let mut w = NetWork::default();
            let a = dn.forward(p, x, &mut w);
            if real {
                softplus(-a)
            } else {
                softplus(a)
            }
        };
        let mut w = NetWork::default();
        let a = dn.forward(&p, &x, &mut w);
        let dl = if real { sigmoid(a) - 1.0 } else { sigmoid(a) };
        let mut grad = vec![0.0; p.len()];
        let mut dx = vec![0.0; x.len()];
        dn.backward(&p, &x, &mut w, dl, Some(&mut grad), Some(&mut dx));
        let gl = dn.gru().len();
        let xc = x.clone();
        for (name, a, b) in [("gru", 0, gl), ("head", gl, p.len())] {
            let n = p.len();
            let num = numeric(&mut p, a..b.min(n), &mut |pp| loss(pp, &xc));
            let e = rel_err(&grad[a..b], &num);
            println!("discriminator (real={real}) {name}: rel err {e:.2e}");
            assert!(e < 1e-5, "{name}: {e}");
        }
        let pc = p.clone();
        let n = x.len();
        let num = numeric(&mut x, 0..n, &mut |xx| loss(&pc, xx));
        let e = rel_err(&dx, &num);
        println!("discriminator (real={real}) dx: rel err {e:.2e}");
        assert!(e < 1e-5, "dx: {e}");
    }
}

#[test]
fn correlation_and_gradient() {
    // Exact values: perfectly (anti-)correlated and a hand-computed case.
    let y = [1.0, 2.0, 3.0, 4.0];
    assert_relative_eq!(correlation(&y, &[2.0, 4.0, 6.0, 8.0], None), 1.0, epsilon = 1e-14);
    assert_relative_eq!(correlation(&y, &[5.0, 3.0, 1.0, -1.0], None), -1.0, epsilon = 1e-14);
    // a = (−1.5,−.5,.5,1.5), b = (−1,1,−1,1) − 0: a·b = 2, ‖a‖² = 5, ‖b‖² = 4.
    assert_relative_eq!(correlation(&y, &[0.0, 2.0, 0.0, 2.0], None), 2.0 / (5.0f64 * 4.0).sqrt(), epsilon = 1e-14);
    // Constant side: defined as 0 with zero gradient.
    let mut gr = [9.0; 4];
    assert_eq!(correlation(&y, &[3.0; 4], Some(&mut gr)), 0.0);
    assert_eq!(gr, [0.0; 4]);
    // Gradient vs central differences.
    let mut rng = Rng::new(3);
    let y = randv(20, &mut rng);
    let mut g = randv(20, &mut rng);
    let mut an = vec![0.0; 20];
    correlation(&y, &g, Some(&mut an));
    let num = numeric(&mut g, 0..20, &mut |gg| correlation(&y, gg, None));
    let e = rel_err(&an, &num);
    println!("correlation grad: rel err {e:.2e}");
    assert!(e < 1e-6, "{e}");
}

/// Λ through the generator w.r.t. z (the latent-search gradient).
#[test]
fn latent_search_gradient_matches_finite_differences() {
    let cfg = GanConfig { window: 6, dim: 2, latent: 3, hidden: 5, ..GanConfig::default() };
    let gn = GanModel::gen_net(&cfg);
    let mut rng = Rng::new(5);
    let p = gn.init(&mut rng);
    let y = randv(cfg.window_len(), &mut rng);
    let mut z = randv(cfg.latent_len(), &mut rng);
    let lam = |z: &[f64]| {
        let mut w = NetWork::default();
        gn.forward(&p, z, &mut w);
        1.0 - correlation(&y, &w.y, None)
    };
    let mut w = NetWork::default();
    gn.forward(&p, &z, &mut w);
    let mut dg = vec![0.0; y.len()];
    correlation(&y, &w.y, Some(&mut dg));
    for v in &mut dg {
        *v = -*v;
    }
    let mut dz = vec![0.0; z.len()];
    gn.backward(&p, &z, &mut w, &dg, None, Some(&mut dz));
    let n = z.len();
    let num = numeric(&mut z, 0..n, &mut |zz| lam(zz));
    let e = rel_err(&dz, &num);
    println!("Λ w.r.t. z: rel err {e:.2e}");
    assert!(e < 1e-5, "{e}");
}

#[test]
fn subsequences_shapes_and_errors() {
    // M = 7 rows, m = 2, w = 3, u = 2 → n = ⌊4/2⌋ + 1 = 3.
    let y: Vec<f64> = (0..14).map(f64::from).collect();
    let s = subsequences(&y, 2, 3, 2).unwrap();
    assert_eq!(s.len(), 3);
    assert_eq!(s[1], vec![4.0, 5.0, 6.0, 7.0, 8.0, 9.0]);
    assert_eq!(s[2], (8..14).map(f64::from).collect::<Vec<_>>());
    assert_eq!(subsequences(&y, 2, 7, 1).unwrap().len(), 1);
    assert_eq!(subsequences(&y, 2, 8, 1).unwrap_err().field, "y");
    assert_eq!(subsequences(&y, 3, 2, 1).unwrap_err().field, "y");
    assert_eq!(subsequences(&y, 2, 0, 1).unwrap_err().field, "w");
    assert_eq!(subsequences(&y, 2, 2, 0).unwrap_err().field, "u");
    let mut bad = y.clone();
    bad[5] = f64::NAN;
    assert_eq!(subsequences(&bad, 2, 2, 1).unwrap_err().field, "y[5]");
}

#[test]
fn config_errors_name_the_field() {
    assert!(GanConfig::default().check().is_ok());
    let cases: Vec<(&str, GanConfig)> = vec![
        ("window", GanConfig { window: 0, ..Default::default() }),
        ("step", GanConfig { step: 0, ..Default::default() }),
        ("dim", GanConfig { dim: 0, ..Default::default() }),
        ("latent", GanConfig { latent: MAX_SIZE + 1, ..Default::default() }),
        ("hidden", GanConfig { hidden: 0, ..Default::default() }),
        ("epochs", GanConfig { epochs: 0, ..Default::default() }),
        ("batch", GanConfig { batch: 0, ..Default::default() }),
        ("lr_g", GanConfig { lr_g: f64::NAN, ..Default::default() }),
        ("lr_d", GanConfig { lr_d: -1e-3, ..Default::default() }),
        ("z_lr", GanConfig { z_lr: 0.0, ..Default::default() }),
        ("z_iters", GanConfig { z_iters: 1_000_000, ..Default::default() }),
    ];
    for (field, cfg) in cases {
        let e = cfg.check().unwrap_err();
        assert_eq!(e.field, field, "{e}");
        let e2 = train(&[vec![0.0; 4], vec![0.0; 4]], &cfg, &mut |_| true).unwrap_err();
        assert_eq!(e2.field, field);
    }
    // Window shape errors name the window.
    let cfg = GanConfig { window: 2, dim: 2, ..Default::default() };
    let e = train(&[vec![0.0; 4], vec![0.0; 3]], &cfg, &mut |_| true).unwrap_err();
    assert_eq!(e.field, "windows[1]");
    let e = train(&[vec![0.0; 4], vec![0.0, f64::INFINITY, 0.0, 0.0]], &cfg, &mut |_| true).unwrap_err();
    assert_eq!(e.field, "windows[1][1]");
}

// ---------------------------------------------------------------------------
// Training on a known process.

/// Noisy sine (period 25 samples, noise σ 0.15), standardised, embedded with
/// m = 3 and delay 2: rows `[s_t, s_{t+2}, s_{t+4}]`.
fn sine_rows(n: usize, seed: u64) -> Vec<f64> {
    let mut rng = Rng::new(seed);
    let s: Vec<f64> = (0..n + 4)
        .map(|t| (2.0 * core::f64::consts::PI * t as f64 / 25.0).sin() + 0.15 * rng.normal())
        .collect();
    let mean = s.iter().sum::<f64>() / s.len() as f64;
    let sd = (s.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / s.len() as f64).sqrt();
    let s: Vec<f64> = s.iter().map(|v| (v - mean) / sd).collect();
    (0..n).flat_map(|t| [s[t], s[t + 2], s[t + 4]]).collect()
}

fn small_cfg() -> GanConfig {
    GanConfig {
        window: 10,
        step: 1,
        dim: 3,
        latent: 3,
        hidden: 12,
        epochs: 40,
        batch: 32,
        lr_g: 2e-3,
        lr_d: 1e-3,
        seed: 42,
        z_iters: 30,
        z_lr: 0.1,
        z_prior: 0.1,
    }
}

fn moments(ws: &[Vec<f64>]) -> (f64, f64) {
    let all: Vec<f64> = ws.iter().flatten().copied().collect();
    let n = all.len() as f64;
    let m = all.iter().sum::<f64>() / n;
    (m, (all.iter().map(|v| (v - m).powi(2)).sum::<f64>() / n).sqrt())
}

#[test]
fn training_learns_the_process_and_detects_shifts() {
    let cfg = small_cfg();
    let train_w = subsequences(&sine_rows(400, 1), cfg.dim, cfg.window, cfg.step).unwrap();
    let mut log = Vec::new();
    let mut model = train(&train_w, &cfg, &mut |p| {
        log.push(p.clone());
        true
    })
    .unwrap();
    for p in log.iter().step_by(5) {
        println!(
            "epoch {:2}: d_loss {:.3} g_loss {:.3} D(real) {:.3} D(fake) {:.3}",
            p.epoch, p.d_loss, p.g_loss, p.d_real, p.d_fake
        );
    }
    assert_eq!(log.len(), cfg.epochs);

    // Generator moments vs data, trained vs untrained (epoch-0 weights).
    let mut rng = Rng::new(99);
    let zs: Vec<Vec<f64>> = (0..200).map(|_| randv(cfg.latent_len(), &mut rng)).collect();
    let gen = |m: &GanModel| zs.iter().map(|z| m.generate(z).unwrap()).collect::<Vec<_>>();
    let mut untrained = model.clone();
    let mut r0 = Rng::new(cfg.seed);
    untrained.g = GanModel::gen_net(&cfg).init(&mut r0);
    let (dm, ds) = moments(&train_w);
    let (gm, gs) = moments(&gen(&model));
    let (um, us) = moments(&gen(&untrained));
    let err_t = (gm - dm).abs() + (gs - ds).abs();
    let err_u = (um - dm).abs() + (us - ds).abs();
    println!("data mean {dm:.3} std {ds:.3}; trained G {gm:.3}/{gs:.3}; untrained G {um:.3}/{us:.3}");
    assert!(err_t < 0.5 * err_u, "trained {err_t} vs untrained {err_u}");

    // D on real data in a sane band (neither collapsed nor saturated).
    let d_real = train_w.iter().map(|w| model.discriminate(w).unwrap()).sum::<f64>() / train_w.len() as f64;
    println!("mean D(real) {d_real:.3}, lambda {:.3}, (S_G, S_D) {:?}", model.lambda(), model.dispersions());
    assert!((0.2..0.95).contains(&d_real), "{d_real}");
    assert!(model.lambda() > 0.0 && model.lambda() < 1.0, "{}", model.lambda());

    // Calibrate on fresh normal data, then check held-out false alarms.
    let cal = subsequences(&sine_rows(300, 2), cfg.dim, cfg.window, cfg.step).unwrap();
    let th = model.calibrate(&cal, 0.05).unwrap();
    println!("threshold {th:?}");
    assert!(th.false_alarm <= 0.05 + 1e-12);
    let held = subsequences(&sine_rows(300, 3), cfg.dim, cfg.window, cfg.step).unwrap();
    let hs = model.score_stream(&held).unwrap();
    let fa = hs.iter().filter(|s| model.is_fault(s)).count() as f64 / hs.len() as f64;
    let normal_mean = hs.iter().map(|s| s.score).sum::<f64>() / hs.len() as f64;
    let rms_z = hs.iter().map(|s| (s.z.iter().map(|v| v * v).sum::<f64>() / s.z.len() as f64).sqrt()).sum::<f64>()
        / hs.len() as f64;
    let corr = hs.iter().map(|s| s.corr).sum::<f64>() / hs.len() as f64;
    println!("held-out false alarms {fa:.3}, mean score {normal_mean:.3}, mean corr {corr:.3}, mean rms z {rms_z:.2}");
    // Warm-started searches stay near the prior (they drifted to rms ≈ 15
    // without the z_prior term) and still fit the shape.
    assert!(rms_z < 2.0, "{rms_z}");
    assert!(corr > 0.8, "{corr}");
    assert!(fa <= 0.12, "{fa}");

    // +1.5σ mean shift: higher scores on average.
    let shifted: Vec<Vec<f64>> = held.iter().map(|w| w.iter().map(|v| v + 1.5).collect()).collect();
    let ss = model.score_stream(&shifted).unwrap();
    let shift_mean = ss.iter().map(|s| s.score).sum::<f64>() / ss.len() as f64;
    let det = ss.iter().filter(|s| model.is_fault(s)).count() as f64 / ss.len() as f64;
    let shift_d = ss.iter().map(|s| s.d).sum::<f64>() / ss.len() as f64;
    let shift_gs = ss.iter().map(|s| s.gs_norm).sum::<f64>() / ss.len() as f64;
    let norm_gs = hs.iter().map(|s| s.gs_norm).sum::<f64>() / hs.len() as f64;
    println!("shifted mean score {shift_mean:.3}, detection rate {det:.3}; D {shift_d:.3} vs {d_real:.3}, gs_norm {shift_gs:.3} vs {norm_gs:.3}");
    assert!(shift_mean > normal_mean + 0.1, "{shift_mean} vs {normal_mean}");
}

// ---------------------------------------------------------------------------
// Small trained model for API tests.

fn tiny_cfg(seed: u64) -> GanConfig {
    GanConfig {
        window: 6,
        step: 1,
        dim: 3,
        latent: 2,
        hidden: 5,
        epochs: 3,
        batch: 16,
        seed,
        z_iters: 10,
        ..GanConfig::default()
    }
}

fn tiny_model(seed: u64) -> (GanModel, Vec<Vec<f64>>) {
    let cfg = tiny_cfg(seed);
    let w = subsequences(&sine_rows(80, 5), cfg.dim, cfg.window, cfg.step).unwrap();
    (train(&w, &cfg, &mut |_| true).unwrap(), w)
}

#[test]
fn determinism_same_seed_bit_identical() {
    let (a, _) = tiny_model(8);
    let (b, _) = tiny_model(8);
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&a.g), bits(&b.g));
    assert_eq!(bits(&a.d), bits(&b.d));
    assert_eq!(a.lambda.to_bits(), b.lambda.to_bits());
    let (c, _) = tiny_model(9);
    assert_ne!(bits(&a.g), bits(&c.g), "a different seed must give different weights");
}

#[test]
fn cancel_and_lambda_and_input_errors() {
    let cfg = tiny_cfg(3);
    let w = subsequences(&sine_rows(80, 5), cfg.dim, cfg.window, cfg.step).unwrap();
    let mut calls = 0;
    let e = train(&w, &cfg, &mut |p| {
        calls += 1;
        p.epoch < 2
    })
    .unwrap_err();
    assert_eq!(e.field, "progress");
    assert!(e.message.contains("cancelled"), "{e}");
    assert_eq!(calls, 2);

    let (mut m, w) = tiny_model(3);
    assert!(m.lambda() > 0.0 && m.lambda() < 1.0, "{}", m.lambda());
    let (sg, sd) = m.dispersions();
    assert_relative_eq!(m.lambda(), sd / (sg + sd), epsilon = 1e-15);
    let (lo, hi) = m.rg_range();
    assert!(lo < hi);
    // Parameter count: G = 3·5·2 + 3·5·5 + 15 + 3·5 + 3 = 138; D = 3·5·3 + 75 + 15 + 5 + 1 = 141.
    assert_eq!(m.param_count(), 138 + 141);

    // Before calibration nothing is a fault.
    let s = m.score(&w[0], None).unwrap();
    assert!(!m.is_fault(&s));
    assert_eq!(m.t2(), f64::INFINITY);
    assert_relative_eq!(s.score, m.lambda() * s.gs_norm + (1.0 - m.lambda()) * (1.0 - s.d), epsilon = 1e-15);
    let gs = s.generated.iter().zip(&w[0]).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt();
    assert_relative_eq!(s.gs, gs, epsilon = 1e-12);
    assert_relative_eq!(s.corr, correlation(&w[0], &s.generated, None), epsilon = 1e-15);
    assert_eq!(s.generated, m.generate(&s.z).unwrap());
    assert_relative_eq!(s.d, m.discriminate(&w[0]).unwrap(), epsilon = 1e-15);

    assert_eq!(m.score(&w[0][1..], None).unwrap_err().field, "y");
    let mut bad = w[0].clone();
    bad[4] = f64::NAN;
    assert_eq!(m.score(&bad, None).unwrap_err().field, "y[4]");
    assert_eq!(m.score(&w[0], Some(&[0.0; 3])).unwrap_err().field, "z0");
    assert_eq!(m.generate(&[0.0; 5]).unwrap_err().field, "z");
    assert_eq!(m.discriminate(&[0.0; 5]).unwrap_err().field, "y");
    assert_eq!(m.calibrate(&w, 0.0).unwrap_err().field, "alpha");
    assert_eq!(m.calibrate(&w[..1], 0.1).unwrap_err().field, "fault_free");
    let mut ws = w.clone();
    ws[3].pop();
    assert_eq!(m.score_stream(&ws).unwrap_err().field, "windows[3].y");

    // Shift: row t ← row t+1, last row repeated (latent = 2).
    let z: Vec<f64> = (0..12).map(f64::from).collect();
    assert_eq!(m.shift_latent(&z, 1).unwrap(), vec![2., 3., 4., 5., 6., 7., 8., 9., 10., 11., 10., 11.]);
    assert_eq!(m.shift_latent(&z, 9).unwrap(), [10., 11.].repeat(6));
    // Warm start is honoured when it is the better start: the search from
    // its own optimum cannot get worse than that optimum.
    let s2 = m.score(&w[0], Some(&s.z)).unwrap();
    assert!(s2.corr >= s.corr - 1e-3, "{} vs {}", s2.corr, s.corr);
}

#[test]
fn serialization_round_trip_and_damage() {
    let (mut m, w) = tiny_model(4);
    let th = m.calibrate(&w, 0.1).unwrap();
    assert!(th.t2 >= th.t2_normal && th.t2 >= th.t2_empirical);
    assert!(th.false_alarm <= 0.1);
    let bytes = m.to_bytes().unwrap();
    let back = GanModel::from_bytes(&bytes).unwrap();
    assert_eq!(back, m);
    for y in w.iter().take(5) {
        let (a, b) = (m.score(y, None).unwrap(), back.score(y, None).unwrap());
        assert_eq!(a.score.to_bits(), b.score.to_bits());
        assert_eq!(a.z, b.z);
    }
    // Every truncation errors (never panics).
    for n in 0..bytes.len() {
        assert!(GanModel::from_bytes(&bytes[..n]).is_err(), "truncated to {n}");
    }
    let mut b = bytes.clone();
    b[0] ^= 0xFF;
    assert!(GanModel::from_bytes(&b).unwrap_err().message.contains("magic"));
    let mut b = bytes.clone();
    b[5] = 9;
    assert!(GanModel::from_bytes(&b).unwrap_err().message.contains("version"));
    let mut b = bytes.clone();
    b.push(0);
    assert!(GanModel::from_bytes(&b).is_err());
    let mut b = bytes.clone();
    let k = b.len() - 3;
    b[k] ^= 0x10;
    assert!(GanModel::from_bytes(&b).unwrap_err().message.contains("checksum"));
    // Valid envelope, wrong weight shape or bad values: rejected by validation.
    let mut bad = m.clone();
    bad.g.pop();
    assert_eq!(GanModel::from_bytes(&bad.to_bytes().unwrap()).unwrap_err().field, "g");
    let mut bad = m.clone();
    bad.d[0] = f64::NAN;
    assert_eq!(GanModel::from_bytes(&bad.to_bytes().unwrap()).unwrap_err().field, "d[0]");
    let mut bad = m.clone();
    bad.cfg.hidden = 0;
    assert_eq!(GanModel::from_bytes(&bad.to_bytes().unwrap()).unwrap_err().field, "hidden");
    let mut bad = m.clone();
    bad.lambda = 1.5;
    assert_eq!(GanModel::from_bytes(&bad.to_bytes().unwrap()).unwrap_err().field, "lambda");
}
