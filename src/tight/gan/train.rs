//! Adversarial training (§3.1) and the fit statistics of §3.2.

use super::adam::Adam;
use super::gru::sigmoid;
use super::net::NetWork;
use super::score::{check_vec, normalised_std};
use super::{GanConfig, GanModel, TrainProgress};
use crate::rng::Rng;
use crate::tight::TightError;

/// `log(1 + eˣ)` without overflow.
#[inline]
pub(crate) fn softplus(x: f64) -> f64 {
    if x > 0.0 {
        x + libm::log1p(libm::exp(-x))
    } else {
        libm::log1p(libm::exp(x))
    }
}

fn fill_normal(v: &mut [f64], rng: &mut Rng) {
    for x in v.iter_mut() {
        *x = rng.normal();
    }
}

/// Trains the GAN on normal windows (each `w × m`, see
/// [`super::subsequences`]) with the losses of §3.1, minibatch Adam, one D
/// step then one G step per minibatch:
///
/// * D minimises `−[log D(x) + log(1 − D(G(z)))]`,
/// * G minimises `−log D(G(z))` (non-saturating form),
///
/// `z ~ N(0, 1)` freshly drawn for each term, seeded shuffling. After
/// training it computes `R_G` (min/max), `S_G`, `S_D` and `λ` on the same
/// windows. `progress` is called after each epoch; returning `false`
/// cancels training with an error.
pub fn train(
    windows: &[Vec<f64>],
    cfg: &GanConfig,
    progress: &mut dyn FnMut(&TrainProgress) -> bool,
) -> Result<GanModel, TightError> {
    cfg.check()?;
    if windows.len() < 2 {
        return Err(TightError::new("windows", format!("need ≥ 2 windows, got {}", windows.len())));
    }
    for (i, w) in windows.iter().enumerate() {
        check_vec(&format!("windows[{i}]"), w, cfg.window_len())?;
    }
    let gn = GanModel::gen_net(cfg);
    let dn = GanModel::disc_net(cfg);
    let mut rng = Rng::new(cfg.seed);
    let mut g = gn.init(&mut rng);
    let mut d = dn.init(&mut rng);
    let mut opt_g = Adam::new(g.len(), cfg.lr_g, 0.5);
    let mut opt_d = Adam::new(d.len(), cfg.lr_d, 0.5);
    let mut grad_g = vec![0.0; g.len()];
    let mut grad_d = vec![0.0; d.len()];
    let (mut gw, mut dw) = (NetWork::default(), NetWork::default());
    let mut z = vec![0.0; cfg.latent_len()];
    let mut fake = vec![0.0; cfg.window_len()];
    let mut dfake = vec![0.0; cfg.window_len()];
    let mut order: Vec<usize> = (0..windows.len()).collect();
    for epoch in 1..=cfg.epochs {
        // Fisher–Yates.
        for i in (1..order.len()).rev() {
            let j = (rng.next_u64() % (i as u64 + 1)) as usize;
            order.swap(i, j);
        }
        let (mut d_loss, mut g_loss, mut d_real, mut d_fake) = (0.0, 0.0, 0.0, 0.0);
        for batch in order.chunks(cfg.batch) {
            let inv = 1.0 / batch.len() as f64;
            grad_d.fill(0.0);
            for &i in batch {
                let x = &windows[i];
                let a = dn.forward(&d, x, &mut dw);
                let p = sigmoid(a);
                d_loss += softplus(-a);
                d_real += p;
                dn.backward(&d, x, &mut dw, (p - 1.0) * inv, Some(&mut grad_d), None);
                fill_normal(&mut z, &mut rng);
                gn.forward(&g, &z, &mut gw);
                fake.copy_from_slice(&gw.y);
                let a = dn.forward(&d, &fake, &mut dw);
                let p = sigmoid(a);
                d_loss += softplus(a);
                d_fake += p;
                dn.backward(&d, &fake, &mut dw, p * inv, Some(&mut grad_d), None);
            }
            opt_d.step(&mut d, &grad_d);
            grad_g.fill(0.0);
            for _ in batch {
                fill_normal(&mut z, &mut rng);
                gn.forward(&g, &z, &mut gw);
                let a = dn.forward(&d, &gw.y, &mut dw);
                let p = sigmoid(a);
                g_loss += softplus(-a);
                dn.backward(&d, &gw.y, &mut dw, (p - 1.0) * inv, None, Some(&mut dfake));
                gn.backward(&g, &z, &mut gw, &dfake, Some(&mut grad_g), None);
            }
            opt_g.step(&mut g, &grad_g);
        }
        let n = windows.len() as f64;
        let rep = TrainProgress {
            epoch,
            epochs: cfg.epochs,
            d_loss: d_loss / n,
            g_loss: g_loss / n,
            d_real: d_real / n,
            d_fake: d_fake / n,
        };
        if !rep.d_loss.is_finite() || !rep.g_loss.is_finite() {
            return Err(TightError::new("train", format!("diverged at epoch {epoch} (non-finite loss)")));
        }
        if !progress(&rep) {
            return Err(TightError::new("progress", format!("training cancelled after epoch {epoch}")));
        }
    }
    let mut model = GanModel {
        cfg: cfg.clone(),
        g,
        d,
        lambda: 0.5,
        rg_min: 0.0,
        rg_max: 1.0,
        s_g: 0.0,
        s_d: 0.0,
        t2: f64::INFINITY,
    };
    model.validate().map_err(|e| TightError::new("train", format!("diverged: {e}")))?;
    fit_statistics(&mut model, windows, &mut rng)?;
    Ok(model)
}

/// §3.2 steps 1–3 and λ. `R_G` uses the detection-time latent search
/// (stream warm starts), `S_D` the discriminator outputs `c_u` on the `n`
/// real and `n` generated windows, `R_D = |c_u − 0.5|`.
fn fit_statistics(model: &mut GanModel, windows: &[Vec<f64>], rng: &mut Rng) -> Result<(), TightError> {
    let scores = model.score_stream(windows)?;
    let rg: Vec<f64> = scores.iter().map(|s| s.gs).collect();
    model.rg_min = rg.iter().copied().fold(f64::INFINITY, f64::min);
    model.rg_max = rg.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    model.s_g = normalised_std(&rg);
    let gn = GanModel::gen_net(&model.cfg);
    let dn = GanModel::disc_net(&model.cfg);
    let (mut gw, mut dw) = (NetWork::default(), NetWork::default());
    let mut z = vec![0.0; model.cfg.latent_len()];
    let mut rd = Vec::with_capacity(2 * windows.len());
    for s in &scores {
        rd.push((s.d - 0.5).abs());
    }
    for _ in windows {
        fill_normal(&mut z, rng);
        gn.forward(&model.g, &z, &mut gw);
        rd.push((sigmoid(dn.forward(&model.d, &gw.y, &mut dw)) - 0.5).abs());
    }
    model.s_d = normalised_std(&rd);
    let sum = model.s_g + model.s_d;
    // Both dispersions zero only for degenerate data: weigh the parts equally.
    model.lambda = if sum > 0.0 { model.s_d / sum } else { 0.5 };
    Ok(())
}
