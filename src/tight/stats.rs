//! Distribution quantiles shared by the λ test (Appendix A), the GAN's
//! threshold T2 and the chi-square checks: pure functions over libm, so
//! identical on every target.

use super::TightError;

/// Upper-tail standard normal quantile: `x` with `P(Z > x) = p`, `0 < p < 1`.
/// Bisection on `erfc` (libm), so identical on every target.
pub fn normal_upper_quantile(p: f64) -> Result<f64, TightError> {
    if !(p > 0.0 && p < 1.0) {
        return Err(TightError::new("p", format!("must be in (0, 1), got {p}")));
    }
    let q = |x: f64| 0.5 * libm::erfc(x / core::f64::consts::SQRT_2);
    let (mut lo, mut hi) = (-40.0f64, 40.0f64);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if q(mid) > p {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok(0.5 * (lo + hi))
}

/// Detection threshold `T1 = N_{α/2}(0, 1)` for the two-sided test of eq. A3
/// at false-alarm rate `α` (α = 0.001 gives 3.29).
pub fn threshold_t1(alpha: f64) -> Result<f64, TightError> {
    if !(alpha > 0.0 && alpha < 1.0) {
        return Err(TightError::new("alpha", format!("must be in (0, 1), got {alpha}")));
    }
    normal_upper_quantile(alpha / 2.0)
}

/// Chi-square quantile (lower tail probability `p`, `k` degrees of freedom),
/// Wilson–Hilferty approximation (relative error < 1 % for k ≥ 3).
pub fn chi2_quantile(p: f64, k: f64) -> Result<f64, TightError> {
    if !(k > 0.0 && k.is_finite()) {
        return Err(TightError::new("k", format!("must be finite and > 0, got {k}")));
    }
    let z = -normal_upper_quantile(p)?;
    let a = 2.0 / (9.0 * k);
    let c = 1.0 - a + z * libm::sqrt(a);
    Ok(k * c * c * c)
}

