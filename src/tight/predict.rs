//! Reconstruction of a faulty pseudo-range from a predictor (Shen et al.
//! 2022, eq. 12): the [`RangePredictor`] interface the reconfigurator calls,
//! the filter's own prediction ([`FilterPredictor`]), and the
//! [`Reconstruction`] both it and the GAN monitor return.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

/// Reconstructed pseudo-range.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Reconstruction {
    /// Pseudo-range, m.
    pub pr: f64,
    /// Its error variance, m².
    pub variance: f64,
}

/// Predictor of a satellite's pseudo-range, used to reconstruct a faulty
/// measurement. The GAN generator of the next issue implements this trait.
pub trait RangePredictor {
    /// A measurement accepted as fault-free at time `t` (s): the measured
    /// pseudo-range and the filter's predicted one (INS position + clock), m.
    fn observe(&mut self, t: f64, prn: u8, measured: f64, predicted: f64);
    /// Pseudo-range of `prn` at time `t`, given the filter's predicted
    /// pseudo-range now; `None` when it cannot predict (then isolate).
    fn reconstruct(&mut self, t: f64, prn: u8, predicted: f64) -> Option<Reconstruction>;
    /// Short name for reports.
    fn name(&self) -> &'static str;
}

/// The filter's own prediction, in the form of the paper's eq. 12 with a zero
/// generated increment difference: `ρ̂_G(k) = ρ_G(k0) + [ρ_I(k) − ρ_I(k0)]`,
/// i.e. the filter-predicted pseudo-range now plus the (smoothed) offset
/// between measurement and prediction while the satellite was healthy.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FilterPredictor {
    /// Weight of the newest offset in its exponential average (0, 1].
    pub smoothing: f64,
    /// Variance at age 0, m².
    pub base_variance: f64,
    /// Growth of the standard deviation with the age of the last healthy
    /// measurement, m/s (an unmodelled increment difference).
    pub sigma_rate: f64,
    /// Refuse to predict from history older than this, s.
    pub max_age: f64,
    /// prn -> (time of last healthy measurement, smoothed offset m).
    history: BTreeMap<u8, (f64, f64)>,
}

impl FilterPredictor {
    /// A predictor with variance `base_variance` (m²) at age 0 and the default smoothing, growth and age limit.
    pub fn new(base_variance: f64) -> Self {
        FilterPredictor { smoothing: 0.2, base_variance, sigma_rate: 0.5, max_age: 120.0, history: BTreeMap::new() }
    }
}

impl RangePredictor for FilterPredictor {
    fn observe(&mut self, t: f64, prn: u8, measured: f64, predicted: f64) {
        let off = measured - predicted;
        let a = self.smoothing;
        let e = self.history.entry(prn).or_insert((t, off));
        *e = (t, (1.0 - a) * e.1 + a * off);
    }
    fn reconstruct(&mut self, t: f64, prn: u8, predicted: f64) -> Option<Reconstruction> {
        let &(t0, off) = self.history.get(&prn)?;
        let age = t - t0;
        if !(age >= 0.0 && age <= self.max_age) {
            return None;
        }
        let s = self.sigma_rate * age;
        Some(Reconstruction { pr: predicted + off, variance: self.base_variance + s * s })
    }
    fn name(&self) -> &'static str {
        "filter-prediction"
    }
}

