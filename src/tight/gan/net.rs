//! Generator and discriminator over flat parameter vectors.
//!
//! * Generator `G`: GRU(latent → hidden), then per time step a linear layer
//!   hidden → m. Outputs are unbounded because the data are standardised.
//!   Parameters: `[GRU | W_o (m × H) | b_o (m)]`.
//! * Discriminator `D`: GRU(m → hidden), mean of the hidden states over the
//!   window, linear → logit, `σ(logit)` = probability "real". Mean pooling
//!   (rather than the last state) gives every time step a direct gradient
//!   path, which trains more stably on short windows.
//!   Parameters: `[GRU | w_d (H) | b_d]`.

use super::gru::{dot, Gru, GruCache};
use crate::rng::Rng;

/// Generator shape.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct GenNet {
    pub latent: usize,
    pub hidden: usize,
    pub dim: usize,
}

/// Discriminator shape.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct DiscNet {
    pub dim: usize,
    pub hidden: usize,
}

/// Reusable buffers for one network pass.
#[derive(Clone, Debug, Default)]
pub(crate) struct NetWork {
    pub gru: GruCache,
    /// Generator output `T × m`.
    pub y: Vec<f64>,
    /// Discriminator: pooled hidden state (`H`).
    pub pooled: Vec<f64>,
    /// ∂L/∂h_t (`T × H`).
    dh: Vec<f64>,
}

fn xavier(p: &mut [f64], fan_in: usize, fan_out: usize, rng: &mut Rng) {
    let lim = libm::sqrt(6.0 / (fan_in + fan_out) as f64);
    for v in p.iter_mut() {
        *v = lim * (2.0 * rng.uniform() - 1.0);
    }
}

impl GenNet {
    pub fn gru(self) -> Gru {
        Gru { input: self.latent, hidden: self.hidden }
    }

    pub fn len(self) -> usize {
        self.gru().len() + self.dim * self.hidden + self.dim
    }

    pub fn init(self, rng: &mut Rng) -> Vec<f64> {
        let mut p = vec![0.0; self.len()];
        let g = self.gru().len();
        self.gru().init(&mut p[..g], rng);
        xavier(&mut p[g..g + self.dim * self.hidden], self.hidden, self.dim, rng);
        p
    }

    /// `G(z)`: `z` is `T × latent`; output `T × m` in `work.y`.
    pub fn forward(self, p: &[f64], z: &[f64], work: &mut NetWork) {
        let (h, m) = (self.hidden, self.dim);
        let gl = self.gru().len();
        self.gru().forward(&p[..gl], z, &mut work.gru);
        let steps = work.gru.steps;
        let wo = &p[gl..gl + m * h];
        let bo = &p[gl + m * h..gl + m * h + m];
        work.y.resize(steps * m, 0.0);
        let hs = work.gru.outputs(h);
        for t in 0..steps {
            let ht = &hs[t * h..(t + 1) * h];
            for k in 0..m {
                work.y[t * m + k] = bo[k] + dot(&wo[k * h..(k + 1) * h], ht);
            }
        }
    }

    /// Backward after [`GenNet::forward`] on the same `z`, given ∂L/∂y
    /// (`T × m`). Adds parameter gradients into `grad`, writes ∂L/∂z.
    pub fn backward(
        self,
        p: &[f64],
        z: &[f64],
        work: &mut NetWork,
        dy: &[f64],
        mut grad: Option<&mut [f64]>,
        dz: Option<&mut [f64]>,
    ) {
        let (h, m) = (self.hidden, self.dim);
        let gl = self.gru().len();
        let steps = work.gru.steps;
        let wo = &p[gl..gl + m * h];
        work.dh.resize(steps * h, 0.0);
        work.dh.fill(0.0);
        let hs = work.gru.outputs(h);
        for t in 0..steps {
            let ht = &hs[t * h..(t + 1) * h];
            let dht = &mut work.dh[t * h..(t + 1) * h];
            for k in 0..m {
                let g = dy[t * m + k];
                for (a, wv) in dht.iter_mut().zip(&wo[k * h..(k + 1) * h]) {
                    *a += g * wv;
                }
            }
            if let Some(gr) = grad.as_deref_mut() {
                let (gwo, gbo) = gr[gl..].split_at_mut(m * h);
                for k in 0..m {
                    let g = dy[t * m + k];
                    gbo[k] += g;
                    for (a, hv) in gwo[k * h..(k + 1) * h].iter_mut().zip(ht) {
                        *a += g * hv;
                    }
                }
            }
        }
        let gg = grad.map(|g| &mut g[..gl]);
        self.gru().backward(&p[..gl], z, &mut work.gru, &work.dh, gg, dz);
    }
}

impl DiscNet {
    pub fn gru(self) -> Gru {
        Gru { input: self.dim, hidden: self.hidden }
    }

    pub fn len(self) -> usize {
        self.gru().len() + self.hidden + 1
    }

    pub fn init(self, rng: &mut Rng) -> Vec<f64> {
        let mut p = vec![0.0; self.len()];
        let g = self.gru().len();
        self.gru().init(&mut p[..g], rng);
        xavier(&mut p[g..g + self.hidden], self.hidden, 1, rng);
        p
    }

    /// Logit of `D(x)`, `x` is `T × m`.
    pub fn forward(self, p: &[f64], x: &[f64], work: &mut NetWork) -> f64 {
        let h = self.hidden;
        let gl = self.gru().len();
        self.gru().forward(&p[..gl], x, &mut work.gru);
        let steps = work.gru.steps;
        work.pooled.resize(h, 0.0);
        work.pooled.fill(0.0);
        let hs = work.gru.outputs(h);
        for t in 0..steps {
            for (a, v) in work.pooled.iter_mut().zip(&hs[t * h..(t + 1) * h]) {
                *a += v;
            }
        }
        let inv = 1.0 / steps.max(1) as f64;
        for a in work.pooled.iter_mut() {
            *a *= inv;
        }
        p[gl + h] + dot(&p[gl..gl + h], &work.pooled)
    }

    /// Backward after [`DiscNet::forward`] given ∂L/∂logit.
    pub fn backward(
        self,
        p: &[f64],
        x: &[f64],
        work: &mut NetWork,
        dlogit: f64,
        grad: Option<&mut [f64]>,
        dx: Option<&mut [f64]>,
    ) {
        let h = self.hidden;
        let gl = self.gru().len();
        let steps = work.gru.steps;
        let inv = 1.0 / steps.max(1) as f64;
        let wd = &p[gl..gl + h];
        work.dh.resize(steps * h, 0.0);
        for t in 0..steps {
            for (a, wv) in work.dh[t * h..(t + 1) * h].iter_mut().zip(wd) {
                *a = dlogit * wv * inv;
            }
        }
        let gg = match grad {
            Some(g) => {
                let (gg, head) = g.split_at_mut(gl);
                for (a, v) in head[..h].iter_mut().zip(&work.pooled) {
                    *a += dlogit * v;
                }
                head[h] += dlogit;
                Some(gg)
            }
            None => None,
        };
        self.gru().backward(&p[..gl], x, &mut work.gru, &work.dh, gg, dx);
    }
}
