//! The GPS position against its own velocity track.
//!
//! `d = y − ∫v dt`: the receiver's position minus its Doppler velocity
//! integrated (trapezoid, true time). Doppler velocity carries neither a
//! position-only fault (a step, a ramp) nor the slow wander of the position
//! error, and its white noise integrates to centimetres over minutes, so on
//! a healthy receiver `d` only wanders by the position error itself. A
//! position fault moves `d`; its end moves `d` back.
//!
//! The track keeps a slow baseline of `d` and a σ of `d`'s wander about
//! it, both learnt in flight from normal epochs within 3σ (outliers are
//! not learnt, so a fault never becomes the baseline; since session 17
//! the GPS position's track learns σ from them too, winsorised at 3σ).
//! What the detector asks it: did this epoch's jump bring `d` back inside
//! its wander from far outside it? That is the end of a position fault
//! that was never flagged (a slow ramp the filter followed), not the start
//! of a new one. And its mirror (session 17, `departed`): did this epoch's
//! jump take `d` from inside its wander to far outside it? That is a
//! position fault's onset, folded into the position group's R whatever the
//! filter's residuals say.
//!
//! Since session 24 the track also keeps a short mean of `d` (time
//! constant `MEAN_TAU_S`) with its own σ learnt on normal epochs: a fast
//! receiver's white noise averages down in it, so a step a few per-fix σ
//! high stands out (the 10 m step check's instance 3: a 10 Hz receiver of
//! 2.55 m σ, its step 3.9 per-fix σ and 2 of 600 epochs flagged; 12 σ of
//! the mean). `mean_departure` is an onset only (the mean left `NEAR` σ
//! within `ONSET_S`), so a slow wander never calls; the detector holds the
//! episode it opens while the mean stays off (`Episode::mean_hold`).
//!
//! The detector also uses it on one axis (the others fed zeros, which stay
//! at zero departure) for the baro's level: against the GPS altitude (no
//! velocity to integrate) and against the GPS vertical velocity integrated.
use crate::MinMax;
use serde::{Deserialize, Serialize};

/// Time constant of the baseline and of σ, s.
const TAU_S: f64 = 60.0;
/// Track time before the baseline is trusted, s (a quick track judges a
/// jump from `QUICK_ORIGIN_S`: see `VelocityTrack::departed`).
const MIN_AGE_S: f64 = 30.0;
/// Time constant of `d`'s short mean, true s (see `mean_departure`).
const MEAN_TAU_S: f64 = 0.5;
/// The short mean's call, in σ of that mean.
pub const MEAN_Z: f64 = 5.0;
/// The short mean is an onset only this long after it was within `NEAR`
/// σ, true s.
const ONSET_S: f64 = 2.0;
/// Fix interval above which the short mean is not judged, s: below about
/// 4 Hz it averages too few fixes to add to the per-fix `departed`, and a
/// Gauss–Markov receiver's wander passed for onsets (battery tune #326, a
/// 1 Hz receiver: 41 false-positive epochs; #696, 2 Hz: 49).
const MEAN_MAX_DT_S: f64 = 0.25;
/// Floor of σ per axis, m: a centimetre-grade receiver's wander is not a
/// scale below which a jump of a metre means nothing.
const SIGMA_FLOOR_M: f64 = 0.3;
/// Prior σ per axis, m, before any is learnt.
const SIGMA0_M: f64 = 2.0;
/// Outside this many σ an epoch is not learnt.
const LEARN_SIGMAS: f64 = 3.0;
/// A return: `d` was outside `FAR` σ before the jump and inside `NEAR` σ
/// after it (norm over the three axes of `(d − base)/σ`).
pub const FAR: f64 = 5.0;
/// Within this many σ of its baseline a level is back (also the detector's
/// bound on a baro jump seen on both levels, `Consistency::vertical_return`).
pub const NEAR: f64 = 2.5;
/// Outlying this long, the baseline is re-learnt from the current `d`, s:
/// a receiver whose track moved for good (a re-acquisition) is not judged
/// against its old one for the rest of the flight.
pub const RELEARN_S: f64 = 120.0;
/// Span of the track's first learnt epochs whose mean is its origin, s.
const ORIGIN_S: f64 = 5.0;
/// Age from which a quick track judges a return to its origin, s (see
/// `VelocityTrack::quick_origin`).
const QUICK_ORIGIN_S: f64 = 10.0;
/// Share of an offset that a return jump takes back: of the baseline's
/// offset from the origin here, of a fault's offset in the detector's
/// episodes.
pub const RETURN_UNDONE: (f64, f64) = (0.6, 1.4);

/// `jump` (m) takes back most of `off` (m, more than `min2` m² long)
/// along its direction: between `RETURN_UNDONE` of it.
pub fn undoes(jump: &[f64; 3], off: &[f64; 3], min2: f64) -> bool {
    let off2: f64 = off.iter().map(|x| x * x).sum();
    if !(off2 > min2 && off2 > 0.0) {
        return false;
    }
    let undone = -(0..3).map(|a| jump[a] * off[a]).sum::<f64>() / off2;
    (RETURN_UNDONE.0..=RETURN_UNDONE.1).contains(&undone)
}

/// See the module docs. Positions in m (NED), times in true s.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct VelocityTrack {
    /// ∫v dt since the track began, m.
    integral: [f64; 3],
    /// `d` at this epoch and at the previous one.
    d: Option<[f64; 3]>,
    d_prev: Option<[f64; 3]>,
    base: [f64; 3],
    /// Learnt mean square of `d − base` per axis, m².
    ms: [f64; 3],
    /// Track time learnt from, s.
    age: f64,
    /// Time outlying (beyond `LEARN_SIGMAS`) since the last learnt epoch, s.
    outlying: f64,
    /// The last interval's length, s.
    dt: f64,
    /// The motion at this fix (horizontal speed² (m/s)², climb m/s; NaN
    /// when unknown) and its mean over the epochs the baseline learnt
    /// from, with the baseline's weights: what a one-axis baro level's
    /// healthy error follows (see `departure_net`).
    motion: [f64; 2],
    motion_base: [f64; 2],
    /// Moments of the motion's deviation `x` from its mean and of the
    /// first axis' `d − base` (`y`), with the baseline's weights: `x xᵀ`
    /// (xx₀₀, xx₀₁, xx₁₁) and `x y`. The level's own error model.
    mxx: [f64; 3],
    mxy: [f64; 2],
    /// The mean of `d` over the track's first `ORIGIN_S` of learnt epochs,
    /// and the time learnt into it, s: where the level began (see
    /// `back_to_origin`).
    origin: [f64; 3],
    origin_age: f64,
    /// This epoch's jump went back to the origin (see `back_to_origin`).
    at_origin: bool,
    /// Learnt mean square of `d`'s change from one epoch to the next per
    /// axis, m² (0 before any): the scale a jump is measured on.
    ms_step: [f64; 3],
    /// A return to the origin is judged from `QUICK_ORIGIN_S` of age, not
    /// `MIN_AGE_S` (the GPS position's track: see `back_to_origin`). Kept
    /// across `clear`.
    quick_origin: bool,
    /// `d`'s short mean (time constant `MEAN_TAU_S`), m, and the learnt
    /// mean square of its offset from the baseline per axis, m² (learnt
    /// like `ms`, winsorised at `LEARN_SIGMAS`).
    dm: [f64; 3],
    ms_mean: [f64; 3],
    /// Track time since the short mean was last within `NEAR` σ, s.
    since_calm: f64,
}

impl VelocityTrack {
    /// Restart (a velocity gap: the integral has nothing to continue).
    pub fn clear(&mut self) {
        *self = VelocityTrack { quick_origin: self.quick_origin, ..VelocityTrack::default() };
    }

    /// A track whose return to the origin is judged early (see
    /// `quick_origin`).
    pub fn quick() -> Self {
        VelocityTrack { quick_origin: true, ..VelocityTrack::default() }
    }

    /// One GPS interval of `dt` true s: position `y` (m) and velocity `v`
    /// at its end, `pv` at its start. Built for size in the core module:
    /// once per GPS epoch (issue 15's budget).
    #[cfg_attr(navguard_cold_size, optimize(size))]
    pub fn step(&mut self, dt: f64, y: [f64; 3], v: [f64; 3], pv: [f64; 3]) {
        let Some(_) = self.d else {
            self.integral = y;
            self.base = [0.0; 3];
            self.ms = [SIGMA0_M * SIGMA0_M; 3];
            self.ms_mean = [SIGMA0_M * SIGMA0_M; 3];
            self.dm = [0.0; 3];
            self.d = Some([0.0; 3]);
            return;
        };
        for a in 0..3 {
            self.integral[a] += 0.5 * (v[a] + pv[a]) * dt;
        }
        self.dt = dt;
        self.d_prev = self.d;
        let d: [f64; 3] = core::array::from_fn(|a| y[a] - self.integral[a]);
        let k = dt / (MEAN_TAU_S + dt);
        for a in 0..3 {
            self.dm[a] += k * (d[a] - self.dm[a]);
        }
        self.d = Some(d);
        self.since_calm = if self.mean_sigmas() < NEAR { 0.0 } else { self.since_calm + dt };
        self.back_to_origin();
    }

    /// A fault that began in the flight's first seconds is learnt as the
    /// baseline, and its end, the level jumping back to where it began,
    /// looked like a new fault (battery tune #270: a 12.2 m baro step from
    /// 8 s to 107 s, its end flagged for the rest of the flight). When the
    /// baseline sits beyond `NEAR` σ of the origin and this epoch's jump
    /// takes back `RETURN_UNDONE` of that offset, to within `NEAR` σ of the
    /// origin, and is `FAR` times the level's epoch-to-epoch change along
    /// it (a jump, not one fix's noise: a healthy 1 Hz level wandering
    /// 1.6 m about its origin had its baseline that far off, and a noise
    /// step back passed for a return; the property test below), the
    /// baseline moves back to the origin and `returned` reports the
    /// return. `NEAR`, not `FAR`: σ itself learnt part of a fault that
    /// came while it was starting. A drift from the first seconds is
    /// learnt more than a step: its baseline lags it and σ grows with it,
    /// so the baseline stays within `NEAR` σ (tune #1513: a baro drifting
    /// 24 m, σ 7.8 m, baseline 12 m off, its end flagged for 89 s). So the
    /// offset is also measured on the level just before the jump: beyond
    /// `NEAR` σ of the origin, the jump taking back `RETURN_UNDONE` of it,
    /// `FAR` times the level's epoch-to-epoch change, and the baseline
    /// moved `NEAR` of those toward it (the track
    /// learnt the fault; a baseline still at the origin needs no return:
    /// tune #273's aggressive flight jumped a level 1.6 m in one epoch).
    /// A position ramp from the first seconds that ends before the track
    /// is `MIN_AGE_S` old (tune #656: 0.37 m/s from 5.6 s to 27.4 s, its
    /// end judged as a step) is caught on the GPS position's track, which
    /// judges its origin from `QUICK_ORIGIN_S` (`quick_origin`): its
    /// `d` holds still to centimetres on a healthy receiver. Not on the
    /// baro's levels, whose early wander passed for a return (battery eval
    /// #238: its Doppler level re-based 10 s in, a later drift missed).
    fn back_to_origin(&mut self) {
        self.at_origin = false;
        let (Some(d), Some(p)) = (self.d, self.d_prev) else { return };
        if self.origin_age < ORIGIN_S || self.age < self.jumps_from() {
            return;
        }
        let jump: [f64; 3] = core::array::from_fn(|a| d[a] - p[a]);
        let off: [f64; 3] = core::array::from_fn(|a| self.base[a] - self.origin[a]);
        // The jump takes back most of `o`, and is a jump, not one fix's noise.
        let takes_back = |o: &[f64; 3]| undoes(&jump, o, 0.0) && -self.steps_along(&jump, o) > FAR;
        let by_base = self.z(&self.origin) > NEAR && takes_back(&off);
        let level: [f64; 3] = core::array::from_fn(|a| p[a] - self.origin[a]);
        let by_level = self.z_from(&p, &self.origin) > NEAR && takes_back(&level) && self.steps_along(&off, &level) > NEAR;
        if (by_base || by_level) && self.z_from(&d, &self.origin) < NEAR {
            self.base = self.origin;
            // The short mean restarts on the fix, as at every re-basing.
            self.dm = d;
            self.outlying = 0.0;
            self.at_origin = true;
        }
    }

    /// `x` (m) along `dir` in σ of `d`'s epoch-to-epoch change along it
    /// (signed; 0 until that is learnt).
    fn steps_along(&self, x: &[f64; 3], dir: &[f64; 3]) -> f64 {
        let (mut along, mut var) = (0.0, 0.0);
        for a in 0..3 {
            along += x[a] * dir[a];
            var += dir[a] * dir[a] * self.ms_step[a];
        }
        if var > 0.0 { along / var.sqrt() } else { 0.0 }
    }

    fn sigma(&self, a: usize) -> f64 {
        self.ms[a].sqrt().fmax(SIGMA_FLOOR_M)
    }

    /// σ of `d`'s wander about the baseline per axis, m (the prior before
    /// any is learnt).
    pub fn sigmas(&self) -> [f64; 3] {
        core::array::from_fn(|a| self.sigma(a))
    }

    /// Norm over the axes of `(x − base)/σ`.
    fn z(&self, x: &[f64; 3]) -> f64 {
        self.z_from(x, &self.base)
    }

    /// Norm over the axes of `(x − level)/σ`.
    fn z_from(&self, x: &[f64; 3], level: &[f64; 3]) -> f64 {
        (0..3).map(|a| ((x[a] - level[a]) / self.sigma(a)).powi(2)).sum::<f64>().sqrt()
    }

    /// A normal epoch: learn the baseline and σ from it if it lies within
    /// `LEARN_SIGMAS` (fast start over the first `TAU_S`). Not inlined:
    /// three tracks call it (issue 15's size budget).
    #[cfg_attr(navguard_cold_size, optimize(size))]
    #[inline(never)]
    pub fn learn(&mut self) {
        let Some(d) = self.d else { return };
        let dt = self.dt;
        if !(dt > 0.0) {
            return;
        }
        let inside = (0..3).all(|a| (d[a] - self.base[a]).abs() <= LEARN_SIGMAS * self.sigma(a));
        let outlier = !inside && self.age >= MIN_AGE_S && self.outlying < RELEARN_S;
        // The GPS position's track learns σ from an outlier too,
        // winsorised at `LEARN_SIGMAS` σ (never the baseline): a σ learnt
        // in a calm first minute otherwise made every fix of a wider wander
        // an outlier for good, and a ramp's end was no return from far off
        // (battery eval #56: 625 false-positive epochs). Not a baro level's:
        // its outliers are the baro's faults, which its σ must not learn.
        if outlier {
            self.outlying += dt;
            if !self.quick_origin {
                return;
            }
        } else {
            if self.outlying >= RELEARN_S {
                self.base = d;
                self.dm = d;
                self.motion_base = self.motion;
            }
            self.outlying = 0.0;
            if self.origin_age < ORIGIN_S {
                let wo = dt / (self.origin_age + dt);
                for a in 0..3 {
                    self.origin[a] += wo * (d[a] - self.origin[a]);
                }
                self.origin_age += dt;
            }
        }
        let w = (dt / TAU_S).fmax(dt / (self.age + dt)).fmin(1.0);
        let (wb, cap) = if outlier { (0.0, LEARN_SIGMAS * LEARN_SIGMAS) } else { (w, f64::INFINITY) };
        for a in 0..3 {
            let e = d[a] - self.base[a];
            self.base[a] += wb * e;
            self.ms[a] += w * ((e * e).fmin(cap * self.ms[a].fmax(SIGMA_FLOOR_M * SIGMA_FLOOR_M)) - self.ms[a]);
            let em = self.dm[a] - self.base[a];
            self.ms_mean[a] += w * ((em * em).fmin(LEARN_SIGMAS * LEARN_SIGMAS * self.ms_mean[a].fmax(SIGMA_FLOOR_M * SIGMA_FLOOR_M)) - self.ms_mean[a]);
        }
        if outlier {
            return;
        }
        self.age += dt;
        if let Some(p) = self.d_prev {
            for a in 0..3 {
                let s2 = (d[a] - p[a]).powi(2);
                let m = self.ms_step[a];
                self.ms_step[a] = if m > 0.0 { m + w * (s2.fmin(9.0 * m) - m) } else { s2 };
            }
        }
        let x = self.deviation();
        if x.iter().all(|v| v.is_finite()) {
            let y = d[0] - self.base[0];
            for (m, v) in self.mxx.iter_mut().zip([x[0] * x[0], x[0] * x[1], x[1] * x[1]]) {
                *m += w * (v - *m);
            }
            for (m, v) in self.mxy.iter_mut().zip([x[0] * y, x[1] * y]) {
                *m += w * (v - *m);
            }
        }
        for k in 0..2 {
            let m = self.motion[k];
            if m.is_finite() {
                let b = self.motion_base[k];
                self.motion_base[k] = if b.is_finite() { b + w * (m - b) } else { m };
            }
        }
    }

    /// The motion's deviation from its mean over the baseline.
    fn deviation(&self) -> [f64; 2] {
        [self.motion[0] - self.motion_base[0], self.motion[1] - self.motion_base[1]]
    }

    /// The motion at this fix (see `motion`).
    pub fn set_motion(&mut self, motion: [f64; 2]) {
        self.motion = motion;
    }

    /// `departure_by` with the first axis' `d` net of the level's own error
    /// model: its learnt error per unit of the motion's deviation from
    /// the mean motion over the baseline (`error_model`, bounded by `k[0]`
    /// m per (m/s)² of speed² and `k[1]` m per m/s of climb; a part
    /// unknown now moves nothing). A baro's healthy error follows the
    /// motion (dynamic pressure, prop-wash), and a level learnt in calmer
    /// flight read a faster leg's as a departure: battery tune #60 and
    /// #105 (aggressive, 10 Hz) had 50 and 54 false-positive epochs so,
    /// now 0; #133 16 → 1, #137 27 → 37.
    ///
    /// Built for size in the core module: once per GPS epoch (issue 15's
    /// budget).
    #[cfg_attr(navguard_cold_size, optimize(size))]
    pub fn departure_net(&self, k: [f64; 2]) -> f64 {
        self.departure_by(self.modelled(k, self.deviation()))
    }

    /// What the level's error model (`error_model`, bounded by `k`) makes
    /// of a motion change `x` ([speed² (m/s)², climb m/s]), m; a part
    /// unknown moves nothing.
    #[cfg_attr(navguard_cold_size, optimize(size))]
    fn modelled(&self, k: [f64; 2], x: [f64; 2]) -> f64 {
        let c = self.error_model(k);
        (0..2).map(|i| if x[i].is_finite() { c[i] * x[i] } else { 0.0 }).sum()
    }

    /// How far the first axis' healthy error moves from the motion `from`
    /// to `to` (horizontal speed² (m/s)², climb m/s), m, by the level's
    /// own error model (`error_model`, bounded by `k`; a part unknown at
    /// either end moves nothing). None before the baseline has lived
    /// `MIN_AGE_S`: no model is learnt yet.
    pub fn moved_by_motion(&self, k: [f64; 2], from: [f64; 2], to: [f64; 2]) -> Option<f64> {
        if self.age < MIN_AGE_S {
            return None;
        }
        Some(self.modelled(k, [to[0] - from[0], to[1] - from[1]]))
    }

    /// The level's error per unit of motion deviation, least squares over
    /// the moments with a ridge that keeps each coefficient near 0 until
    /// the data outweighs a prior spread of its bound `k[i]` (the moments
    /// are means over about `TAU_S` of fixes, so the prior weighs as one
    /// of them), and clamped to ±`k[i]`.
    fn error_model(&self, k: [f64; 2]) -> [f64; 2] {
        let fixes = (self.age.fmin(TAU_S) / self.dt.fmax(1e-3)).fmax(1.0);
        let var = self.ms[0].fmax(SIGMA_FLOOR_M * SIGMA_FLOOR_M) / fixes;
        let (a, b, d) = (self.mxx[0] + var / (k[0] * k[0]), self.mxx[1], self.mxx[2] + var / (k[1] * k[1]));
        let det = a * d - b * b;
        if !(det > 0.0) {
            return [0.0; 2];
        }
        let c = [(d * self.mxy[0] - b * self.mxy[1]) / det, (a * self.mxy[1] - b * self.mxy[0]) / det];
        [c[0].clamp(-k[0], k[0]), c[1].clamp(-k[1], k[1])]
    }

    /// The last fix's jump off the track is the truth coming back (the end
    /// of a drag-off, whose position and velocity moved together so `d`
    /// held still through it): move the baseline with it, so the fixes
    /// after it are not read as outlying.
    pub fn rebase(&mut self) {
        if let Some(d) = self.d {
            self.dm = d;
        }
        if let Some(j) = self.jump() {
            for a in 0..3 {
                self.base[a] += j[a];
                // The level before the jump was the fault's, from the
                // track's start too: the origin moves with the baseline.
                self.origin[a] += j[a];
            }
            self.outlying = 0.0;
        }
    }

    /// `d`'s short mean off the baseline, in σ of that mean learnt on
    /// normal epochs (the axes combined), over `MEAN_Z`: 1 at the call.
    /// NaN until the baseline has lived `MIN_AGE_S`, once the mean has been
    /// off `NEAR` σ for longer than `ONSET_S` (an onset, not a level), and
    /// on a receiver slower than `MEAN_MAX_DT_S`.
    pub fn mean_departure(&self) -> f64 {
        if self.since_calm > ONSET_S || !(self.dt < MEAN_MAX_DT_S) {
            return f64::NAN;
        }
        self.mean_sigmas() / MEAN_Z
    }

    /// The short mean's departure is no onset until it is calm again: the
    /// jump that moved it was read as a fault's end (the detector's
    /// restart, or the episode's return; battery tune #631: a
    /// 1 m/s vertical drag-off's 23 m return, which the track keeps as a
    /// jump of `d` until it re-learns its baseline, held for 60 s).
    pub fn settle_mean(&mut self) {
        self.since_calm = ONSET_S + 1.0;
    }

    /// `d`'s short mean off the baseline in σ of that mean (the axes
    /// combined); NaN until the baseline has lived `MIN_AGE_S`. Built for
    /// size, not inlined: once per track per GPS epoch (issue 15's budget).
    #[cfg_attr(navguard_cold_size, optimize(size))]
    #[inline(never)]
    pub fn mean_sigmas(&self) -> f64 {
        if self.d.is_none() || self.age < MIN_AGE_S {
            return f64::NAN;
        }
        (0..3).map(|a| ((self.dm[a] - self.base[a]) / self.ms_mean[a].sqrt().fmax(SIGMA_FLOOR_M)).powi(2)).sum::<f64>().sqrt()
    }

    /// `d` (m, NED): the position off its velocity integrated since the
    /// track began. None before its first step.
    pub fn d(&self) -> Option<[f64; 3]> {
        self.d
    }

    /// `d` on the first axis (m): the level a one-axis track follows. None
    /// before its first step.
    pub fn level(&self) -> Option<f64> {
        self.d.map(|d| d[0])
    }

    /// How far the GPS position moved off its own velocity track at the
    /// last fix, m (NED): `d − d_prev`. None before two fixes. A jump of the
    /// receiver shows here; a filter pulled by another sensor does not.
    pub fn jump(&self) -> Option<[f64; 3]> {
        let (d, p) = (self.d?, self.d_prev?);
        Some(core::array::from_fn(|a| d[a] - p[a]))
    }

    /// This fix's jump on the first axis, m, `d` there before it, m, and
    /// whether it took `d` further from both its baseline and its origin (a
    /// departure, not a return). None before two fixes.
    pub fn jump_on_first_axis(&self) -> Option<(f64, f64, bool)> {
        let (d, p) = (self.d?[0], self.d_prev?[0]);
        let away = |c: f64| (d - c).abs() > (p - c).abs();
        Some((d - p, p, away(self.base[0]) && away(self.origin[0])))
    }

    /// σ of the first axis' epoch-to-epoch change, m (0 until learnt).
    pub fn step_sigma(&self) -> f64 {
        self.ms_step[0].sqrt()
    }

    /// How far `d`, its first axis less `moved` m, sits from its learnt
    /// baseline: its σ-normalised distance (the axes combined) over `FAR`,
    /// so 1 at `FAR` σ. NaN until the baseline has lived `MIN_AGE_S`.
    fn departure_by(&self, moved: f64) -> f64 {
        match self.d {
            Some(mut d) if self.age >= MIN_AGE_S => {
                d[0] -= moved;
                self.z(&d) / FAR
            }
            _ => f64::NAN,
        }
    }

    /// Age from which the track judges a jump (s): `QUICK_ORIGIN_S` for a
    /// quick track (see `quick_origin`), else `MIN_AGE_S`.
    fn jumps_from(&self) -> f64 {
        if self.quick_origin { QUICK_ORIGIN_S } else { MIN_AGE_S }
    }

    /// This fix's jump took `d` from within `NEAR` σ of its baseline to
    /// beyond `FAR` σ (the onset of a position fault, the mirror of
    /// `returned`): how far it sits now, over `FAR` σ; NaN otherwise.
    /// The GPS position's track judges it from `QUICK_ORIGIN_S` of age, as
    /// it judges a return to its origin: before `MIN_AGE_S` it has no
    /// outlier rule, so a step it did not call there was learnt as the
    /// track's own wander, and by `MIN_AGE_S` its σ had grown to hide it
    /// (battery eval #63: a 6.63 m vertical step from 27.4 s of the
    /// track's age, σ 0.83 m there, 7.9 m off, 9.6σ; 2.16 m and 2.9σ at
    /// 30 s; all 472 of its epochs missed, now flagged).
    pub fn departed(&self) -> f64 {
        match (self.d, self.d_prev) {
            (Some(d), Some(p)) if self.age >= self.jumps_from() && self.z(&p) < NEAR => {
                let x = self.z(&d) / FAR;
                if x >= 1.0 { x } else { f64::NAN }
            }
            _ => f64::NAN,
        }
    }

    /// `d − base` on axis `a` (m) at this fix and at the previous one, and
    /// σ of that axis (m). None until the baseline has lived `MIN_AGE_S`.
    pub fn offset(&self, a: usize) -> Option<(f64, f64, f64)> {
        match (self.d, self.d_prev) {
            (Some(d), Some(p)) if self.age >= MIN_AGE_S && a < 3 => Some((d[a] - self.base[a], p[a] - self.base[a], self.sigma(a))),
            _ => None,
        }
    }

    /// The baseline of axis `a` moves to this fix's `d`: what remains after
    /// a fault's end is the receiver's slow wander, not the fault.
    pub fn rebase_axis(&mut self, a: usize) {
        if a == 0 {
            self.motion_base = self.motion;
        }
        if let (Some(d), true) = (self.d, a < 3) {
            self.origin[a] += d[a] - self.base[a];
            self.base[a] = d[a];
            self.dm[a] = d[a];
            self.outlying = 0.0;
        }
    }

    /// The fix sits on its own velocity track: within `NEAR` σ of the
    /// learnt baseline, once the baseline has lived `MIN_AGE_S`.
    pub fn on_track(&self) -> bool {
        match self.d {
            Some(d) if self.age >= MIN_AGE_S => self.z(&d) < NEAR,
            _ => false,
        }
    }

    /// This epoch's jump brought `d` from beyond `FAR` σ of its baseline to
    /// within `NEAR` σ, or back to where the track began (`back_to_origin`):
    /// the end of a position fault.
    pub fn returned(&self) -> bool {
        if self.at_origin {
            return true;
        }
        match (self.d, self.d_prev) {
            (Some(d), Some(p)) if self.age >= MIN_AGE_S => self.z(&p) > FAR && self.z(&d) < NEAR,
            _ => false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A track fed `n` epochs of 10 Hz hover whose position error is `e(t)`.
    fn run(track: &mut VelocityTrack, t0: usize, n: usize, e: &dyn Fn(f64) -> [f64; 3]) -> Vec<bool> {
        let dt = 0.1;
        (t0..t0 + n)
            .map(|i| {
                let t = i as f64 * dt;
                track.step(dt, e(t), [0.0; 3], [0.0; 3]);
                let r = track.returned();
                if !r {
                    track.learn();
                }
                r
            })
            .collect()
    }

    /// Under white noise of 2.5 m per fix at 10 Hz, a 10 m step east is
    /// 4 σ of one fix (never `FAR`, so `departed` stays silent) and 11.6 σ
    /// of the short mean after a second, which calls it at its fourth fix; over
    /// 10 minutes of the noise alone the mean calls nothing.
    #[test]
    fn the_short_mean_calls_a_step_a_single_fix_cannot() {
        let mut rng = crate::rng::Rng::new(24);
        let mut tr = VelocityTrack::quick();
        let mut noise = |off: f64| [2.5 * rng.normal(), off + 2.5 * rng.normal(), 5.0 * rng.normal()];
        let mut calls = 0;
        for _ in 0..6000 {
            tr.step(0.1, noise(0.0), [0.0; 3], [0.0; 3]);
            calls += (tr.mean_departure() >= 1.0) as u32;
            tr.learn();
        }
        assert_eq!(calls, 0);
        let (mut first, mut per_fix) = (None, 0);
        for i in 0..10 {
            tr.step(0.1, noise(10.0), [0.0; 3], [0.0; 3]);
            per_fix += (tr.departed() >= 1.0) as u32;
            if first.is_none() && tr.mean_departure() >= 1.0 {
                first = Some(i);
            }
        }
        let first = first.expect("the mean never called the step");
        assert!(first <= 5 && per_fix == 0, "called at the step's fix {first}; {per_fix} per-fix calls");
        assert!(tr.mean_sigmas() > 8.0, "{:.1} σ of the mean", tr.mean_sigmas());
        // Settled (the jump read as a fault's end), it is no onset.
        tr.settle_mean();
        tr.step(0.1, noise(10.0), [0.0; 3], [0.0; 3]);
        assert!(tr.mean_departure().is_nan());
    }

    #[test]
    fn the_end_of_a_followed_ramp_is_a_return_and_a_step_onset_is_not() {
        let wander = |t: f64| [0.8 * (t / 13.0).sin(), 0.8 * (t / 17.0).cos(), 1.5 * (t / 11.0).sin()];
        let mut tr = VelocityTrack::default();
        assert!(!run(&mut tr, 0, 600, &wander).iter().any(|r| *r), "clean wander read as a return");
        // A 0.5 m/s ramp north for 40 s, then the GPS back on the truth.
        let ramp = |t: f64| {
            let w = wander(t);
            [w[0] + 0.5 * (t - 60.0), w[1], w[2]]
        };
        assert!(!run(&mut tr, 600, 400, &ramp).iter().any(|r| *r));
        let back = run(&mut tr, 1000, 100, &wander);
        assert!(back[0] && !back[1..].iter().any(|r| *r), "{back:?}");
        // A 10 m step east from the clean track: an onset, never a return.
        let step = |t: f64| {
            let w = wander(t);
            [w[0], w[1] + 10.0, w[2]]
        };
        assert!(!run(&mut tr, 1100, 300, &step).iter().any(|r| *r));
    }

    /// The GPS position's track (`quick`) learns σ from outlying fixes
    /// too, winsorised at `LEARN_SIGMAS` σ, so a receiver whose wander
    /// outgrows the σ of a calm start is not judged on that σ for good;
    /// the baseline still does not learn them, and a baro level keeps its
    /// σ (its outliers are the baro's faults).
    #[test]
    fn the_gps_track_outgrows_the_sigma_of_a_calm_start() {
        let calm = |t: f64| [0.1 * (t / 1.3).sin(), 0.1 * (t / 1.7).cos(), 0.1 * (t / 1.1).sin()];
        let wide = |t: f64| {
            let c = calm(t);
            [c[0], c[1], c[2] + 3.0 * (t / 7.0).sin()]
        };
        for (quick, grows) in [(true, true), (false, false)] {
            let mut tr = if quick { VelocityTrack::quick() } else { VelocityTrack::default() };
            run(&mut tr, 0, 600, &calm);
            let (s0, base0) = (tr.sigmas()[2], tr.base[2]);
            assert!(s0 < 0.35, "calm σ {s0:.2}");
            run(&mut tr, 600, 600, &wide);
            let s1 = tr.sigmas()[2];
            assert_eq!(s1 > 3.0 * s0, grows, "quick {quick}: σ {s0:.2} -> {s1:.2}");
            if !grows {
                assert_eq!(s1, s0);
            }
            // Only the fixes within 3σ taught the baseline, near the
            // wander's zero crossings.
            assert!((tr.base[2] - base0).abs() < 0.5, "base {base0:.2} -> {:.2}", tr.base[2]);
        }
    }

    /// A jump from on the track to beyond `FAR` σ off it is a departure
    /// at that fix only; a ramp that walks off never jumps, and a return
    /// (from far off to on) is none.
    #[test]
    fn a_jump_off_the_track_is_a_departure_at_that_fix() {
        let wander = |t: f64| [0.8 * (t / 13.0).sin(), 0.8 * (t / 17.0).cos(), 1.5 * (t / 11.0).sin()];
        let mut tr = VelocityTrack::default();
        let dep = |tr: &mut VelocityTrack, x: [f64; 3]| {
            tr.step(0.1, x, [0.0; 3], [0.0; 3]);
            tr.departed()
        };
        // Before the baseline has lived `MIN_AGE_S`, nothing is judged;
        // the GPS position's quick track judges from `QUICK_ORIGIN_S`.
        run(&mut tr, 0, 100, &wander);
        assert!(dep(&mut tr, [20.0, 0.0, 0.0]).is_nan());
        let mut quick = VelocityTrack::quick();
        run(&mut quick, 0, 150, &wander);
        assert!(dep(&mut quick, [20.0, 0.0, 0.0]) > 1.0);
        let mut quick = VelocityTrack::quick();
        run(&mut quick, 0, 90, &wander);
        assert!(dep(&mut quick, [20.0, 0.0, 0.0]).is_nan());
        let mut tr = VelocityTrack::default();
        run(&mut tr, 0, 600, &wander);
        // A 10 m step east: its first fix departs, by its σ-distance over
        // `FAR`; the fixes after it are already off, so none of them.
        let w = wander(60.0);
        let first = dep(&mut tr, [w[0], w[1] + 10.0, w[2]]);
        let sigma = tr.sigmas();
        let d = tr.d().unwrap();
        let z = ((d[0] - tr.base[0]) / sigma[0]).hypot((d[1] - tr.base[1]) / sigma[1]).hypot((d[2] - tr.base[2]) / sigma[2]);
        assert!(first > 1.0 && (first - z / FAR).abs() < 1e-9, "{first:.3} against {:.3}", z / FAR);
        let w = wander(60.1);
        assert!(dep(&mut tr, [w[0], w[1] + 10.0, w[2]]).is_nan());
        // Back on the track: a return, not a departure.
        let w = wander(60.2);
        assert!(dep(&mut tr, w).is_nan());
        // A 0.5 m/s ramp north for 40 s: never a jump off the track.
        let mut tr = VelocityTrack::default();
        run(&mut tr, 0, 600, &wander);
        for i in 0..400 {
            let t = 60.0 + i as f64 * 0.1;
            let w = wander(t);
            assert!(dep(&mut tr, [w[0] + 0.5 * (t - 60.0), w[1], w[2]]).is_nan(), "at {t:.1} s");
        }
    }

    /// A one-axis baro level whose healthy error follows the speed²
    /// (0.012 m per (m/s)², inside the 0.02 bound) learns it over a survey
    /// at 2–8 m/s; a later 16 m/s dash moves the level 2.6 m, which the
    /// plain departure reads as beyond `FAR` σ and the net one does not,
    /// while a 6 m step during the dash still departs net of the model.
    #[test]
    fn a_level_learns_its_error_per_unit_of_motion() {
        const K: [f64; 2] = [0.02, 1.0];
        let speed2 = |t: f64| if t < 400.0 { (5.0 + 3.0 * (t / 9.5).sin()).powi(2) } else { 256.0 };
        let level = |t: f64, extra: f64| 0.012 * speed2(t) + 0.3 * (t / 3.7).sin() + extra;
        let mut tr = VelocityTrack::default();
        let dt = 0.2;
        let (mut net, mut plain) = (0.0_f64, 0.0_f64);
        for i in 0..2050 {
            let t = i as f64 * dt;
            tr.set_motion([speed2(t), 0.0]);
            tr.step(dt, [level(t, 0.0), 0.0, 0.0], [0.0; 3], [0.0; 3]);
            if t > 400.0 {
                net = net.max(tr.departure_net(K));
                plain = plain.max(tr.departure_by(0.0));
            }
            tr.learn();
        }
        assert!(net < 0.5 && plain > 1.0, "net {net:.2}, plain {plain:.2}");
        tr.set_motion([speed2(410.0), 0.0]);
        tr.step(dt, [level(410.0, 6.0), 0.0, 0.0], [0.0; 3], [0.0; 3]);
        assert!(tr.departure_net(K) > 1.0, "{:.2}", tr.departure_net(K));
    }

    /// A level that steps 12 m 8 s after it began learns the step into its
    /// baseline and σ; its jump back to where it began is a return
    /// (`back_to_origin`), while the same jump up from a level that never
    /// left its origin is not.
    #[test]
    fn a_jump_back_to_where_the_track_began_is_a_return() {
        let noise = |t: f64| 0.2 * (t / 1.3).sin();
        let mut stepped = VelocityTrack::default();
        let back = run(&mut stepped, 0, 1000, &|t| [noise(t) + if t >= 8.0 { 12.0 } else { 0.0 }, 0.0, 0.0]);
        assert!(!back.iter().any(|r| *r), "no return while the step lasts");
        let back = run(&mut stepped, 1000, 5, &|t| [noise(t), 0.0, 0.0]);
        assert_eq!(back, [true, false, false, false, false]);
        assert!(stepped.on_track());
        let mut steady = VelocityTrack::default();
        run(&mut steady, 0, 1000, &|t| [noise(t), 0.0, 0.0]);
        let up = run(&mut steady, 1000, 5, &|t| [noise(t) + 12.0, 0.0, 0.0]);
        assert!(!up.iter().any(|r| *r), "{up:?}");
    }

    /// A drift from the first seconds (battery tune #1513: a baro drifting
    /// 0.25 m/s from 8.8 s for 96 s): σ learns the drift and the baseline
    /// lags it, so the baseline never sits `NEAR` σ off the origin. The
    /// jump back to the origin from the drifted level is still a return:
    /// measured on the level before it, and large against the epoch-to-epoch
    /// change. A jump back by half the offset is not.
    #[test]
    fn a_jump_back_to_the_origin_from_a_drift_the_baseline_lagged_is_a_return() {
        let noise = |t: f64| 0.2 * (t / 1.3).sin();
        let drift = |t: f64| noise(t) + 0.25 * (t - 8.0).clamp(0.0, 96.0);
        for (back, end) in [(1.0, true), (0.5, false)] {
            let mut tr = VelocityTrack::default();
            let during = run(&mut tr, 0, 1040, &|t| [drift(t), 0.0, 0.0]);
            assert!(!during.iter().any(|r| *r), "no return while the drift lasts");
            assert!(tr.z(&tr.origin) < NEAR, "the baseline lagged: {:.2} σ", tr.z(&tr.origin));
            let after = run(&mut tr, 1040, 3, &|t| [drift(t) - back * 0.25 * 96.0, 0.0, 0.0]);
            assert_eq!(after, [end, false, false], "back {back}");
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(24))]
        /// A healthy level (white noise of any size about a slow wander,
        /// at any GPS rate) has no fault to come back from: no epoch of
        /// five minutes is a return to the origin, by the baseline's offset
        /// or by the level's.
        #[test]
        fn a_healthy_level_never_returns_to_its_origin(sigma in 0.05f64..3.0, hz in 1.0f64..20.0, wander in 0.0f64..2.0, seed in 0u64..u64::MAX) {
            let mut rng = crate::rng::Rng::new(seed);
            let mut tr = VelocityTrack::default();
            let dt = 1.0 / hz;
            for i in 0..(300.0 * hz) as usize {
                let t = i as f64 * dt;
                let w = wander * libm::sin(t / 40.0);
                let d = [w + sigma * rng.normal(), sigma * rng.normal(), -w + sigma * rng.normal()];
                tr.step(dt, d, [0.0; 3], [0.0; 3]);
                proptest::prop_assert!(!tr.at_origin, "t {t:.1}");
                tr.learn();
            }
        }
    }

    /// After a drag-off's end (rebased), the fixes at the new level are the
    /// track: a later jump back to the drag's level is not a "return".
    #[test]
    fn a_rebased_track_follows_the_jump() {
        let wander = |t: f64| [0.8 * (t / 13.0).sin(), 0.8 * (t / 17.0).cos(), 1.5 * (t / 11.0).sin()];
        let shifted = |t: f64| {
            let w = wander(t);
            [w[0] - 30.0, w[1], w[2]]
        };
        for rebase in [false, true] {
            let mut tr = VelocityTrack::default();
            run(&mut tr, 0, 600, &wander);
            tr.step(0.1, shifted(60.0), [0.0; 3], [0.0; 3]);
            let j = tr.jump().unwrap();
            assert!((j[0] + 30.0).abs() < 0.5 && j[1].abs() < 0.5, "{j:?}");
            if rebase {
                tr.rebase();
            }
            let mut follow = run(&mut tr, 601, 200, &shifted);
            follow.extend(run(&mut tr, 801, 1, &wander));
            // Not rebased: the track still holds the old level, and the
            // jump back to it reads as a return.
            assert_eq!(follow.last(), Some(&!rebase), "rebase {rebase}");
            assert!(!follow[..200].iter().any(|r| *r), "rebase {rebase}");
        }
    }

    #[test]
    fn an_outlier_is_not_learnt_until_it_has_lasted_relearn_s() {
        let mut tr = VelocityTrack::default();
        run(&mut tr, 0, 600, &|_| [0.0; 3]);
        run(&mut tr, 600, 100, &|_| [20.0, 0.0, 0.0]);
        assert_eq!(tr.base, [0.0; 3], "a 10 s outlier moved the baseline");
        run(&mut tr, 700, 1300, &|_| [20.0, 0.0, 0.0]);
        assert!((tr.base[0] - 20.0).abs() < 0.1, "{:?}", tr.base);
    }
}

/// The snapshot codec of this file's state types ([`crate::codec`]): each
/// struct's fields in declaration order (a field left out does not compile;
/// `skip`: not saved, rebuilt on restore).
mod codec_impls {
    use super::*;
    use crate::codec::impl_codec;

    impl_codec!(VelocityTrack { integral, d, d_prev, base, ms, age, outlying, dt, motion, motion_base, mxx, mxy, origin, origin_age, at_origin, ms_step, quick_origin, dm, ms_mean, since_calm });
}
