//! A stuck sensor: the same reading, bit for bit, for longer than its own
//! noise allows.
//!
//! A barometer that stops updating keeps reporting its last altitude. In a
//! climb the consistency tests see it (`indicators`, the baro–filter test),
//! but slowly: they need the climb to carry the truth metres away from the
//! held value, and in a hover they never do (battery tune: 21 stuck baros,
//! 26.9% of their epochs flagged, first flag after a median 8.6 s). The
//! reading itself says it sooner. A live sensor's noise changes its value at
//! almost every sample; a repeat happens only when the noise is below its
//! quantisation or when the logger writes a sample twice. How often that
//! happens is learnt on this flight: `p`, the share of samples that repeat
//! the previous one, over the runs that ended without a verdict, with a
//! Laplace prior (`(k + 1) / (n + 2)`, so 1/2 before anything is learnt).
//! A run of `r` repeats then has probability `p^r` under a live sensor,
//! and the statistic is that probability as a normal z-score,
//! `z = sqrt(2 r ln(1/p))` (`-ln P(|Z| > z) ≈ z²/2`). It is called at `Z`,
//! a probability of 10⁻⁶, and only once the run spans `MIN_S`: repeats
//! come in bursts on some loggers, and ArduPilot's own baro driver calls a
//! sensor stuck after 2 s without a change (`BARO_DATA_CHANGE_TIMEOUT_MS`).
//!
//! The real logs: ArduPilot's `BARO.Alt` repeats at 0.5–1% of its samples,
//! never twice in a row; PX4's `vehicle_air_data` at 1.4–4.8%, at most
//! twice; old PX4 logs that copy the baro into every 250 Hz
//! `sensor_combined` row repeat 74% of their samples, 12 in a row (50 ms):
//! `p` learns each.
use navguard_logs::decimal::Shortest;
use serde::{Deserialize, Serialize};

/// The call: a run this unlikely under the learnt repeat share, as a
/// z-score (`sqrt(2 ln 10⁶)`, a probability of 10⁻⁶).
pub const Z: f64 = 5.256_521_769_756_932;
/// Shortest run that is judged, s.
const MIN_S: f64 = 1.0;
/// Horizon of the learnt share, samples: the counts are scaled down to it.
const HORIZON: f64 = 2000.0;

/// See the module docs. Times in s.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Flatline {
    /// The last reading (NaN before the first).
    last: f64,
    /// Time of the run's first sample and of its latest repeat, s.
    t0: f64,
    t1: f64,
    /// Repeats in the current run.
    run: u32,
    /// The current run reached `Z`: it is not learnt when it ends.
    called: bool,
    /// Learnt counts: repeats, and samples after a first.
    k: f64,
    n: f64,
}

impl Default for Flatline {
    fn default() -> Self {
        Flatline {
            last: f64::NAN,
            t0: f64::NAN,
            t1: f64::NAN,
            run: 0,
            called: false,
            k: 0.0,
            n: 0.0,
        }
    }
}

impl Flatline {
    /// A reading `x` at `t`. Non-finite readings restart the run unlearnt.
    /// Returns whether this reading ended a run that was called stuck: the
    /// sensor is live again.
    pub fn push(&mut self, t: f64, x: f64) -> bool {
        if x.is_finite() && x.to_bits() == self.last.to_bits() {
            self.run = self.run.saturating_add(1);
            self.t1 = t;
            if self.z() >= Z {
                self.called = true;
            }
            return false;
        }
        let revived = self.called;
        if self.last.is_finite() && x.is_finite() && !self.called {
            // The run ended with a change: `run` repeats, then one change.
            self.k += f64::from(self.run);
            self.n += f64::from(self.run) + 1.0;
            if self.n > HORIZON {
                let s = HORIZON / self.n;
                self.k *= s;
                self.n = HORIZON;
            }
        }
        self.last = if x.is_finite() { x } else { f64::NAN };
        self.t0 = t;
        self.t1 = t;
        self.run = 0;
        self.called = false;
        revived
    }

    /// The learnt share of samples that repeat the previous one.
    pub fn share(&self) -> f64 {
        (self.k + 1.0) / (self.n + 2.0)
    }

    /// The current run as a z-score (0 below `MIN_S`).
    pub fn z(&self) -> f64 {
        if self.run == 0 || !(self.t1 - self.t0 >= MIN_S) {
            return 0.0;
        }
        // libm's log: the same bits natively and in wasm.
        libm::sqrt(2.0 * f64::from(self.run) * libm::log(1.0 / self.share()))
    }

    /// The current run has been called stuck.
    pub fn stuck(&self) -> bool {
        self.called
    }

    /// Time of the current run's first sample, s (NaN before any).
    pub fn run_start(&self) -> f64 {
        self.t0
    }

    /// Forget the reading (a data gap, a filter restart): the next one
    /// starts a run; the learnt share stays.
    pub fn restart(&mut self) {
        let (k, n) = (self.k, self.n);
        *self = Flatline {
            k,
            n,
            ..Flatline::default()
        };
    }

    /// A restored state is usable: counts finite, `0 ≤ k ≤ n ≤ HORIZON`.
    #[cfg_attr(navguard_cold_size, optimize(size))]
    #[inline(never)]
    pub fn check(&self) -> Result<(), String> {
        if self.k.is_finite()
            && self.n.is_finite()
            && 0.0 <= self.k
            && self.k <= self.n
            && self.n <= HORIZON
        {
            Ok(())
        } else {
            Err(format!("baro flatline: counts k {} n {} out of range", Shortest(self.k), Shortest(self.n)))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    /// `secs` s of a live sensor at `hz`, quantised to `q` with noise `sd`.
    fn live(f: &mut Flatline, rng: &mut Rng, t0: f64, secs: f64, hz: f64, sd: f64, q: f64) -> f64 {
        let n = (secs * hz) as usize;
        let mut zmax: f64 = 0.0;
        for i in 0..n {
            let x = (100.0 + sd * rng.normal()) / q;
            f.push(t0 + i as f64 / hz, x.round() * q);
            zmax = zmax.max(f.z());
        }
        zmax
    }

    #[test]
    fn a_held_reading_is_called_after_min_s_and_a_live_one_never() {
        let (mut f, mut rng) = (Flatline::default(), Rng::new(1));
        // 10 Hz, 0.1 m noise at 1 cm steps: repeats at about 4%.
        let zmax = live(&mut f, &mut rng, 0.0, 120.0, 10.0, 0.1, 0.01);
        assert!(zmax < 2.0, "live z reached {zmax}");
        assert!(f.share() > 0.01 && f.share() < 0.08, "share {}", f.share());
        let mut called_at = None;
        for i in 0..50 {
            let t = 120.0 + f64::from(i) * 0.1;
            f.push(t, 123.45);
            if called_at.is_none() && f.stuck() {
                called_at = Some(t);
            }
        }
        // The first sample starts the run; 1 s later it has 10 repeats,
        // z = sqrt(20 ln(1/p)) ≈ 8 at p ≈ 4%.
        assert_eq!(called_at, Some(121.0));
        assert!(f.z() > 2.0 * Z);
    }

    #[test]
    fn coarse_quantisation_is_learnt_not_called() {
        // Noise below the step (0.05 m at 0.1 m steps): most samples repeat.
        let (mut f, mut rng) = (Flatline::default(), Rng::new(2));
        let zmax = live(&mut f, &mut rng, 0.0, 300.0, 20.0, 0.05, 0.1);
        assert!(zmax < Z, "z reached {zmax}");
        assert!(f.share() > 0.4, "share {}", f.share());
    }

    #[test]
    fn a_called_run_is_not_learnt_and_restart_keeps_the_share() {
        let (mut f, mut rng) = (Flatline::default(), Rng::new(3));
        live(&mut f, &mut rng, 0.0, 60.0, 10.0, 0.1, 0.01);
        // The held run's first sample ends the live run before it.
        f.push(60.0, 5.0);
        let share = f.share();
        for i in 1..100 {
            f.push(60.0 + 0.1 * f64::from(i), 5.0);
        }
        assert!(f.stuck());
        assert!(f.push(70.0, 6.0), "the end of a called run is a revival");
        assert_eq!(f.share(), share, "the stuck run was learnt");
        assert!(!f.stuck());
        f.restart();
        assert_eq!(f.share(), share);
        assert_eq!(f.z(), 0.0);
        assert!(!f.push(71.0, 6.0), "a restart forgets the reading");
        assert_eq!(f.z(), 0.0);
        assert!(!f.push(71.1, 6.1), "a live change after an uncalled run");
    }

    #[test]
    fn before_anything_is_learnt_twenty_repeats_over_a_second_are_needed() {
        // p = 1/2: 2 r ln 2 ≥ Z² at r = 20.
        let mut f = Flatline::default();
        for i in 0..=19 {
            f.push(f64::from(i) * 0.1, 1.0);
        }
        assert_eq!(f.run, 19);
        assert!(!f.stuck());
        f.push(2.0, 1.0);
        assert!(f.stuck());
    }

    #[test]
    fn non_finite_readings_are_never_a_run() {
        let mut f = Flatline::default();
        for i in 0..100 {
            f.push(f64::from(i) * 0.1, f64::NAN);
        }
        assert_eq!(f.z(), 0.0);
        assert!(f.check().is_ok());
        f.k = 3.0;
        assert!(f.check().is_err());
    }
}

/// The snapshot codec of this file's state type ([`crate::codec`]).
mod codec_impls {
    use super::*;
    use crate::codec::impl_codec;

    impl_codec!(Flatline {
        last,
        t0,
        t1,
        run,
        called,
        k,
        n
    });
}
