//! One GRU layer over a flat parameter slice, with forward caching and
//! backpropagation through time (gradients w.r.t. parameters and inputs).
//!
//! Convention (Cho et al. 2014, as in PyTorch except that the reset gate
//! multiplies `h` *before* `U_h`):
//!
//! ```text
//! z_t = σ(W_z x_t + U_z h_{t−1} + b_z)          update gate
//! r_t = σ(W_r x_t + U_r h_{t−1} + b_r)          reset gate
//! ĥ_t = tanh(W_h x_t + U_h (r_t ⊙ h_{t−1}) + b_h)
//! h_t = (1 − z_t) ⊙ h_{t−1} + z_t ⊙ ĥ_t,         h_0 = 0
//! ```
//!
//! Parameter layout (`H` hidden, `I` input), row-major, gates stacked in the
//! order `z, r, h`: `W` is `3H × I`, then `U` is `3H × H`, then `b` is `3H`.
//! One flat slice keeps Adam, serialization and shape checks trivial.

use crate::rng::Rng;

/// Numerically safe logistic function.
#[inline]
pub(crate) fn sigmoid(x: f64) -> f64 {
    if x >= 0.0 {
        1.0 / (1.0 + libm::exp(-x))
    } else {
        let e = libm::exp(x);
        e / (1.0 + e)
    }
}

/// Dot product with four independent accumulators (fixed summation order,
/// so results are identical on every target, but the compiler can keep
/// the multiply–adds in flight).
#[inline]
pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut acc = [0.0f64; 4];
    let mut ca = a.chunks_exact(4);
    let mut cb = b.chunks_exact(4);
    for (x, y) in (&mut ca).zip(&mut cb) {
        for k in 0..4 {
            acc[k] += x[k] * y[k];
        }
    }
    let tail: f64 = ca.remainder().iter().zip(cb.remainder()).map(|(x, y)| x * y).sum();
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

/// Shape of a GRU layer; parameters live in a caller-owned slice of
/// length [`Gru::len`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Gru {
    pub input: usize,
    pub hidden: usize,
}

/// Activations of one forward pass (reused between calls: no per-step
/// allocation once sized).
#[derive(Clone, Debug, Default)]
pub(crate) struct GruCache {
    pub steps: usize,
    /// `(T+1) × H`, row 0 is `h_0 = 0`, row `t+1` is `h_t`.
    pub h: Vec<f64>,
    /// `T × H` each: update gate, reset gate, candidate, `r ⊙ h_{t−1}`.
    z: Vec<f64>,
    r: Vec<f64>,
    c: Vec<f64>,
    rh: Vec<f64>,
    // Backward scratch.
    da: Vec<f64>,
    dh_next: Vec<f64>,
    dh_prev: Vec<f64>,
    drh: Vec<f64>,
}

impl GruCache {
    fn size(&mut self, steps: usize, hidden: usize) {
        self.steps = steps;
        self.h.resize((steps + 1) * hidden, 0.0);
        for v in [&mut self.z, &mut self.r, &mut self.c, &mut self.rh] {
            v.resize(steps * hidden, 0.0);
        }
        self.da.resize(3 * hidden, 0.0);
        for v in [&mut self.dh_next, &mut self.dh_prev, &mut self.drh] {
            v.resize(hidden, 0.0);
        }
    }

    /// Hidden state `h_t` for `t = 1..=T` (`T × H`).
    pub fn outputs(&self, hidden: usize) -> &[f64] {
        &self.h[hidden..(self.steps + 1) * hidden]
    }
}

impl Gru {
    /// Number of parameters: `3H·I + 3H·H + 3H`.
    pub fn len(self) -> usize {
        let h = self.hidden;
        3 * h * self.input + 3 * h * h + 3 * h
    }

    fn split(self, p: &[f64]) -> (&[f64], &[f64], &[f64]) {
        let h = self.hidden;
        let (w, rest) = p.split_at(3 * h * self.input);
        let (u, b) = rest.split_at(3 * h * h);
        (w, u, b)
    }

    fn split_mut(self, p: &mut [f64]) -> (&mut [f64], &mut [f64], &mut [f64]) {
        let h = self.hidden;
        let (w, rest) = p.split_at_mut(3 * h * self.input);
        let (u, b) = rest.split_at_mut(3 * h * h);
        (w, u, b)
    }

    /// Seeded init into `p` (length [`Gru::len`]): Xavier-uniform `W`,
    /// orthogonal `U` per gate (Gram–Schmidt on Gaussian rows, keeps the
    /// recurrence norm-preserving at start), zero biases.
    pub fn init(self, p: &mut [f64], rng: &mut Rng) {
        let (h, i) = (self.hidden, self.input);
        let (w, u, b) = self.split_mut(p);
        let lim = libm::sqrt(6.0 / (i + h) as f64);
        for v in w.iter_mut() {
            *v = lim * (2.0 * rng.uniform() - 1.0);
        }
        for g in 0..3 {
            let blk = &mut u[g * h * h..(g + 1) * h * h];
            for v in blk.iter_mut() {
                *v = rng.normal();
            }
            for row in 0..h {
                for prev in 0..row {
                    let d: f64 = (0..h).map(|k| blk[row * h + k] * blk[prev * h + k]).sum();
                    for k in 0..h {
                        blk[row * h + k] -= d * blk[prev * h + k];
                    }
                }
                let n = libm::sqrt((0..h).map(|k| blk[row * h + k].powi(2)).sum::<f64>());
                for k in 0..h {
                    blk[row * h + k] /= n.max(1e-12);
                }
            }
        }
        b.fill(0.0);
    }

    /// Forward over `x` (`T × I`, `T = x.len() / I`), filling `cache`.
    /// Callers guarantee `p.len() == len()` and `x.len() % I == 0`.
    pub fn forward(self, p: &[f64], x: &[f64], cache: &mut GruCache) {
        let (hd, id) = (self.hidden, self.input);
        let steps = x.len() / id;
        cache.size(steps, hd);
        let (w, u, b) = self.split(p);
        cache.h[..hd].fill(0.0);
        for t in 0..steps {
            let xt = &x[t * id..(t + 1) * id];
            let (past, next) = cache.h.split_at_mut((t + 1) * hd);
            let hp = &past[t * hd..];
            let hn = &mut next[..hd];
            let zt = &mut cache.z[t * hd..(t + 1) * hd];
            let rt = &mut cache.r[t * hd..(t + 1) * hd];
            let rh = &mut cache.rh[t * hd..(t + 1) * hd];
            for j in 0..hd {
                let az = b[j] + dot(&w[j * id..(j + 1) * id], xt) + dot(&u[j * hd..(j + 1) * hd], hp);
                let jr = hd + j;
                let ar = b[jr] + dot(&w[jr * id..(jr + 1) * id], xt) + dot(&u[jr * hd..(jr + 1) * hd], hp);
                zt[j] = sigmoid(az);
                rt[j] = sigmoid(ar);
                rh[j] = rt[j] * hp[j];
            }
            let ct = &mut cache.c[t * hd..(t + 1) * hd];
            for j in 0..hd {
                let jc = 2 * hd + j;
                let ac = b[jc] + dot(&w[jc * id..(jc + 1) * id], xt) + dot(&u[jc * hd..(jc + 1) * hd], rh);
                ct[j] = libm::tanh(ac);
                hn[j] = (1.0 - zt[j]) * hp[j] + zt[j] * ct[j];
            }
        }
    }

    /// Backpropagation through time after [`Gru::forward`] on the same `x`.
    /// `dh_out` (`T × H`) is ∂L/∂h_t from the layers above. Parameter
    /// gradients are *added* into `grad` (length [`Gru::len`]) when given;
    /// ∂L/∂x (`T × I`) is *written* into `dx` when given.
    pub fn backward(
        self,
        p: &[f64],
        x: &[f64],
        cache: &mut GruCache,
        dh_out: &[f64],
        mut grad: Option<&mut [f64]>,
        mut dx: Option<&mut [f64]>,
    ) {
        let (hd, id) = (self.hidden, self.input);
        let steps = cache.steps;
        let (w, u, _) = self.split(p);
        let GruCache { h, z, r, c, rh, da, dh_next, dh_prev, drh, .. } = cache;
        dh_next.fill(0.0);
        for t in (0..steps).rev() {
            let xt = &x[t * id..(t + 1) * id];
            let hp = &h[t * hd..(t + 1) * hd];
            let (zt, rt, ct, rht) = (
                &z[t * hd..(t + 1) * hd],
                &r[t * hd..(t + 1) * hd],
                &c[t * hd..(t + 1) * hd],
                &rh[t * hd..(t + 1) * hd],
            );
            for j in 0..hd {
                let dh = dh_out[t * hd + j] + dh_next[j];
                da[j] = dh * (ct[j] - hp[j]) * zt[j] * (1.0 - zt[j]);
                da[2 * hd + j] = dh * zt[j] * (1.0 - ct[j] * ct[j]);
                dh_prev[j] = dh * (1.0 - zt[j]);
            }
            // d(r ⊙ h_{t−1}) = U_hᵀ da_c
            drh.fill(0.0);
            for j in 0..hd {
                let g = da[2 * hd + j];
                let row = &u[(2 * hd + j) * hd..(2 * hd + j + 1) * hd];
                for k in 0..hd {
                    drh[k] += row[k] * g;
                }
            }
            for k in 0..hd {
                da[hd + k] = drh[k] * hp[k] * rt[k] * (1.0 - rt[k]);
                dh_prev[k] += drh[k] * rt[k];
            }
            // dh_{t−1} += U_zᵀ da_z + U_rᵀ da_r
            for row in 0..2 * hd {
                let g = da[row];
                let ur = &u[row * hd..(row + 1) * hd];
                for k in 0..hd {
                    dh_prev[k] += ur[k] * g;
                }
            }
            if let Some(gr) = grad.as_deref_mut() {
                let (gw, gu, gb) = self.split_mut(gr);
                for row in 0..3 * hd {
                    let g = da[row];
                    gb[row] += g;
                    for (a, xv) in gw[row * id..(row + 1) * id].iter_mut().zip(xt) {
                        *a += g * xv;
                    }
                    let src = if row < 2 * hd { hp } else { rht };
                    for (a, hv) in gu[row * hd..(row + 1) * hd].iter_mut().zip(src) {
                        *a += g * hv;
                    }
                }
            }
            if let Some(dxs) = dx.as_deref_mut() {
                let dxt = &mut dxs[t * id..(t + 1) * id];
                dxt.fill(0.0);
                for row in 0..3 * hd {
                    let g = da[row];
                    for (a, wv) in dxt.iter_mut().zip(&w[row * id..(row + 1) * id]) {
                        *a += g * wv;
                    }
                }
            }
            core::mem::swap(dh_next, dh_prev);
        }
    }
}
