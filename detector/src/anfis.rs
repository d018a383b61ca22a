//! Two-input first-order Sugeno ANFIS (Jang 1993), as in Sun et al. 2017 §2.3.
//!
//! Inputs are `x1 = ln(1 + R)` and `x2 = C`: the log keeps R's long tail
//! (R runs from ≈1 on clean data to hundreds in a step fault) from crushing
//! the Gaussian memberships into one corner. Layers:
//! 1. Gaussian memberships `μ(x) = exp(−(x − c)² / (2σ²))` (eq. 8), `M` per
//!    input, grid partition, so `M²` rules;
//! 2. firing strength by product T-norm `w_ij = μ_i(x1) μ_j(x2)` (eq. 9);
//! 3. normalisation `w̄ = w / Σw`;
//! 4. consequents `f = p x1 + q x2 + r` (eq. 7);
//! 5. output `F = Σ w̄ f`.
//!
//! Hybrid learning: with premises fixed, `F` is linear in the consequents, so
//! they are solved by ridge-regularised least squares (normal equations via
//! Cholesky, raising the ridge if rounding makes them indefinite); then
//! premises take gradient steps on the
//! squared error. `exp` comes from `libm` so native and wasm agree bit for bit.

use crate::MinMax;
use nalgebra::{SMatrix, SVector};
use serde::{Deserialize, Serialize};

/// Memberships per input.
pub const M: usize = 3;
/// Rules (grid partition).
pub const RULES: usize = M * M;
/// Consequent parameters per rule: p, q, r.
pub const CP: usize = 3;

/// Smallest membership width allowed during training, so no MF collapses.
const MIN_SIGMA: f64 = 0.05;

/// ANFIS parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Anfis {
    /// Membership centres per input: `[input][mf]`.
    pub centre: [[f64; M]; 2],
    /// Membership widths per input: `[input][mf]` (positive).
    pub sigma: [[f64; M]; 2],
    /// Consequents per rule `[p, q, r]`, rule index `i * M + j`.
    pub conseq: [[f64; CP]; RULES],
}

/// Gaussian membership (eq. 8).
#[inline]
pub fn gauss(x: f64, c: f64, s: f64) -> f64 {
    let z = (x - c) / s;
    libm::exp(-0.5 * z * z)
}

/// Map the indicators to the ANFIS input space.
#[inline]
pub fn inputs(r: f64, c: f64) -> [f64; 2] {
    let r = if r.is_finite() { r.fmax(0.0) } else { 1e6 };
    let c = if c.is_finite() { c.clamp(0.0, 1.0) } else { 0.0 };
    [libm::log1p(r), c]
}

impl Anfis {
    /// Grid-partition initialisation over the data's range per input.
    pub fn init_grid(lo: [f64; 2], hi: [f64; 2]) -> Self {
        let mut centre = [[0.0; M]; 2];
        let mut sigma = [[0.0; M]; 2];
        for k in 0..2 {
            let span = (hi[k] - lo[k]).fmax(0.2);
            for m in 0..M {
                centre[k][m] = lo[k] + span * m as f64 / (M - 1) as f64;
                sigma[k][m] = (span / (2.0 * (M - 1) as f64)).fmax(MIN_SIGMA);
            }
        }
        Anfis { centre, sigma, conseq: [[0.0; CP]; RULES] }
    }

    /// Normalised firing strengths (layers 1–3). Falls back to the nearest
    /// rule when every strength underflows, so the output stays defined far
    /// outside the training range.
    pub fn strengths(&self, x: &[f64; 2]) -> [f64; RULES] {
        let mut mu = [[0.0; M]; 2];
        for k in 0..2 {
            for m in 0..M {
                mu[k][m] = gauss(x[k], self.centre[k][m], self.sigma[k][m]);
            }
        }
        let mut w = [0.0; RULES];
        let mut sum = 0.0;
        for i in 0..M {
            for j in 0..M {
                let v = mu[0][i] * mu[1][j];
                w[i * M + j] = v;
                sum += v;
            }
        }
        if sum > 1e-300 && sum.is_finite() {
            for v in w.iter_mut() {
                *v /= sum;
            }
        } else {
            // Nearest rule in normalised distance.
            let mut best = (0usize, f64::INFINITY);
            for i in 0..M {
                for j in 0..M {
                    let d0 = (x[0] - self.centre[0][i]) / self.sigma[0][i];
                    let d1 = (x[1] - self.centre[1][j]) / self.sigma[1][j];
                    let d = d0 * d0 + d1 * d1;
                    if d < best.1 {
                        best = (i * M + j, d);
                    }
                }
            }
            w = [0.0; RULES];
            w[best.0] = 1.0;
        }
        w
    }

    /// F-indicator for ANFIS inputs `x` (layers 4–5).
    pub fn eval(&self, x: &[f64; 2]) -> f64 {
        let w = self.strengths(x);
        let mut f = 0.0;
        for (k, wk) in w.iter().enumerate() {
            let c = &self.conseq[k];
            f += wk * (c[0] * x[0] + c[1] * x[1] + c[2]);
        }
        f
    }

    /// F from raw R and C.
    pub fn f_indicator(&self, r: f64, c: f64) -> f64 {
        self.eval(&inputs(r, c))
    }

    /// Least-squares step: consequents for fixed premises. `ridge` (≥0)
    /// regularises rules that no sample fires.
    #[cfg_attr(navguard_cold_size, optimize(size))]
    pub fn fit_consequents(&mut self, xs: &[[f64; 2]], ys: &[f64], ridge: f64) -> bool {
        let n = xs.len().min(ys.len());
        if n == 0 {
            return false;
        }
        let p = RULES * CP;
        // Accumulate AᵀA and Aᵀy directly: no n×p matrix.
        let mut ata = SMatrix::<f64, { RULES * CP }, { RULES * CP }>::zeros();
        let mut aty = SVector::<f64, { RULES * CP }>::zeros();
        let mut row = [0.0; RULES * CP];
        for k in 0..n {
            let x = &xs[k];
            let w = self.strengths(x);
            for r in 0..RULES {
                row[r * CP] = w[r] * x[0];
                row[r * CP + 1] = w[r] * x[1];
                row[r * CP + 2] = w[r];
            }
            for a in 0..p {
                if row[a] == 0.0 {
                    continue;
                }
                aty[a] += row[a] * ys[k];
                for b in a..p {
                    ata[(a, b)] += row[a] * row[b];
                }
            }
        }
        for a in 0..p {
            for b in 0..a {
                ata[(a, b)] = ata[(b, a)];
            }
            ata[(a, a)] += ridge.fmax(1e-9);
        }
        // Cholesky on the (regularised) normal equations; if rounding leaves
        // them indefinite, raise the ridge tenfold and retry. Fixed-size, so
        // no general SVD is linked into the wasm.
        let mut extra = 0.0;
        let mut sol = None;
        for _ in 0..8 {
            let mut m = ata;
            for a in 0..p {
                m[(a, a)] += extra;
            }
            if let Some(ch) = m.cholesky() {
                sol = Some(ch.solve(&aty));
                break;
            }
            extra = if extra == 0.0 { 1e-6 * (1.0 + ata.diagonal().max()) } else { extra * 10.0 };
        }
        let Some(sol) = sol else { return false };
        if !sol.iter().all(|v| v.is_finite()) {
            return false;
        }
        for r in 0..RULES {
            for c in 0..CP {
                self.conseq[r][c] = sol[r * CP + c];
            }
        }
        true
    }

    /// Mean squared error over a data set.
    #[cfg_attr(navguard_cold_size, optimize(size))]
    pub fn mse(&self, xs: &[[f64; 2]], ys: &[f64]) -> f64 {
        let n = xs.len().min(ys.len());
        if n == 0 {
            return 0.0;
        }
        xs.iter().zip(ys).map(|(x, y)| { let e = self.eval(x) - y; e * e }).sum::<f64>() / n as f64
    }

    /// Gradient of the mean squared error w.r.t. premise parameters
    /// (`[input][mf]` for centres, then widths).
    #[cfg_attr(navguard_cold_size, optimize(size))]
    pub fn premise_gradient(&self, xs: &[[f64; 2]], ys: &[f64]) -> ([[f64; M]; 2], [[f64; M]; 2]) {
        let n = xs.len().min(ys.len());
        let mut gc = [[0.0; M]; 2];
        let mut gs = [[0.0; M]; 2];
        if n == 0 {
            return (gc, gs);
        }
        for k in 0..n {
            let x = &xs[k];
            let mut mu = [[0.0; M]; 2];
            for i in 0..2 {
                for m in 0..M {
                    mu[i][m] = gauss(x[i], self.centre[i][m], self.sigma[i][m]);
                }
            }
            let mut wsum = 0.0;
            let mut fsum = 0.0;
            let mut f = [0.0; RULES];
            let mut w = [0.0; RULES];
            for i in 0..M {
                for j in 0..M {
                    let r = i * M + j;
                    w[r] = mu[0][i] * mu[1][j];
                    let c = &self.conseq[r];
                    f[r] = c[0] * x[0] + c[1] * x[1] + c[2];
                    wsum += w[r];
                    fsum += w[r] * f[r];
                }
            }
            if wsum <= 1e-300 {
                continue;
            }
            let out = fsum / wsum;
            let err = out - ys[k];
            // dOut/dw_r = (f_r − out)/Σw ; dw_r/dμ0_i = μ1_j etc.
            for i in 0..M {
                for j in 0..M {
                    let r = i * M + j;
                    let dw = 2.0 * err * (f[r] - out) / wsum / n as f64;
                    // input 0, mf i
                    let z0 = (x[0] - self.centre[0][i]) / self.sigma[0][i];
                    let d0 = w[r]; // ∂w/∂μ0_i · μ0_i = w
                    gc[0][i] += dw * d0 * z0 / self.sigma[0][i];
                    gs[0][i] += dw * d0 * z0 * z0 / self.sigma[0][i];
                    let z1 = (x[1] - self.centre[1][j]) / self.sigma[1][j];
                    gc[1][j] += dw * w[r] * z1 / self.sigma[1][j];
                    gs[1][j] += dw * w[r] * z1 * z1 / self.sigma[1][j];
                }
            }
        }
        (gc, gs)
    }

    /// Hybrid learning: alternate least squares on consequents and
    /// `epochs` gradient steps on premises with step `lr`. Returns final MSE.
    /// Parameters that would become non-finite are left as they were.
    #[cfg_attr(navguard_cold_size, optimize(size))]
    pub fn train_hybrid(&mut self, xs: &[[f64; 2]], ys: &[f64], epochs: usize, lr: f64) -> f64 {
        let ridge = 1e-6 * xs.len().max(1) as f64;
        self.fit_consequents(xs, ys, ridge);
        let mut best = self.clone();
        let mut best_mse = self.mse(xs, ys);
        let mut step = lr;
        for _ in 0..epochs {
            let (gc, gs) = self.premise_gradient(xs, ys);
            let mut cand = self.clone();
            for i in 0..2 {
                for m in 0..M {
                    cand.centre[i][m] -= step * gc[i][m];
                    cand.sigma[i][m] = (cand.sigma[i][m] - step * gs[i][m]).fmax(MIN_SIGMA);
                }
            }
            if !cand.is_finite() {
                break;
            }
            cand.fit_consequents(xs, ys, ridge);
            let mse = cand.mse(xs, ys);
            if mse < best_mse {
                best = cand.clone();
                best_mse = mse;
                *self = cand;
                step *= 1.1;
            } else {
                // Jang's step-size rule, simplified: shrink on a failed step.
                step *= 0.5;
            }
        }
        *self = best;
        best_mse
    }

    /// Every parameter finite and every width positive.
    #[cfg_attr(navguard_cold_size, optimize(size))]
    pub fn is_finite(&self) -> bool {
        // Over flat slices: `iter().flatten()` of nested arrays made 1.7 KB
        // of wasm.
        self.centre.as_flattened().iter().all(|v| v.is_finite())
            && self.sigma.as_flattened().iter().all(|v| v.is_finite() && *v > 0.0)
            && self.conseq.as_flattened().iter().all(|v| v.is_finite())
    }
}

#[cfg(all(test, not(target_arch = "wasm32")))]
mod tests {
    use super::*;
    use approx::assert_abs_diff_eq;
    use proptest::prelude::*;

    #[test]
    fn gaussian_membership_values() {
        assert_abs_diff_eq!(gauss(1.0, 1.0, 0.5), 1.0);
        // One sigma away: exp(-1/2).
        assert_abs_diff_eq!(gauss(1.5, 1.0, 0.5), 0.6065306597126334, epsilon = 1e-15);
        assert_abs_diff_eq!(gauss(0.0, 1.0, 0.5), (-2.0f64).exp(), epsilon = 1e-15);
    }

    #[test]
    fn sugeno_output_hand_computed() {
        // With all consequents f = x1 + 2 x2 + 3 the output is that plane everywhere.
        let mut a = Anfis::init_grid([0.0, 0.0], [2.0, 1.0]);
        for c in a.conseq.iter_mut() {
            *c = [1.0, 2.0, 3.0];
        }
        assert_abs_diff_eq!(a.eval(&[0.7, 0.2]), 0.7 + 0.4 + 3.0, epsilon = 1e-12);
        // One rule with r=1, others 0: output = its normalised strength.
        let mut b = Anfis::init_grid([0.0, 0.0], [2.0, 1.0]);
        b.conseq[0] = [0.0, 0.0, 1.0];
        let x = [0.0, 0.0];
        let mu0 = [gauss(0.0, 0.0, 0.5), gauss(0.0, 1.0, 0.5), gauss(0.0, 2.0, 0.5)];
        let mu1 = [gauss(0.0, 0.0, 0.25), gauss(0.0, 0.5, 0.25), gauss(0.0, 1.0, 0.25)];
        let total: f64 = mu0.iter().map(|a| mu1.iter().map(|b| a * b).sum::<f64>()).sum();
        assert_abs_diff_eq!(b.eval(&x), mu0[0] * mu1[0] / total, epsilon = 1e-12);
    }

    #[test]
    fn least_squares_recovers_a_plane_exactly() {
        let mut a = Anfis::init_grid([0.0, 0.0], [3.0, 1.0]);
        let mut xs = vec![];
        let mut ys = vec![];
        for i in 0..20 {
            for j in 0..10 {
                let x = [i as f64 * 0.15, j as f64 * 0.1];
                xs.push(x);
                ys.push(0.5 * x[0] - 0.25 * x[1] + 0.1);
            }
        }
        assert!(a.fit_consequents(&xs, &ys, 1e-12));
        assert!(a.mse(&xs, &ys) < 1e-12);
    }

    #[test]
    fn hybrid_learning_separates_classes() {
        // Fault when R is large or C is high; learn it from samples.
        let mut xs = vec![];
        let mut ys = vec![];
        for i in 0..40 {
            for j in 0..20 {
                let r = i as f64 * 0.25;
                let c = j as f64 / 19.0;
                xs.push(inputs(r, c));
                ys.push(if r > 4.0 || c > 0.8 { 1.0 } else { 0.0 });
            }
        }
        let mut a = Anfis::init_grid([0.0, 0.0], [2.4, 1.0]);
        a.fit_consequents(&xs, &ys, 1e-6);
        let before = a.mse(&xs, &ys);
        let after = a.train_hybrid(&xs, &ys, 30, 0.05);
        assert!(after <= before, "hybrid must not worsen: {before} -> {after}");
        let wrong = xs.iter().zip(&ys).filter(|(x, y)| (a.eval(x) >= 0.5) != (**y >= 0.5)).count();
        assert!((wrong as f64) < 0.08 * xs.len() as f64, "misclassified {wrong}/{}", xs.len());
    }

    #[test]
    fn premise_gradient_matches_finite_difference() {
        let mut a = Anfis::init_grid([0.0, 0.0], [2.0, 1.0]);
        for (k, c) in a.conseq.iter_mut().enumerate() {
            *c = [0.1 * k as f64, -0.05 * k as f64, 0.3 - 0.02 * k as f64];
        }
        let xs = [[0.3, 0.2], [1.5, 0.9], [0.9, 0.5], [1.9, 0.1]];
        let ys = [0.0, 1.0, 0.3, 0.8];
        let (gc, gs) = a.premise_gradient(&xs, &ys);
        let h = 1e-6;
        for i in 0..2 {
            for m in 0..M {
                let mut p = a.clone();
                p.centre[i][m] += h;
                let mut q = a.clone();
                q.centre[i][m] -= h;
                let num = (p.mse(&xs, &ys) - q.mse(&xs, &ys)) / (2.0 * h);
                assert_abs_diff_eq!(gc[i][m], num, epsilon = 1e-6);
                let mut p = a.clone();
                p.sigma[i][m] += h;
                let mut q = a.clone();
                q.sigma[i][m] -= h;
                let num = (p.mse(&xs, &ys) - q.mse(&xs, &ys)) / (2.0 * h);
                assert_abs_diff_eq!(gs[i][m], num, epsilon = 1e-6);
            }
        }
    }

    proptest! {
        #[test]
        fn memberships_in_unit_interval(x in -1e6f64..1e6, c in -10.0f64..10.0, s in 0.01f64..100.0) {
            let m = gauss(x, c, s);
            prop_assert!((0.0..=1.0).contains(&m));
        }

        #[test]
        fn normalised_strengths_sum_to_one(r in 0.0f64..1e9, c in -2.0f64..2.0) {
            let a = Anfis::init_grid([0.0, 0.0], [3.0, 1.0]);
            let w = a.strengths(&inputs(r, c));
            let s: f64 = w.iter().sum();
            prop_assert!((s - 1.0).abs() < 1e-9);
            prop_assert!(w.iter().all(|v| (0.0..=1.0).contains(v)));
        }
    }
}

/// The snapshot codec of this file's state types ([`crate::codec`]): each
/// struct's fields in declaration order (a field left out does not compile;
/// `skip`: not saved, rebuilt on restore).
mod codec_impls {
    use super::*;
    use crate::codec::impl_codec;

    impl_codec!(Anfis { centre, sigma, conseq });
}
