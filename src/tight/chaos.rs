//! Chaos analysis and phase-space reconstruction of the pseudo-range
//! increment difference, after Shen et al. 2022 (GAN-FDSR), §2.2 and Table 1.
//!
//! The paper checks that the per-satellite series
//! ρD(ε) = [ρG(ε+1) − ρG(ε)] − [ρI(ε+1) − ρI(ε)] (eq. 10) is chaotic before
//! it reconstructs it in phase space for the predictor. The pipeline is:
//!
//! 1. [`increment_difference`]: eq. 10 (metres in, metres out).
//! 2. [`delay_by_mutual_information`]: the delay τ (samples) as the first
//!    local minimum of the average mutual information E(τ) (eq. 11).
//! 3. [`cao`]: the minimum embedding dimension m from Cao's E1(m), and Cao's
//!    E2(m), which tells deterministic signals from noise.
//! 4. [`embed`]: the M×m delay matrix Y (eq. 16), M = N − (m − 1)τ.
//! 5. [`mean_period`] and [`largest_lyapunov`]: the largest Lyapunov
//!    exponent by Rosenstein et al. (1993), with the temporal-separation
//!    window set to the FFT mean period as in the paper's step 1.
//! 6. [`analyze`] runs 2–5 and [`table1_markdown`] prints Table 1.
//!
//! Units: delays, periods and Lyapunov fit indices are in samples; the
//! Lyapunov exponent is per second given the sample period `dt` in seconds
//! (pass `dt = 1` for maps: the exponent is then per iteration). Mutual
//! information is in nats (natural log).
//!
//! Everything is deterministic, single-threaded and allocation-bounded, so it
//! runs unchanged on wasm32. Transcendental functions come from `libm` so
//! results are bit-identical across targets, like the rest of the crate.

use core::ops::Range;

use serde::{Deserialize, Serialize};

use super::TightError;

/// Largest supported β for the mutual-information histogram: the joint
/// histogram holds β² counters, and 1024² is already 8 MiB.
pub const MAX_BINS: usize = 1024;

// ---------------------------------------------------------------------------
// Input checks
// ---------------------------------------------------------------------------

/// Rejects series shorter than `min_len` or holding a non-finite value.
fn check_series(field: &str, r: &[f64], min_len: usize) -> Result<(), TightError> {
    if r.len() < min_len {
        return Err(TightError::new(
            field,
            format!("series too short: {} samples, need at least {min_len}", r.len()),
        ));
    }
    if let Some((i, v)) = r.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(TightError::new(field, format!("sample {i} must be finite, got {v}")));
    }
    Ok(())
}

fn check_dt(dt: f64) -> Result<f64, TightError> {
    if dt.is_finite() && dt > 0.0 {
        Ok(dt)
    } else {
        Err(TightError::new("dt", format!("sample period must be finite and > 0 s, got {dt}")))
    }
}

// ---------------------------------------------------------------------------
// Eq. 10
// ---------------------------------------------------------------------------

/// Pseudo-range increment difference, eq. 10:
/// ρD(ε) = [ρG(ε+1) − ρG(ε)] − [ρI(ε+1) − ρI(ε)], for ε = 0..N−1.
///
/// `rho_g` is the GNSS pseudo-range and `rho_i` the INS-predicted range of
/// the same satellite at the same epochs (metres). Differencing increments
/// removes the common range and most of the slowly varying errors, which is
/// what leaves a series worth analysing for chaos. Output length N − 1.
pub fn increment_difference(rho_g: &[f64], rho_i: &[f64]) -> Result<Vec<f64>, TightError> {
    if rho_g.len() != rho_i.len() {
        return Err(TightError::new(
            "rho_i",
            format!("length {} differs from rho_g length {}", rho_i.len(), rho_g.len()),
        ));
    }
    check_series("rho_g", rho_g, 2)?;
    check_series("rho_i", rho_i, 2)?;
    Ok(rho_g
        .iter()
        .zip(rho_g.iter().skip(1))
        .zip(rho_i.iter().zip(rho_i.iter().skip(1)))
        .map(|((g0, g1), (i0, i1))| (g1 - g0) - (i1 - i0))
        .collect())
}

// ---------------------------------------------------------------------------
// Mutual information (eq. 11)
// ---------------------------------------------------------------------------

/// Default β for [`mutual_information`] on a series of `n` samples:
/// ⌊√(n/5)⌋ clamped to [4, 200].
///
/// Why: the histogram estimate of E(τ) is biased upwards by about
/// (β − 1)²/(2(N − τ)) nats, and sparsely filled cells make that bias and
/// the scatter swamp the shallow minimum being looked for. Cellucci et al.
/// (2005) advise at most √(N/5) cells per axis, i.e. at least 5 expected
/// points per cell of the β×β grid for independent uniform marginals. The
/// paper's β ∈ [100, 200]
/// then corresponds to N ≈ 50 000–200 000 samples; for a few hundred samples
/// it gives 6–10 cells, where 100 cells would leave almost every cell with
/// zero or one point.
pub fn default_bins(n: usize) -> usize {
    let b = libm::floor(libm::sqrt(n as f64 / 5.0));
    // `as` saturates; the clamp keeps it in [4, 200].
    (b as usize).clamp(4, 200)
}

/// Cell index of `x` among `bins` equal cells spanning [lo, lo + span].
fn cell(x: f64, lo: f64, span: f64, bins: usize) -> usize {
    let c = libm::floor((x - lo) / span * bins as f64);
    if c <= 0.0 {
        0
    } else {
        (c as usize).min(bins - 1)
    }
}

/// Average mutual information E(τ) between r(t) and r(t + τ), eq. 11, in
/// nats: Σ_ab p_ab ln(p_ab / (p_a p_b)) over β×β equal cells spanning the
/// range [min r, max r] of the whole series (the same grid for A and B, as
/// in the paper). Probabilities are counts over the N − τ pairs.
///
/// E(τ) ≥ 0 (a Kullback–Leibler divergence between the empirical joint and
/// the product of its own marginals); a constant series gives 0. Any β ≥ 2
/// is accepted (see [`default_bins`] for why the paper's 100–200 is too many
/// for short series); β ≤ [`MAX_BINS`] bounds memory. Cost O(N + β²).
pub fn mutual_information(r: &[f64], tau: usize, bins: usize) -> Result<f64, TightError> {
    check_series("r", r, 2)?;
    if !(2..=MAX_BINS).contains(&bins) {
        return Err(TightError::new("bins", format!("β must be in 2..={MAX_BINS}, got {bins}")));
    }
    if tau == 0 || tau > r.len() - 2 {
        return Err(TightError::new(
            "tau",
            format!("delay must be in 1..={} samples for N = {}, got {tau}", r.len() - 2, r.len()),
        ));
    }
    let (lo, hi) = r.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| {
        (lo.min(x), hi.max(x))
    });
    let span = hi - lo;
    if !(span.is_finite() && span > 0.0) {
        // Constant series (or a range that overflows f64): no information.
        return Ok(0.0);
    }
    let n_pairs = r.len() - tau;
    let mut joint = vec![0u32; bins * bins];
    let mut pa = vec![0u32; bins];
    let mut pb = vec![0u32; bins];
    for (a, b) in r.iter().zip(r.iter().skip(tau)) {
        let ia = cell(*a, lo, span, bins);
        let ib = cell(*b, lo, span, bins);
        if let Some(c) = joint.get_mut(ia * bins + ib) {
            *c += 1;
        }
        if let Some(c) = pa.get_mut(ia) {
            *c += 1;
        }
        if let Some(c) = pb.get_mut(ib) {
            *c += 1;
        }
    }
    let n = n_pairs as f64;
    let mut e = 0.0;
    for (k, &c) in joint.iter().enumerate() {
        if c == 0 {
            continue;
        }
        let (ca, cb) = match (pa.get(k / bins), pb.get(k % bins)) {
            (Some(&ca), Some(&cb)) => (ca as f64, cb as f64),
            _ => continue,
        };
        let pab = c as f64 / n;
        // p_ab / (p_a p_b) = c·n / (ca·cb)
        e += pab * libm::log(c as f64 * n / (ca * cb));
    }
    Ok(e)
}

/// The delay chosen from the mutual-information curve.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DelayEstimate {
    /// Chosen delay, samples.
    pub tau: usize,
    /// E(τ) for τ = 1..=max_tau (`curve[k]` is E(k + 1)), nats.
    pub curve: Vec<f64>,
    /// True if `tau` is a genuine first local minimum; false if the curve
    /// decreased (or was flat) all the way and `tau` is its global minimum.
    pub found_minimum: bool,
}

/// Delay τ (samples) as the first local minimum of E(τ), τ = 1..=max_tau.
///
/// τ is a local minimum when E(τ) < E(τ − 1) and E(τ) ≤ E(τ + 1); for τ = 1
/// the left neighbour is E(0), the entropy of the binned series, which is
/// never below E(1), so τ = 1 qualifies as soon as E(2) ≥ E(1) (white noise).
/// τ = max_tau cannot be confirmed. Fallback when there is no local minimum
/// in range: the global minimum of the curve (first one on ties), with
/// `found_minimum = false` — the usual sign that `max_tau` is too small.
pub fn delay_by_mutual_information(
    r: &[f64],
    bins: usize,
    max_tau: usize,
) -> Result<DelayEstimate, TightError> {
    check_series("r", r, 4)?;
    if max_tau < 2 || max_tau > r.len() - 2 {
        return Err(TightError::new(
            "max_tau",
            format!("must be in 2..={} for N = {}, got {max_tau}", r.len() - 2, r.len()),
        ));
    }
    let mut curve = Vec::with_capacity(max_tau);
    for tau in 1..=max_tau {
        curve.push(mutual_information(r, tau, bins)?);
    }
    let first_min = curve.windows(2).enumerate().find_map(|(k, w)| {
        let (e, next) = (w.first().copied()?, w.get(1).copied()?);
        let prev_higher = k == 0 || curve.get(k - 1).is_some_and(|&p| e < p);
        (prev_higher && e <= next).then_some(k + 1)
    });
    let (tau, found_minimum) = match first_min {
        Some(t) => (t, true),
        None => {
            let mut best = 0;
            for (k, &e) in curve.iter().enumerate() {
                if curve.get(best).is_some_and(|&b| e < b) {
                    best = k;
                }
            }
            (best + 1, false)
        }
    };
    Ok(DelayEstimate { tau, curve, found_minimum })
}

// ---------------------------------------------------------------------------
// Phase-space reconstruction (eq. 16)
// ---------------------------------------------------------------------------

/// A delay embedding: row i is Y_i = (r_i, r_{i+τ}, …, r_{i+(m−1)τ}).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PhaseSpace {
    /// Embedding dimension.
    pub m: usize,
    /// Delay, samples.
    pub tau: usize,
    /// Number of phase points M = N − (m − 1)τ.
    pub rows: usize,
    /// Row-major M×m matrix, same units as the series.
    pub data: Vec<f64>,
}

impl PhaseSpace {
    /// Phase point i (length m); an empty slice if `i ≥ rows`.
    pub fn row(&self, i: usize) -> &[f64] {
        let start = i.saturating_mul(self.m);
        self.data.get(start..start.saturating_add(self.m)).unwrap_or(&[])
    }
}

/// Number of delay vectors N − (m − 1)τ, or `None` if the embedding window
/// (m − 1)τ + 1 does not fit in N samples.
fn n_vectors(n: usize, m: usize, tau: usize) -> Option<usize> {
    let window = (m.checked_sub(1)?).checked_mul(tau)?;
    n.checked_sub(window).filter(|&k| k > 0)
}

/// Phase-space reconstruction into the M×m matrix of eq. 16,
/// M = N − (m − 1)τ. Needs m ≥ 1, τ ≥ 1 and at least one full row.
pub fn embed(r: &[f64], m: usize, tau: usize) -> Result<PhaseSpace, TightError> {
    check_series("r", r, 1)?;
    if m == 0 {
        return Err(TightError::new("m", "embedding dimension must be ≥ 1, got 0"));
    }
    if tau == 0 {
        return Err(TightError::new("tau", "delay must be ≥ 1 sample, got 0"));
    }
    let rows = n_vectors(r.len(), m, tau).ok_or_else(|| {
        TightError::new(
            "m",
            format!("(m − 1)τ = ({m} − 1)·{tau} leaves no delay vector in {} samples", r.len()),
        )
    })?;
    let mut data = Vec::with_capacity(rows * m);
    for i in 0..rows {
        for k in 0..m {
            data.push(r.get(i + k * tau).copied().unwrap_or(f64::NAN));
        }
    }
    Ok(PhaseSpace { m, tau, rows, data })
}

// ---------------------------------------------------------------------------
// Nearest neighbours
// ---------------------------------------------------------------------------

/// Exact nearest-neighbour search over delay vectors of a scalar series.
///
/// Points are sorted by their first coordinate r_j; since |r_i − r_j| is a
/// lower bound of both the maximum and the Euclidean norm of Y_i − Y_j, a
/// scan outwards from i in that order can stop on each side as soon as the
/// first-coordinate gap reaches the best distance so far. Exact, no extra
/// dependency, and typically far below the O(M²) brute force.
struct Neighbours<'a> {
    r: &'a [f64],
    /// Sample indices 0..n sorted by value.
    order: Vec<usize>,
    /// `pos[j]` = position of index j in `order`.
    pos: Vec<usize>,
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Norm {
    Max,
    Euclid,
}

impl<'a> Neighbours<'a> {
    fn new(r: &'a [f64]) -> Self {
        let mut order: Vec<usize> = (0..r.len()).collect();
        order.sort_by(|&a, &b| {
            let (x, y) = (r.get(a).copied().unwrap_or(0.0), r.get(b).copied().unwrap_or(0.0));
            x.total_cmp(&y).then(a.cmp(&b))
        });
        let mut pos = vec![0; r.len()];
        for (p, &j) in order.iter().enumerate() {
            if let Some(slot) = pos.get_mut(j) {
                *slot = p;
            }
        }
        Neighbours { r, order, pos }
    }

    /// Distance between delay vectors i and j (dimension m, delay τ), with
    /// early exit once it exceeds `bound`. Callers keep i, j < N − (m−1)τ.
    fn dist(&self, i: usize, j: usize, m: usize, tau: usize, norm: Norm, bound: f64) -> f64 {
        let mut acc = 0.0f64;
        for k in 0..m {
            let (a, b) = match (self.r.get(i + k * tau), self.r.get(j + k * tau)) {
                (Some(a), Some(b)) => (*a, *b),
                _ => return f64::INFINITY,
            };
            let d = (a - b).abs();
            match norm {
                Norm::Max => {
                    acc = acc.max(d);
                    if acc > bound {
                        return acc;
                    }
                }
                Norm::Euclid => {
                    acc += d * d;
                    if acc > bound * bound {
                        return libm::sqrt(acc);
                    }
                }
            }
        }
        if norm == Norm::Euclid {
            libm::sqrt(acc)
        } else {
            acc
        }
    }

    /// Nearest delay vector j ≠ i with j < `limit`, `ok(j)` true and a
    /// strictly positive distance. Returns (j, distance).
    fn nearest(
        &self,
        i: usize,
        m: usize,
        tau: usize,
        norm: Norm,
        limit: usize,
        ok: impl Fn(usize) -> bool,
    ) -> Option<(usize, f64)> {
        let xi = *self.r.get(i)?;
        let p = *self.pos.get(i)?;
        let mut best: Option<(usize, f64)> = None;
        let mut bound = f64::INFINITY;
        let mut left = p.checked_sub(1);
        let mut right = p + 1;
        let mut left_open = left.is_some();
        let mut right_open = right < self.order.len();
        while left_open || right_open {
            for side in 0..2 {
                let (slot, open) = if side == 0 {
                    (left, &mut left_open)
                } else {
                    (Some(right), &mut right_open)
                };
                if !*open {
                    continue;
                }
                let Some(j) = slot.and_then(|s| self.order.get(s)).copied() else {
                    *open = false;
                    continue;
                };
                let gap = (self.r.get(j).copied().unwrap_or(f64::INFINITY) - xi).abs();
                if gap >= bound {
                    *open = false;
                    continue;
                }
                if j != i && j < limit && ok(j) {
                    let d = self.dist(i, j, m, tau, norm, bound);
                    if d > 0.0 && d < bound {
                        bound = d;
                        best = Some((j, d));
                    }
                }
                if side == 0 {
                    left = left.and_then(|l| l.checked_sub(1));
                    if left.is_none() {
                        left_open = false;
                    }
                } else {
                    right += 1;
                    if right >= self.order.len() {
                        right_open = false;
                    }
                }
            }
        }
        best
    }
}

// ---------------------------------------------------------------------------
// Cao's method
// ---------------------------------------------------------------------------

/// Cao's false-neighbour statistics for d = 1..=max_m.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CaoResult {
    /// E1(d) = E(d + 1)/E(d); `e1[k]` is E1(k + 1).
    pub e1: Vec<f64>,
    /// E2(d) = E*(d + 1)/E*(d); `e2[k]` is E2(k + 1). ≈ 1 for every d on
    /// an i.i.d. series, clearly ≠ 1 for some d on a deterministic one.
    pub e2: Vec<f64>,
    /// Minimum embedding dimension (see [`cao`]).
    pub dimension: usize,
}

/// Tolerance on |E1(d + 1) − E1(d)| for "E1 has stopped changing".
pub const CAO_E1_TOL: f64 = 0.05;
/// E1 must also be at least this close to 1 to count as saturated.
pub const CAO_E1_MIN: f64 = 0.9;

/// Cao (1997) embedding dimension.
///
/// For d = 1..=max_m + 1 and every i < N − dτ: n(i, d) is the nearest
/// neighbour of Y_i(d) among the Y_j(d), j < N − dτ, j ≠ i, and
/// a(i, d) = ‖Y_i(d+1) − Y_n(d+1)‖ / ‖Y_i(d) − Y_n(d)‖;
/// E(d) = mean a(i, d), E*(d) = mean |r_{i+dτ} − r_{n+dτ}|,
/// E1(d) = E(d+1)/E(d), E2(d) = E*(d+1)/E*(d).
///
/// Norm: the maximum norm, as in Cao's paper (Shen et al. write Euclidean).
/// With it a(i, d) ≥ 1 exactly and Y(d+1) distances follow from Y(d) ones
/// by one extra coordinate, and the ratio is not inflated by the √d growth
/// of Euclidean distances with dimension, which would keep E1 drifting above
/// 1 for long after the attractor is unfolded.
///
/// Zero distances (repeated points, e.g. quantised data): such neighbours
/// are skipped and the nearest neighbour at a strictly positive distance is
/// used instead, as Cao recommends; a point with no such neighbour is left
/// out of the means. No temporal (Theiler) exclusion, as in Cao and Shen.
///
/// `dimension`: the smallest d in 1..max_m with E1(d) ≥ [`CAO_E1_MIN`] and
/// |E1(d+1) − E1(d)| < [`CAO_E1_TOL`] — the first d at which adding a
/// coordinate no longer changes neighbour distances (Cao's "d0 + 1"); if
/// none, `max_m`. Cost about O(max_m² · N · k) with k the candidates the
/// sorted scan visits (O(max_m² · N²) worst case).
pub fn cao(r: &[f64], tau: usize, max_m: usize) -> Result<CaoResult, TightError> {
    check_series("r", r, 4)?;
    if tau == 0 {
        return Err(TightError::new("tau", "delay must be ≥ 1 sample, got 0"));
    }
    if max_m < 2 {
        return Err(TightError::new("max_m", format!("must be ≥ 2, got {max_m}")));
    }
    // E(d) up to d = max_m + 1 needs N − (max_m + 1)τ points; ask for 10.
    let need = (max_m + 1).checked_mul(tau).and_then(|w| w.checked_add(10));
    if need.is_none_or(|w| r.len() < w) {
        return Err(TightError::new(
            "r",
            format!(
                "series too short for max_m = {max_m}, τ = {tau}: {} samples, need (max_m + 1)τ + 10",
                r.len()
            ),
        ));
    }
    let nb = Neighbours::new(r);
    let mut e = Vec::with_capacity(max_m + 1);
    let mut e_star = Vec::with_capacity(max_m + 1);
    for d in 1..=max_m + 1 {
        let limit = r.len() - d * tau;
        let (mut sa, mut ss, mut count) = (0.0, 0.0, 0usize);
        for i in 0..limit {
            let Some((j, dd)) = nb.nearest(i, d, tau, Norm::Max, limit, |_| true) else {
                continue;
            };
            let (Some(xi), Some(xj)) = (r.get(i + d * tau), r.get(j + d * tau)) else {
                continue;
            };
            let extra = (xi - xj).abs();
            sa += dd.max(extra) / dd;
            ss += extra;
            count += 1;
        }
        if count == 0 {
            return Err(TightError::new(
                "r",
                format!("no point has a neighbour at non-zero distance in dimension {d}"),
            ));
        }
        e.push(sa / count as f64);
        e_star.push(ss / count as f64);
    }
    let ratio = |v: &[f64]| -> Vec<f64> {
        v.windows(2)
            .map(|w| match w {
                [a, b] if *a > 0.0 => b / a,
                // E* = 0 means every neighbour predicts the next value
                // exactly (e.g. a constant future): call the ratio 1.
                _ => 1.0,
            })
            .collect()
    };
    let e1 = ratio(&e);
    let e2 = ratio(&e_star);
    let dimension = e1
        .windows(2)
        .position(|w| matches!(w, [a, b] if *a >= CAO_E1_MIN && (b - a).abs() < CAO_E1_TOL))
        .map_or(max_m, |k| k + 1);
    Ok(CaoResult { e1, e2, dimension })
}

// ---------------------------------------------------------------------------
// Mean period (FFT)
// ---------------------------------------------------------------------------

/// In-place iterative radix-2 FFT; `re.len() == im.len()` a power of two.
fn fft(re: &mut [f64], im: &mut [f64]) {
    let n = re.len();
    if n < 2 || im.len() != n || !n.is_power_of_two() {
        return;
    }
    let bits = n.trailing_zeros();
    for i in 0..n {
        let j = i.reverse_bits() >> (usize::BITS - bits);
        if j > i {
            re.swap(i, j);
            im.swap(i, j);
        }
    }
    let mut len = 2;
    while len <= n {
        let ang = -2.0 * core::f64::consts::PI / len as f64;
        let half = len / 2;
        for start in (0..n).step_by(len) {
            for k in 0..half {
                let (wr, wi) = (libm::cos(ang * k as f64), libm::sin(ang * k as f64));
                let (a, b) = (start + k, start + k + half);
                let (xr, xi) = (re[b] * wr - im[b] * wi, re[b] * wi + im[b] * wr);
                re[b] = re[a] - xr;
                im[b] = im[a] - xi;
                re[a] += xr;
                im[a] += xi;
            }
        }
        len <<= 1;
    }
}

/// Average period in samples: 1 / f̄, where f̄ (cycles per sample) is the
/// power-weighted mean frequency of the spectrum, DC excluded — the mean
/// period Rosenstein et al. use as the temporal-separation window.
///
/// The mean is removed and a Hann window applied before a zero-padded
/// radix-2 FFT (next power of two ≥ N): without the window, spectral leakage
/// spreads power into far bins, and since the weights grow with frequency
/// that biases f̄ upwards by a few percent even for a pure sine. O(N log N)
/// time, O(N) memory; a few thousand samples take well under a millisecond.
pub fn mean_period(r: &[f64]) -> Result<f64, TightError> {
    check_series("r", r, 4)?;
    let n = r.len();
    let nfft = n.checked_next_power_of_two().ok_or_else(|| {
        TightError::new("r", format!("series of {n} samples too long for the FFT"))
    })?;
    let mean = r.iter().sum::<f64>() / n as f64;
    let mut re = vec![0.0; nfft];
    let mut im = vec![0.0; nfft];
    for (k, (slot, &x)) in re.iter_mut().zip(r).enumerate() {
        let w = 0.5 - 0.5 * libm::cos(2.0 * core::f64::consts::PI * k as f64 / (n - 1) as f64);
        *slot = (x - mean) * w;
    }
    fft(&mut re, &mut im);
    let (mut num, mut den) = (0.0, 0.0);
    for k in 1..=nfft / 2 {
        let p = re[k] * re[k] + im[k] * im[k];
        num += p * k as f64 / nfft as f64;
        den += p;
    }
    if !(den.is_finite() && den > 0.0 && num > 0.0) {
        return Err(TightError::new("r", "series is constant: no period"));
    }
    Ok(den / num)
}

// ---------------------------------------------------------------------------
// Largest Lyapunov exponent (Rosenstein et al. 1993)
// ---------------------------------------------------------------------------

/// Result of [`largest_lyapunov`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LyapunovResult {
    /// Largest Lyapunov exponent, per second (per iteration when dt = 1).
    pub exponent: f64,
    /// y(i) = ⟨ln d_j(i)⟩ / dt for i = 0..steps (ln of the series' units,
    /// per second); the exponent is its least-squares slope per step over
    /// the fit range.
    pub curve: Vec<f64>,
    /// FFT mean period used as the temporal-separation window, samples.
    pub mean_period: f64,
    /// Number of reference points that found a neighbour.
    pub pairs: usize,
    /// Indices of `curve` used for the fit.
    pub fit: Range<usize>,
}

/// Largest Lyapunov exponent with the fit over the whole curve, i = 0..steps.
///
/// The caller chooses `steps` to cover the linear (exponential-divergence)
/// region, which ends when separations reach the attractor size; see
/// [`largest_lyapunov_fit`] for a separate fit window.
pub fn largest_lyapunov(
    r: &[f64],
    m: usize,
    tau: usize,
    dt: f64,
    steps: usize,
) -> Result<LyapunovResult, TightError> {
    largest_lyapunov_fit(r, m, tau, dt, steps, 0..steps)
}

/// Rosenstein et al. (1993), as in Shen et al. §2.2.3.
///
/// 1. P = [`mean_period`] (samples).
/// 2. Y = [`embed`]`(r, m, tau)`, M rows.
/// 3. For every j < M − steps + 1, the nearest (Euclidean) Y_ĵ with
///    |j − ĵ| > P and ĵ < M − steps + 1, at non-zero distance. Restricting
///    both to points with `steps` of future keeps the same pair set for every
///    i, so the curve is not bent by pairs dropping out.
/// 4. d_j(i) = ‖Y_{j+i} − Y_{ĵ+i}‖ for i = 0..steps.
/// 5. y(i) = ⟨ln d_j(i)⟩ / dt over the non-zero d_j(i), and the exponent is
///    the least-squares slope of y over `fit` (indices into 0..steps, at
///    least two), per second.
pub fn largest_lyapunov_fit(
    r: &[f64],
    m: usize,
    tau: usize,
    dt: f64,
    steps: usize,
    fit: Range<usize>,
) -> Result<LyapunovResult, TightError> {
    check_dt(dt)?;
    if steps < 2 {
        return Err(TightError::new("steps", format!("must be ≥ 2, got {steps}")));
    }
    if fit.end > steps || fit.end < fit.start.saturating_add(2) {
        return Err(TightError::new(
            "fit",
            format!("must hold at least two indices within 0..{steps}, got {fit:?}"),
        ));
    }
    let ps = embed(r, m, tau)?;
    let period = mean_period(r)?;
    let window = libm::ceil(period);
    let limit = ps.rows.checked_sub(steps - 1).filter(|&l| (l as f64) > window + 1.0).ok_or_else(
        || {
            TightError::new(
                "steps",
                format!(
                    "{steps} steps leave too few of the {} phase points for a temporal \
                     separation of {window} samples",
                    ps.rows
                ),
            )
        },
    )?;
    let nb = Neighbours::new(r);
    let mut pairs = Vec::new();
    for j in 0..limit {
        let far = |k: usize| (k.abs_diff(j) as f64) > window;
        if let Some((k, _)) = nb.nearest(j, m, tau, Norm::Euclid, limit, far) {
            pairs.push((j, k));
        }
    }
    if pairs.is_empty() {
        return Err(TightError::new("r", "no neighbour pair found beyond the mean period"));
    }
    let mut curve = Vec::with_capacity(steps);
    for i in 0..steps {
        let (mut s, mut q) = (0.0, 0usize);
        for &(j, k) in &pairs {
            let d = nb.dist(j + i, k + i, m, tau, Norm::Euclid, f64::INFINITY);
            if d > 0.0 && d.is_finite() {
                s += libm::log(d);
                q += 1;
            }
        }
        curve.push(if q > 0 { s / q as f64 / dt } else { f64::NAN });
    }
    let exponent = slope(&curve, fit.clone()).ok_or_else(|| {
        TightError::new("fit", format!("no finite points to fit in {fit:?}"))
    })?;
    Ok(LyapunovResult { exponent, curve, mean_period: period, pairs: pairs.len(), fit })
}

/// Least-squares slope of y against its index over `range` (finite y only).
fn slope(y: &[f64], range: Range<usize>) -> Option<f64> {
    let pts: Vec<(f64, f64)> = y
        .get(range.clone())?
        .iter()
        .zip(range)
        .filter(|(v, _)| v.is_finite())
        .map(|(v, i)| (i as f64, *v))
        .collect();
    if pts.len() < 2 {
        return None;
    }
    let n = pts.len() as f64;
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / n;
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

// ---------------------------------------------------------------------------
// Whole pipeline and Table 1
// ---------------------------------------------------------------------------

/// Options for [`analyze`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ChaosOptions {
    /// β for mutual information; `None` → [`default_bins`]`(N)`.
    pub bins: Option<usize>,
    /// Largest delay tried, samples.
    pub max_tau: usize,
    /// Largest embedding dimension tried by Cao's method.
    pub max_m: usize,
    /// Rosenstein divergence curve length, samples.
    pub lyapunov_steps: usize,
    /// Fit window within 0..lyapunov_steps; `None` → the whole curve.
    pub lyapunov_fit: Option<Range<usize>>,
}

impl Default for ChaosOptions {
    /// Sized for the paper's 1 Hz pseudo-range series (τ ≈ 5–10 s,
    /// m ≈ 9–11 in Table 1).
    fn default() -> Self {
        ChaosOptions { bins: None, max_tau: 30, max_m: 12, lyapunov_steps: 10, lyapunov_fit: None }
    }
}

/// Chaos indices of one series (a row of Table 1 and the curves behind it).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ChaosIndices {
    /// Delay, samples (first minimum of mutual information).
    pub tau: usize,
    /// Whether `tau` is a true local minimum (see [`DelayEstimate`]).
    pub tau_found_minimum: bool,
    /// Embedding dimension (Cao).
    pub m: usize,
    /// Largest Lyapunov exponent, per second.
    pub lyapunov: f64,
    /// FFT mean period, samples.
    pub mean_period: f64,
    /// β used for the mutual information.
    pub bins: usize,
    /// E(τ), τ = 1..=max_tau, nats.
    pub mutual_information: Vec<f64>,
    /// Cao E1(d), d = 1..=max_m.
    pub e1: Vec<f64>,
    /// Cao E2(d), d = 1..=max_m.
    pub e2: Vec<f64>,
    /// Rosenstein curve ⟨ln d(i)⟩ / dt.
    pub lyapunov_curve: Vec<f64>,
}

/// τ by mutual information, m by Cao, λ_max by Rosenstein, for a series
/// sampled every `dt` seconds.
pub fn analyze(r: &[f64], dt: f64, opts: &ChaosOptions) -> Result<ChaosIndices, TightError> {
    check_dt(dt)?;
    check_series("r", r, 4)?;
    let bins = opts.bins.unwrap_or_else(|| default_bins(r.len()));
    let delay = delay_by_mutual_information(r, bins, opts.max_tau)?;
    let c = cao(r, delay.tau, opts.max_m)?;
    let fit = opts.lyapunov_fit.clone().unwrap_or(0..opts.lyapunov_steps);
    let ly = largest_lyapunov_fit(r, c.dimension, delay.tau, dt, opts.lyapunov_steps, fit)
        .map_err(|mut e| {
            // Name the option the caller actually set.
            if e.field == "steps" || e.field == "fit" {
                e.field = format!("lyapunov_{}", e.field);
            }
            e
        })?;
    Ok(ChaosIndices {
        tau: delay.tau,
        tau_found_minimum: delay.found_minimum,
        m: c.dimension,
        lyapunov: ly.exponent,
        mean_period: ly.mean_period,
        bins,
        mutual_information: delay.curve,
        e1: c.e1,
        e2: c.e2,
        lyapunov_curve: ly.curve,
    })
}

/// Markdown table in the layout of the paper's Table 1: satellite, τ
/// (samples; seconds at the paper's 1 Hz), m, largest Lyapunov exponent
/// (per second, four decimals). `|` in names is escaped.
pub fn table1_markdown(rows: &[(String, ChaosIndices)]) -> String {
    let mut s = String::from(
        "| Satellite | τ | m | Largest Lyapunov exponent | Cao E2 (min–max over d) |\n|---|---:|---:|---:|---:|\n",
    );
    for (name, c) in rows {
        // E2 stays near 1 at every d for a stochastic series (Cao 1997): the
        // check that a positive exponent alone cannot make.
        let lo = c.e2.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = c.e2.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        s.push_str(&format!(
            "| {} | {} | {} | {:.4} | {:.2}–{:.2} |\n",
            name.replace('|', "\\|"),
            c.tau,
            c.m,
            c.lyapunov,
            lo,
            hi
        ));
    }
    s
}

#[cfg(all(test, not(target_arch = "wasm32")))]
mod tests {
    use super::*;
    use crate::rng::Rng;
    use approx::assert_relative_eq;

    fn henon(n: usize) -> Vec<f64> {
        let (mut x, mut y) = (0.1, 0.0);
        let mut out = Vec::with_capacity(n);
        for k in 0..n + 100 {
            let xn = 1.0 - 1.4 * x * x + y;
            y = 0.3 * x;
            x = xn;
            if k >= 100 {
                out.push(x);
            }
        }
        out
    }

    /// Lorenz x sampled every `every` RK4 steps of 0.01 s after 20 s.
    fn lorenz(n: usize, every: usize) -> Vec<f64> {
        let f = |s: [f64; 3]| {
            [10.0 * (s[1] - s[0]), s[0] * (28.0 - s[2]) - s[1], s[0] * s[1] - 8.0 / 3.0 * s[2]]
        };
        let h = 0.01;
        let mut s = [1.0, 1.0, 1.0];
        let mut out = Vec::with_capacity(n);
        let mut k = 0usize;
        while out.len() < n {
            let k1 = f(s);
            let a = |v: [f64; 3], c: f64| [s[0] + c * v[0], s[1] + c * v[1], s[2] + c * v[2]];
            let k2 = f(a(k1, h / 2.0));
            let k3 = f(a(k2, h / 2.0));
            let k4 = f(a(k3, h));
            for d in 0..3 {
                s[d] += h / 6.0 * (k1[d] + 2.0 * k2[d] + 2.0 * k3[d] + k4[d]);
            }
            k += 1;
            if k >= 2000 && k.is_multiple_of(every) {
                out.push(s[0]);
            }
        }
        out
    }

    fn sine(n: usize, period: f64) -> Vec<f64> {
        (0..n).map(|k| (2.0 * core::f64::consts::PI * k as f64 / period).sin()).collect()
    }

    fn field(e: TightError) -> String {
        e.field
    }

    #[test]
    fn increment_difference_hand_numbers_and_errors() {
        let g = [10.0, 13.0, 19.0, 20.0];
        let i = [0.0, 2.0, 5.0, 9.0];
        let d = increment_difference(&g, &i).unwrap();
        assert_eq!(d.len(), 3);
        for (a, b) in d.iter().zip([1.0, 3.0, -3.0]) {
            assert_relative_eq!(*a, b);
        }
        assert_eq!(field(increment_difference(&g, &i[..3]).unwrap_err()), "rho_i");
        assert_eq!(field(increment_difference(&[1.0], &[1.0]).unwrap_err()), "rho_g");
        let e = increment_difference(&g, &[0.0, f64::NAN, 1.0, 2.0]).unwrap_err();
        assert_eq!(e.field, "rho_i");
        assert!(e.message.contains("sample 1"), "{}", e.message);
    }

    #[test]
    fn mutual_information_hand_values_and_errors() {
        // Period-2 square wave: r(t + τ) determines r(t) exactly, two
        // equiprobable states (an even number N − τ of pairs) → E = ln 2.
        let sq: Vec<f64> = (0..104).map(|k| (k % 2) as f64).collect();
        assert_relative_eq!(mutual_information(&sq[..101], 1, 2).unwrap(), 2f64.ln(), epsilon = 1e-12);
        assert_relative_eq!(mutual_information(&sq, 4, 8).unwrap(), 2f64.ln(), epsilon = 1e-12);
        // Constant: nothing to learn.
        assert_eq!(mutual_information(&[3.0; 50], 2, 10).unwrap(), 0.0);
        // Sine: a quarter period decorrelates; τ = 1 nearly copies.
        let s = sine(2000, 40.0);
        let e1 = mutual_information(&s, 1, 16).unwrap();
        let e10 = mutual_information(&s, 10, 16).unwrap();
        assert!(e10 < 0.8 * e1, "E(1) = {e1}, E(10) = {e10}");
        // The delay ellipse is widest (a circle) near a quarter period. With
        // equal-width cells E(τ) is a flat plateau (±0.3 %) for τ ≈ 6–14 at
        // period 40, so the first minimum lands somewhere on it (measured 6).
        let d = delay_by_mutual_information(&s, 16, 20).unwrap();
        assert!(d.found_minimum && (5..=15).contains(&d.tau), "{d:?}");
        assert_eq!(field(mutual_information(&s, 1, 1).unwrap_err()), "bins");
        assert_eq!(field(mutual_information(&s, 1, MAX_BINS + 1).unwrap_err()), "bins");
        assert_eq!(field(mutual_information(&s, 0, 16).unwrap_err()), "tau");
        assert_eq!(field(mutual_information(&s, 1999, 16).unwrap_err()), "tau");
        assert_eq!(field(mutual_information(&[1.0, f64::INFINITY, 2.0], 1, 2).unwrap_err()), "r");
    }

    #[test]
    fn default_bins_scales_and_clamps() {
        assert_eq!(default_bins(10), 4);
        assert_eq!(default_bins(500), 10);
        assert_eq!(default_bins(5000), 31);
        assert_eq!(default_bins(1_000_000), 200);
    }

    #[test]
    fn embed_rows_and_errors() {
        let r: Vec<f64> = (0..10).map(|k| k as f64).collect();
        let ps = embed(&r, 3, 2).unwrap();
        assert_eq!(ps.rows, 6);
        assert_eq!(ps.row(0), &[0.0, 2.0, 4.0]);
        assert_eq!(ps.row(5), &[5.0, 7.0, 9.0]);
        assert!(ps.row(6).is_empty());
        assert!(ps.row(usize::MAX).is_empty());
        let back: PhaseSpace = serde_json::from_str(&serde_json::to_string(&ps).unwrap()).unwrap();
        assert_eq!(back, ps);
        assert_eq!(field(embed(&r, 0, 1).unwrap_err()), "m");
        assert_eq!(field(embed(&r, 2, 0).unwrap_err()), "tau");
        assert_eq!(field(embed(&r, 6, 2).unwrap_err()), "m");
        assert_eq!(field(embed(&r, 2, usize::MAX).unwrap_err()), "m");
        assert_eq!(field(embed(&[], 1, 1).unwrap_err()), "r");
    }

    #[test]
    fn fft_matches_direct_dft() {
        let mut rng = Rng::new(3);
        let x: Vec<f64> = (0..16).map(|_| rng.normal()).collect();
        let (mut re, mut im) = (x.clone(), vec![0.0; 16]);
        fft(&mut re, &mut im);
        for k in 0..16 {
            let (mut a, mut b) = (0.0, 0.0);
            for (t, v) in x.iter().enumerate() {
                let w = -2.0 * core::f64::consts::PI * (k * t) as f64 / 16.0;
                a += v * w.cos();
                b += v * w.sin();
            }
            assert_relative_eq!(re[k], a, epsilon = 1e-12);
            assert_relative_eq!(im[k], b, epsilon = 1e-12);
        }
    }

    #[test]
    fn henon_lyapunov_and_dimension() {
        let x = henon(2500);
        // ln d(i) is linear for ~10 iterations before saturating at the
        // attractor size (d(0) ≈ e^-6); fit the first 8.
        let ly = largest_lyapunov_fit(&x, 2, 1, 1.0, 12, 0..8).unwrap();
        println!("Hénon λ = {:.4} /iter, P = {:.2}", ly.exponent, ly.mean_period);
        assert_relative_eq!(ly.exponent, 0.419, epsilon = 0.06);
        let c = cao(&x, 1, 6).unwrap();
        println!("Hénon Cao {c:?}");
        assert_eq!(c.dimension, 2);
    }

    #[test]
    fn lorenz_delay_dimension_lyapunov() {
        let dt = 0.01;
        let x = lorenz(10_000, 1);
        let d = delay_by_mutual_information(&x, default_bins(x.len()), 40).unwrap();
        println!("Lorenz τ = {} samples ({} s), minimum found {}", d.tau, d.tau as f64 * dt, d.found_minimum);
        assert!(d.found_minimum);
        assert!((12..=20).contains(&d.tau), "τ = {}", d.tau);
        assert_eq!(d.curve.len(), 40);
        // Too short a search: no minimum, fallback to the global one (last).
        let short = delay_by_mutual_information(&x, default_bins(x.len()), 6).unwrap();
        assert!(!short.found_minimum);
        assert_eq!(short.tau, 6);

        let c = cao(&x, d.tau, 8).unwrap();
        println!("Lorenz Cao dimension {} E1 {:.3?} E2 {:.3?}", c.dimension, c.e1, c.e2);
        assert!((2..=5).contains(&c.dimension), "m = {}", c.dimension);
        assert!(c.e2[0] < 0.5 && c.e2[1] < 0.9, "E2 = {:?}", c.e2);

        // Linear region: after a ~0.5 s transient (neighbour separations
        // aligning with the unstable direction, local slope ≈ 1.8/s) and
        // before saturation near 3.5 s. Fit 0.5–2.5 s.
        let ly = largest_lyapunov_fit(&x, 3, d.tau, dt, 300, 50..250).unwrap();
        println!("Lorenz λ = {:.4} /s, P = {:.1} samples, {} pairs", ly.exponent, ly.mean_period, ly.pairs);
        assert_relative_eq!(ly.exponent, 0.906, epsilon = 0.2);
        let early = slope(&ly.curve, 0..50).unwrap();
        println!("Lorenz slope over 0–0.5 s = {early:.3} /s");
    }

    #[test]
    fn sine_period_and_zero_exponent() {
        let s = sine(2000, 37.3);
        let p = mean_period(&s).unwrap();
        println!("sine P = {p:.4} samples (true 37.3)");
        assert_relative_eq!(p, 37.3, max_relative = 0.02);
        let ly = largest_lyapunov(&s, 2, 9, 1.0, 30).unwrap();
        println!("sine λ = {:.5} per sample", ly.exponent);
        // Hénon gives 0.42 per sample on the same scale.
        assert!(ly.exponent.abs() < 0.02, "λ = {}", ly.exponent);
        assert_eq!(field(mean_period(&[2.0; 16]).unwrap_err()), "r");
    }

    #[test]
    fn white_noise_cao_e2_is_one() {
        let mut rng = Rng::new(7);
        let w: Vec<f64> = (0..2000).map(|_| rng.normal()).collect();
        let c = cao(&w, 1, 8).unwrap();
        println!("noise Cao E1 {:.3?} E2 {:.3?}", c.e1, c.e2);
        for (k, e2) in c.e2.iter().enumerate() {
            assert_relative_eq!(*e2, 1.0, epsilon = 0.1);
            assert!(k < 8);
        }
        // E1 keeps climbing instead of saturating: no dimension found.
        assert_eq!(c.dimension, 8);
    }

    #[test]
    fn cao_skips_zero_distances() {
        // Quantised series with many exact repeats must still work.
        let x: Vec<f64> = henon(1500).iter().map(|v| (v * 20.0).round() / 20.0).collect();
        let c = cao(&x, 1, 4).unwrap();
        assert!(c.e1.iter().chain(&c.e2).all(|v| v.is_finite() && *v > 0.0), "{c:?}");
        assert_eq!(field(cao(&x, 0, 4).unwrap_err()), "tau");
        assert_eq!(field(cao(&x, 1, 1).unwrap_err()), "max_m");
        assert_eq!(field(cao(&x[..20], 5, 4).unwrap_err()), "r");
    }

    #[test]
    fn lyapunov_parameter_errors() {
        let x = henon(300);
        assert_eq!(field(largest_lyapunov(&x, 2, 1, 0.0, 10).unwrap_err()), "dt");
        assert_eq!(field(largest_lyapunov(&x, 2, 1, f64::NAN, 10).unwrap_err()), "dt");
        assert_eq!(field(largest_lyapunov(&x, 2, 1, 1.0, 1).unwrap_err()), "steps");
        assert_eq!(field(largest_lyapunov(&x, 2, 1, 1.0, 400).unwrap_err()), "steps");
        assert_eq!(field(largest_lyapunov_fit(&x, 2, 1, 1.0, 10, 3..4).unwrap_err()), "fit");
        assert_eq!(field(largest_lyapunov_fit(&x, 2, 1, 1.0, 10, 5..11).unwrap_err()), "fit");
        assert_eq!(field(largest_lyapunov(&x, 0, 1, 1.0, 10).unwrap_err()), "m");
    }

    #[test]
    fn analyze_and_table1() {
        let x = lorenz(4000, 2); // 80 s at 0.02 s
        let opts = ChaosOptions {
            max_tau: 30,
            max_m: 8,
            lyapunov_steps: 150,
            lyapunov_fit: Some(25..125),
            ..ChaosOptions::default()
        };
        let c = analyze(&x, 0.02, &opts).unwrap();
        println!("analyze Lorenz: τ {} m {} λ {:.4} P {:.1} β {}", c.tau, c.m, c.lyapunov, c.mean_period, c.bins);
        assert!((6..=10).contains(&c.tau), "τ = {}", c.tau);
        assert!((2..=5).contains(&c.m), "m = {}", c.m);
        assert_relative_eq!(c.lyapunov, 0.906, epsilon = 0.25);
        assert_eq!((c.e1.len(), c.e2.len(), c.lyapunov_curve.len()), (8, 8, 150));
        let t = table1_markdown(&[("G8".into(), c.clone()), ("a|b".into(), c.clone())]);
        let lines: Vec<&str> = t.lines().collect();
        assert_eq!(lines.len(), 4);
        let (lo, hi) = (c.e2.iter().copied().fold(f64::INFINITY, f64::min), c.e2.iter().copied().fold(f64::NEG_INFINITY, f64::max));
        assert_eq!(lines[2], format!("| G8 | {} | {} | {:.4} | {lo:.2}–{hi:.2} |", c.tau, c.m, c.lyapunov));
        assert!(lines[3].starts_with("| a\\|b |"));
        assert_eq!(field(analyze(&x, -1.0, &opts).unwrap_err()), "dt");
        let bad = ChaosOptions { lyapunov_fit: Some(0..151), ..opts.clone() };
        assert_eq!(field(analyze(&x, 0.02, &bad).unwrap_err()), "lyapunov_fit");
    }

    proptest::proptest! {
        #[test]
        fn mi_nonnegative_and_embed_layout(
            // Longer than the widest embedding, (m − 1)τ = 12: a shorter
            // series leaves no delay vector and `embed` rightly refuses it.
            r in proptest::collection::vec(-1e3f64..1e3, 13..200),
            tau in 1usize..5,
            m in 1usize..5,
            bins in 2usize..40,
        ) {
            let e = mutual_information(&r, tau, bins).unwrap();
            proptest::prop_assert!(e >= -1e-12, "E = {}", e);
            let ps = embed(&r, m, tau).unwrap();
            proptest::prop_assert_eq!(ps.rows, r.len() - (m - 1) * tau);
            for i in 0..ps.rows {
                for k in 0..m {
                    proptest::prop_assert_eq!(ps.row(i)[k], r[i + k * tau]);
                }
            }
        }
    }
}
