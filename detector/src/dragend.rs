//! The end of a drag-off, confirmed over the seconds after the jump: on
//! the horizontal and, since session 12, on the vertical (a second
//! instance, `DragEnd::vertical`, whose `z` and jump have the down axis
//! first and 0 second: battery tune #246, a 0.55 m/s vertical drag whose
//! return was judged as a step for 54 s).
//!
//! A drag-off (position and velocity pulled off together, spoofing style)
//! is followed by the filter; when it ends, the position jumps back by the
//! drag's rate times its age and the velocity by the rate. The detector
//! tells that return from a step's onset at the jump itself when the
//! velocity's jump clears its noise at one epoch (`Residuals::
//! drag_returned`), which a 0.3–0.6 m/s drag under 0.2–0.3 m/s of velocity
//! noise does not: the return was then judged as a step and flagged until
//! the episode coasted out (battery tune #58: 0.58 m/s for 23 s, 60 s
//! flagged after it).
//!
//! Here the velocity's jump is measured on means. `z = v − Σ Δv_IMU` (the
//! GPS velocity against the IMU's predicted velocity changes on the axes
//! judged, m/s) holds still through a manoeuvre, whatever the filter does. When a
//! position episode opens on a jump `J` of the position off its velocity
//! track, the mean of `z` over the `BEFORE_S` before the jump is compared
//! with its mean from the jump on: a return moves it along `J` by the
//! drag's rate, a step's onset does not move it. It is confirmed when that
//! shift clears `Z` σ of the difference of the two means, and the drag's
//! age it implies, `|J|` over the shift, is at least `MIN_AGE_S`. σ is the
//! larger of the two sides' pooled spread (never below `SIGMA_FLOOR`) over
//! their counts and the same shift's RMS learnt on normal epochs: a
//! Gauss–Markov receiver's velocity wanders over seconds, so its means are
//! not those of white noise (battery tune #65: a 7.3 m step under a 2 Hz
//! receiver, 0.18 m/s of shift against 0.04 m/s of white σ). The detector
//! then re-anchors on the fix: the episode flags the seconds the
//! confirmation takes, not the coast limit.
//!
//! Since session 15 a second, short shape judges the same jump: the mean of
//! `z` over the `SHORT_S` from the jump on against the `SHORT_S` before it,
//! with its own learnt RMS; either shape confirms. `z`'s wander is the
//! IMU's error integrated, a random walk, which moves 2 s means apart far
//! more than half-second means taken right at the jump, while a drag's end
//! moves both by its rate (battery eval #59, a 20 Hz receiver on a
//! vibrating 50 Hz IMU: 0.23 m/s of long-shape σ against 0.10 m/s short,
//! a 0.35 m/s drag's end confirmed only by the short shape). A 1 Hz
//! receiver has no entry in the half second before a jump, so only the
//! long shape judges it.
use crate::MinMax;
use serde::{Deserialize, Serialize};

/// Span of `z` before the jump that its level is taken over, s.
const BEFORE_S: f64 = 2.0;
/// Entries kept: a 20 Hz receiver's `AFTER_S + BEFORE_S`, which `learn`
/// spans, with room.
const CAP: usize = 96;
/// After the jump: at least this span and this many entries before a
/// verdict, s; none after `GIVE_UP_S`. Two seconds hold three fixes of a
/// 1 Hz receiver, so its σ is learnt too, not left at the prior.
const AFTER_S: f64 = 2.0;
const MIN_AFTER: u32 = 3;
const GIVE_UP_S: f64 = 4.0;
/// Shift of the mean along the jump, in σ of the difference of means.
/// 2.5, not 3 (session 11): a step's onset taken for a drag-off's end is
/// no longer final, as the offset re-anchored onto is kept and the step's
/// own end undoes it (`Episode::accepted`), while a missed end is judged
/// as a step for the 60 s coast limit (battery tune #531: 2.8σ).
const Z: f64 = 2.5;
/// Floor of one entry's σ, m/s.
const SIGMA_FLOOR: f64 = 0.05;
/// Shortest drag the shift and the jump imply, s.
const MIN_AGE_S: f64 = 5.0;
/// The short shape's span each side of the jump, s (see the module docs).
const SHORT_S: f64 = 0.5;
/// The learnt shift's RMS: prior (counted as `PRIOR_N` shifts), m/s, and
/// the forgetting rate once learnt, per second of entries (0.01 per entry
/// of a 5 Hz receiver, the rate it was tuned at; per entry before session
/// 15, which made a 20 Hz receiver's horizon four times shorter).
const SHIFT_SIGMA0: f64 = 0.15;
const PRIOR_N: f64 = 5.0;
const ALPHA_PER_S: f64 = 0.05;

/// The learnt RMS of one shape's shift on normal epochs (m/s), winsorised
/// at 3σ: a running mean from the prior at first (`SHIFT_SIGMA0`, counted
/// as `PRIOR_N` shifts), then forgetting at `alpha` per shift.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ShiftRms {
    /// Mean square, (m/s)², and the shifts learnt from.
    ms: f64,
    n: f64,
}

impl Default for ShiftRms {
    fn default() -> Self {
        ShiftRms { ms: SHIFT_SIGMA0 * SHIFT_SIGMA0, n: 0.0 }
    }
}

impl ShiftRms {
    fn sigma(&self) -> f64 {
        self.ms.sqrt()
    }

    /// Learn one shift (a NaN, a side with no entry, is skipped).
    fn learn(&mut self, x: f64, alpha: f64) {
        if x.is_nan() {
            return;
        }
        self.n += 1.0;
        let w = (1.0 / (self.n + PRIOR_N)).fmax(alpha);
        self.ms += w * ((x * x).fmin(9.0 * self.ms) - self.ms);
    }
}

/// An armed confirmation: the jump and both sides' sums along it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Pending {
    /// Time of the jump, s.
    t0: f64,
    /// Unit direction of the jump (N, E) and its length, m.
    u: [f64; 2],
    len: f64,
    /// Entries before the jump: count, mean and sum of squared deviations
    /// of `z` along `u`.
    n_b: f64,
    mean_b: f64,
    ss_b: f64,
    /// Entries from the jump on: count, sum and sum of squares along `u`.
    n_a: f64,
    sum_a: f64,
    sum2_a: f64,
}

/// See the module docs. Times in true s from the detector.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DragEnd {
    /// Recent `(t, z)` entries, oldest first.
    recent: Vec<(f64, [f64; 2])>,
    pending: Option<Pending>,
    /// The learnt RMS of the shift a confirmation measures (`BEFORE_S`
    /// before the jump, `AFTER_S` from it on) ...
    long: ShiftRms,
    /// ... and of the short shape's (`SHORT_S` each side).
    short: ShiftRms,
    /// Judges one axis (the vertical, first; the second is 0), so the
    /// shift's RMS is learnt from that axis alone.
    one_axis: bool,
    /// The last judged jump cannot have been a drag-off's end: the shift
    /// is `Z` σ short of the rate the jump would need over the time flown
    /// (see `confirmed`). Cleared when a jump is armed.
    ruled_out: bool,
}

impl Default for DragEnd {
    fn default() -> Self {
        DragEnd { recent: Vec::new(), pending: None, long: ShiftRms::default(), short: ShiftRms::default(), one_axis: false, ruled_out: false }
    }
}

impl DragEnd {
    /// The vertical confirmation: `z` and the jump as `[down, 0]`.
    fn vertical() -> Self {
        DragEnd { one_axis: true, ..DragEnd::default() }
    }

    /// This GPS epoch's `z` at `t` (None: no usable velocity or IMU, which
    /// restarts everything).
    pub fn push(&mut self, t: f64, z: Option<[f64; 2]>) {
        let Some(z) = z.filter(|z| t.is_finite() && z.iter().all(|x| x.is_finite())) else {
            self.recent.clear();
            self.pending = None;
            return;
        };
        if self.recent.last().is_some_and(|(tl, _)| t < *tl) {
            self.recent.clear();
        }
        let keep_from = self.recent.iter().position(|(ti, _)| t - ti <= AFTER_S + BEFORE_S).unwrap_or(self.recent.len());
        self.recent.drain(..keep_from);
        if self.recent.len() >= CAP {
            self.recent.remove(0);
        }
        self.recent.push((t, z));
        if let Some(p) = self.pending.as_mut() {
            let x = z[0] * p.u[0] + z[1] * p.u[1];
            p.n_a += 1.0;
            p.sum_a += x;
            p.sum2_a += x * x;
        }
    }

    /// A position episode opened at this epoch (`t`, the last `push`) on a
    /// jump of the position off its velocity track, `jump` (N, E, m): arm
    /// the confirmation. The newest entry is the first after the jump.
    ///
    /// Built for size in the core module: once per position episode
    /// (issue 15's budget).
    #[cfg_attr(navguard_cold_size, optimize(size))]
    pub fn arm(&mut self, t: f64, jump: [f64; 2]) {
        self.pending = None;
        self.ruled_out = false;
        let len = (jump[0] * jump[0] + jump[1] * jump[1]).sqrt();
        let Some(&(tn, zn)) = self.recent.last() else { return };
        if !(len > 0.0 && len.is_finite()) || tn != t {
            return;
        }
        let u = [jump[0] / len, jump[1] / len];
        let along = |z: &[f64; 2]| z[0] * u[0] + z[1] * u[1];
        let before = || self.recent[..self.recent.len() - 1].iter().filter(|(ti, _)| t - ti <= BEFORE_S).map(|(_, z)| along(z));
        let n_b = before().count() as f64;
        if n_b < 2.0 {
            return;
        }
        let mean_b = before().sum::<f64>() / n_b;
        let ss_b = before().map(|x| (x - mean_b) * (x - mean_b)).sum();
        let x = along(&zn);
        self.pending = Some(Pending { t0: t, u, len, n_b, mean_b, ss_b, n_a: 1.0, sum_a: x, sum2_a: x * x });
    }

    /// Whether the armed jump is now confirmed as a drag-off's end (NaN
    /// when not), and then when the drag began (s on the row clock: the
    /// jump's time less the drag's age, the jump over the shift and its σ,
    /// the latest onset the shift allows, in true s over `scale`, true s
    /// per row s; 0 without the `dated` feature). A float, not an option:
    /// the core module's size budget. `flown`: time flown, s; the drag
    /// cannot be older. Judged once, at the first epoch `AFTER_S` and
    /// `MIN_AFTER` entries past the jump (the
    /// shape the learnt σ measures: a longer wait lets `z`'s slow drift,
    /// the accelerometer bias integrated, pass for a shift), then disarmed;
    /// given up `GIVE_UP_S` after the jump.
    ///
    /// Built for size in the core module: judged only while armed (issue
    /// 15's budget).
    #[cfg_attr(navguard_cold_size, optimize(size))]
    pub fn confirmed(&mut self, t: f64, flown: f64, scale: f64) -> f64 {
        let Some(p) = self.pending else { return f64::NAN };
        if t - p.t0 > GIVE_UP_S {
            self.pending = None;
            return f64::NAN;
        }
        if t - p.t0 < AFTER_S || p.n_a < MIN_AFTER as f64 {
            return f64::NAN;
        }
        self.pending = None;
        let mean_a = p.sum_a / p.n_a;
        let ss_a = (p.sum2_a - p.n_a * mean_a * mean_a).fmax(0.0);
        let var = ((p.ss_b + ss_a) / (p.n_b + p.n_a - 2.0)).fmax(SIGMA_FLOOR * SIGMA_FLOOR);
        let sigma = (var * (1.0 / p.n_b + 1.0 / p.n_a)).sqrt().fmax(self.long.sigma());
        let shift = mean_a - p.mean_b;
        // A drag-off older than the flight is impossible: its rate is at
        // least the jump over the time flown.
        self.ruled_out = shift + Z * sigma < p.len / flown;
        // Either shape: the drag's end moves `z` at the jump and keeps it
        // there, so both see it; each has its own noise.
        let v = self.short_shift(p.t0);
        let short = v[0] * p.u[0] + v[1] * p.u[1];
        let drag = |shift: f64, sigma: f64| match shift > Z * sigma && (MIN_AGE_S..=flown).contains(&(p.len / shift)) {
            true if cfg!(feature = "dated") => p.t0 - p.len / (shift + sigma) / scale,
            true => 0.0,
            false => f64::NAN,
        };
        let long = drag(shift, sigma);
        if long.is_nan() { drag(short, self.short.sigma()) } else { long }
    }

    /// The shift of `z`'s mean (N, E) from the `SHORT_S` before `t0` to the
    /// `SHORT_S` from `t0` on (NaN when either side is empty). Not inlined:
    /// it serves both `confirmed` and `learn` (issue 15's size budget).
    #[inline(never)]
    fn short_shift(&self, t0: f64) -> [f64; 2] {
        let (mut n, mut a, mut b) = ([0.0; 2], [0.0; 2], [0.0; 2]);
        for (t, z) in &self.recent {
            let dt = t - t0;
            if (0.0..SHORT_S).contains(&dt) {
                n[0] += 1.0;
                a = [a[0] + z[0], a[1] + z[1]];
            } else if (-SHORT_S..0.0).contains(&dt) {
                n[1] += 1.0;
                b = [b[0] + z[0], b[1] + z[1]];
            }
        }
        [a[0] / n[0] - b[0] / n[1], a[1] / n[0] - b[1] / n[1]]
    }

    /// A normal epoch: learn the RMS of the shift a confirmation measures,
    /// the mean of `z` over the last `AFTER_S` against the `BEFORE_S`
    /// before, per axis (winsorised at 3σ; a running mean from the prior at
    /// first, then forgetting at `ALPHA_PER_S`).
    pub fn learn(&mut self) {
        let Some(&(tn, _)) = self.recent.last() else { return };
        // After: the last `AFTER_S` with its newest entry, as a confirmation
        // takes the jump's epoch and the `AFTER_S` past it; before: the
        // `BEFORE_S` ahead of that.
        let mean = |inside: &dyn Fn(f64) -> bool| {
            let (mut n, mut s) = (0.0, [0.0; 2]);
            for (_, z) in self.recent.iter().filter(|(t, _)| inside(tn - t)) {
                n += 1.0;
                s[0] += z[0];
                s[1] += z[1];
            }
            (n >= 2.0).then(|| [s[0] / n, s[1] / n])
        };
        let axes = if self.one_axis { 1 } else { 2 };
        // Forgetting per second of entries, not per entry: the same
        // horizon at every receiver rate.
        let n = self.recent.len();
        let alpha = if n >= 2 { (ALPHA_PER_S * (tn - self.recent[n - 2].0)).fmin(0.5) } else { 0.5 };
        // The short shape, with its jump's epoch the newest entry at least
        // `SHORT_S` old, so both its sides are full.
        if let Some(&(t0, _)) = self.recent.iter().rev().find(|(t, _)| tn - t >= SHORT_S) {
            let v = self.short_shift(t0);
            for x in &v[..axes] {
                self.short.learn(*x, alpha);
            }
        }
        let after = mean(&|age| age <= AFTER_S);
        let before = mean(&|age| age > AFTER_S && age <= AFTER_S + BEFORE_S);
        let (Some(a), Some(b)) = (after, before) else { return };
        for k in 0..axes {
            self.long.learn(a[k] - b[k], alpha);
        }
    }

    /// Disarm (the episode ended or the filter re-anchored).
    pub fn disarm(&mut self) {
        self.pending = None;
        self.ruled_out = false;
    }

    /// A confirmation is armed.
    pub fn armed(&self) -> bool {
        self.pending.is_some()
    }
}

/// Both confirmations: the horizontal one on (N, E) and the vertical one
/// on the down axis, each judging its own part of a jump (the implied
/// drag's age, `MIN_AGE_S`, rules out the small part a jump has on the
/// other axes). `z` and jumps are NED.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DragEnds {
    h: DragEnd,
    v: DragEnd,
}

impl Default for DragEnds {
    fn default() -> Self {
        DragEnds { h: DragEnd::default(), v: DragEnd::vertical() }
    }
}

impl DragEnds {
    /// This GPS epoch's `z` (see `DragEnd::push`).
    pub fn push(&mut self, t: f64, z: Option<[f64; 3]>) {
        self.h.push(t, z.map(|z| [z[0], z[1]]));
        self.v.push(t, z.map(|z| [z[2], 0.0]));
    }

    /// Arm both on a position episode's jump (see `DragEnd::arm`); none
    /// known disarms them.
    pub fn arm(&mut self, t: f64, jump: Option<[f64; 3]>) {
        match jump {
            Some(j) => {
                self.h.arm(t, [j[0], j[1]]);
                self.v.arm(t, [j[2], 0.0]);
            }
            None => self.disarm(),
        }
    }

    /// Which ends are confirmed at this epoch, with their drags' onsets:
    /// horizontal, vertical (see `DragEnd::confirmed`).
    pub fn confirmed(&mut self, t: f64, flown: f64, scale: f64) -> [f64; 2] {
        [self.h.confirmed(t, flown, scale), self.v.confirmed(t, flown, scale)]
    }

    /// A normal epoch (see `DragEnd::learn`).
    pub fn learn(&mut self) {
        self.h.learn();
        self.v.learn();
    }

    /// Disarm both.
    pub fn disarm(&mut self) {
        self.h.disarm();
        self.v.disarm();
    }

    /// The last judged jump was no drag-off's end on either axis it moved
    /// along (see `DragEnd::ruled_out`).
    pub fn ruled_out(&self) -> bool {
        self.h.ruled_out || self.v.ruled_out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    /// 5 Hz entries with white noise `sd` around `level(t)` along N.
    fn feed(d: &mut DragEnd, rng: &mut Rng, t0: f64, t1: f64, sd: f64, level: f64) {
        let mut t = t0;
        while t < t1 - 1e-9 {
            d.push(t, Some([level + sd * rng.normal(), 0.3 * rng.normal()]));
            t += 0.2;
        }
    }

    #[test]
    fn a_velocity_shift_along_the_jump_confirms_a_return() {
        let (mut d, mut rng) = (DragEnd::default(), Rng::new(1));
        feed(&mut d, &mut rng, 0.0, 10.0, 0.3, 0.0);
        // A 0.8 m/s drag for 20 s ends: position back by 16 m north,
        // velocity back by 0.8 m/s along it.
        d.push(10.0, Some([0.8, 0.0]));
        d.arm(10.0, [16.0, 0.0]);
        let mut at = None;
        let mut t = 10.2;
        while t < 14.0 {
            d.push(t, Some([0.8 + 0.3 * rng.normal(), 0.3 * rng.normal()]));
            let since = d.confirmed(t, 100.0, 1.0);
            if !since.is_nan() {
                at = Some((t, since));
                break;
            }
            t += 0.2;
        }
        let (at, since) = at.expect("confirmed");
        assert!(at <= 12.3, "confirmed at {at}");
        // The drag began 20 s before its end, at -10 s. It is dated at the
        // latest onset the shift allows, 16 m over the shift plus its σ
        // (about 0.8 + 0.2 m/s here): later than -10 s, not before it.
        assert!((-10.5..-5.5).contains(&since), "began at {since}");
        assert!(!d.armed());
    }

    #[test]
    fn a_jump_too_large_for_a_drag_as_old_as_the_flight_is_ruled_out() {
        // A 20 m jump north with the velocity unmoved (0.05 m/s of noise,
        // σ of the shift at its 0.15 m/s prior): 40 s flown, a drag-off's
        // end would have moved it by at least 0.5 m/s, beyond `Z` σ. 1000 s
        // flown, 0.02 m/s would do: not ruled out. Disarming forgets it.
        for (flown, ruled) in [(40.0, true), (1000.0, false)] {
            let (mut d, mut rng) = (DragEnd::default(), Rng::new(3));
            feed(&mut d, &mut rng, 0.0, 10.0, 0.05, 0.0);
            d.push(10.0, Some([0.0, 0.0]));
            d.arm(10.0, [20.0, 0.0]);
            let mut t = 10.2;
            while d.armed() && t < 14.0 {
                d.push(t, Some([0.05 * rng.normal(), 0.3 * rng.normal()]));
                assert!(d.confirmed(t, flown, 1.0).is_nan());
                t += 0.2;
            }
            assert_eq!(d.ruled_out, ruled, "flown {flown}");
            d.disarm();
            assert!(!d.ruled_out);
        }
    }

    #[test]
    fn a_step_onset_leaves_the_velocity_and_is_not_confirmed() {
        for seed in 1..30 {
            let (mut d, mut rng) = (DragEnd::default(), Rng::new(seed));
            feed(&mut d, &mut rng, 0.0, 10.0, 0.3, 0.2);
            d.push(10.0, Some([0.2 + 0.3 * rng.normal(), 0.0]));
            d.arm(10.0, [10.0, 0.0]);
            let mut t = 10.2;
            while t < 15.0 {
                d.push(t, Some([0.2 + 0.3 * rng.normal(), 0.3 * rng.normal()]));
                assert!(d.confirmed(t, 100.0, 1.0).is_nan(), "seed {seed}: confirmed at {t}");
                t += 0.2;
            }
            assert!(!d.armed(), "gave up");
        }
    }

    #[test]
    fn a_receiver_whose_velocity_wanders_teaches_a_larger_sigma() {
        // Gauss–Markov velocity error (σ 0.2 m/s, τ 5 s) at 2 Hz: the means
        // over seconds wander by far more than the white part says.
        let (mut d, mut rng) = (DragEnd::default(), Rng::new(6));
        let (mut gm, mut t) = (0.0, 0.0);
        let phi = (-0.5f64 / 5.0).exp();
        while t < 300.0 {
            gm = phi * gm + 0.2 * (1.0 - phi * phi).sqrt() * rng.normal();
            d.push(t, Some([gm + 0.02 * rng.normal(), 0.0]));
            d.learn();
            t += 0.5;
        }
        // White noise of 0.02 m/s would give 0.02·√(1/2 + 1/4) ≈ 0.017.
        let sigma = d.long.sigma();
        assert!(sigma > 0.05 && sigma < 0.15, "learnt {sigma}");
    }

    #[test]
    fn the_learnt_shift_spans_the_full_window_before_at_20_hz() {
        // z at 0 for 1 s, then at 1 m/s for 3 s: over the last 2 s against
        // the 2 s before them, a shift of 0.5 (one axis). A ring that kept
        // only 3 s saw the before-window's last second alone, at 1: no shift.
        let mut d = DragEnd::default();
        let mut t = 0.0;
        while t < 4.0 - 1e-9 {
            d.push(t, Some([if t < 1.0 - 1e-9 { 0.0 } else { 1.0 }, 0.0]));
            t += 0.05;
        }
        assert!(d.recent.len() == 80 && d.recent[0].0 == 0.0, "{} entries from {} s", d.recent.len(), d.recent[0].0);
        d.learn();
        // Axis N: 0.25 winsorised at 9σ² = 0.2025, weight 1/6; axis E: 0,
        // weight 1/7.
        let prior = SHIFT_SIGMA0 * SHIFT_SIGMA0;
        let expect = (prior + (9.0 * prior - prior) / 6.0) * 6.0 / 7.0;
        assert!((d.long.ms - expect).abs() < 1e-12, "{} against {expect}", d.long.ms);
    }

    #[test]
    fn a_shift_too_large_for_the_jump_is_no_drag() {
        // 2 m of jump with 1 m/s of shift: a 2 s drag, shorter than any.
        let (mut d, mut rng) = (DragEnd::default(), Rng::new(4));
        feed(&mut d, &mut rng, 0.0, 10.0, 0.1, 0.0);
        d.push(10.0, Some([1.0, 0.0]));
        d.arm(10.0, [2.0, 0.0]);
        let mut t = 10.2;
        while t < 15.0 {
            d.push(t, Some([1.0 + 0.1 * rng.normal(), 0.0]));
            assert!(d.confirmed(t, 100.0, 1.0).is_nan());
            t += 0.2;
        }
    }

    #[test]
    fn a_missing_entry_disarms_and_arming_needs_the_jump_epoch() {
        let (mut d, mut rng) = (DragEnd::default(), Rng::new(2));
        feed(&mut d, &mut rng, 0.0, 10.0, 0.3, 0.0);
        d.arm(11.0, [10.0, 0.0]);
        assert!(!d.armed(), "no entry at 11 s");
        d.push(10.0, Some([0.5, 0.0]));
        d.arm(10.0, [10.0, 0.0]);
        assert!(d.armed());
        d.push(10.2, None);
        assert!(!d.armed());
    }

    /// The vertical instance learns the shift's RMS from its one axis: a
    /// 5 Hz `z` of white σ 0.3 m/s shifts between two 2 s means by
    /// 0.3·sqrt(1/11 + 1/10) ≈ 0.13 m/s. Pooled with the unused second
    /// axis (always 0), as the horizontal instance would pool it, half of
    /// the learnt shifts are 0 and σ comes out √2 too small: a vertical
    /// drag's end would be confirmed on noise.
    #[test]
    fn the_vertical_instance_learns_its_shift_from_one_axis() {
        let mut rng = Rng::new(3);
        let (mut v, mut h) = (DragEnd::vertical(), DragEnd::default());
        // The learnt mean square forgets over 100 shifts (20 s), which
        // overlap: averaged over the 540 s after a minute of learning.
        let (mut mv, mut mh, mut n) = (0.0, 0.0, 0.0);
        for i in 0..3000 {
            let t = i as f64 * 0.2;
            let z = [0.3 * rng.normal(), 0.0];
            for d in [&mut v, &mut h] {
                d.push(t, Some(z));
                d.learn();
            }
            if t >= 60.0 {
                (mv, mh, n) = (mv + v.long.ms, mh + h.long.ms, n + 1.0);
            }
        }
        let expected = 0.3 * (1.0f64 / 11.0 + 1.0 / 10.0).sqrt();
        let (sv, sh) = ((mv / n).sqrt(), (mh / n).sqrt());
        assert!((sv / expected - 1.0).abs() < 0.2, "vertical σ {sv:.3} against {expected:.3}");
        assert!((sh * 2f64.sqrt() / sv - 1.0).abs() < 0.15, "pooled σ {sh:.3} against {sv:.3}/√2");
    }

    /// The learnt shift forgets per second, not per entry: over 20 s of
    /// zero shifts, after 100 s of them, its mean square falls by the same
    /// factor at 5 and at 20 Hz, exp(−2 · 0.05 · 20) (two axes learn per
    /// entry). Per entry, 20 Hz forgot in 5 s what 5 Hz forgot in 20.
    #[test]
    fn the_shift_forgets_at_the_same_pace_at_every_rate() {
        let decay = |hz: f64| {
            let mut d = DragEnd::default();
            let mut at = |from: usize, to: usize| {
                for i in from..to {
                    d.push(i as f64 / hz, Some([0.0, 0.0]));
                    d.learn();
                }
                d.long.ms
            };
            let n = (100.0 * hz) as usize;
            let m100 = at(0, n);
            at(n, n + (20.0 * hz) as usize) / m100
        };
        let expect = (-2.0f64 * ALPHA_PER_S * 20.0).exp();
        for hz in [5.0, 20.0] {
            let r = decay(hz);
            assert!((r / expect - 1.0).abs() < 0.05, "{hz} Hz: {r:.4} against {expect:.4}");
        }
    }

    /// 20 Hz entries along N: a random walk (`rw` m/s per entry, the IMU's
    /// integrated error) plus white noise `sd`, learnt on normal epochs;
    /// from 60 s on, `shift` added (0: a step's onset). Whether the jump
    /// armed there was confirmed.
    fn random_walk_jump(seed: u64, shift: f64) -> bool {
        let (mut d, mut rng) = (DragEnd::default(), Rng::new(seed));
        let (rw, sd, jump) = (0.05, 0.05, 1200);
        let mut walk = 0.0;
        let mut confirmed = false;
        for i in 0..1280 {
            let t = i as f64 * 0.05;
            walk += rw * rng.normal();
            let level = walk + if i >= jump { shift } else { 0.0 };
            d.push(t, Some([level + sd * rng.normal(), sd * rng.normal()]));
            if i < jump {
                d.learn();
            } else if i == jump {
                d.arm(t, [27.0, 0.0]);
            } else {
                confirmed |= !d.confirmed(t, 160.0, 1.0).is_nan();
            }
        }
        confirmed
    }

    /// Regression: battery eval #59 (20 Hz receiver, industrial IMU at
    /// 50 Hz with vibration): a 0.35 m/s drag for 77 s ended with a 27 m
    /// jump back, judged as a step for 60 s (1,195 false-positive epochs).
    /// `z` wandered 0.23 m/s between 2 s means, so the long shape could not
    /// confirm the 0.53 m/s it measured; the wander is a random walk, whose
    /// half-second means right at the jump differ less (0.10 m/s), and the
    /// short shape confirmed it. Here, under such a walk, the long shape
    /// alone confirms 12 of 20 drag ends and 4 of 40 step onsets; with the
    /// short shape, 19 and 5.
    #[test]
    fn the_short_shape_confirms_a_drag_end_under_a_wandering_z() {
        let ends = (1..=20).filter(|&s| random_walk_jump(s, 0.5)).count();
        assert!(ends >= 18, "{ends}/20 drag ends confirmed");
        let onsets = (1..=40).filter(|&s| random_walk_jump(s, 0.0)).count();
        assert!(onsets <= 5, "{onsets}/40 step onsets confirmed");
    }
}

/// The snapshot codec of this file's state types ([`crate::codec`]).
mod codec_impls {
    use super::*;
    use crate::codec::impl_codec;

    impl_codec!(Pending { t0, u, len, n_b, mean_b, ss_b, n_a, sum_a, sum2_a });
    impl_codec!(ShiftRms { ms, n });
    impl_codec!(DragEnd { recent, pending, long, short, one_axis, ruled_out });
    impl_codec!(DragEnds { h, v });
}
