//! The window the two slow tests share: the baro's drift (`drift`) and the
//! position's ramp (`ramp`).
//!
//! Each judges the change of a smoothed level over the last `SPAN_S` (true
//! time, or longer while the start is held) against the level at the
//! window's start, and the change over the
//! last `RECENT_S` for its rate. The start is kept from normal epochs only
//! (`enter`), so while a fault is flagged it stays on the level from before
//! the fault (the drift test also holds it while it suspects one, see
//! `drift`); the first normal epoch after a gap of `RESTART_S` (another
//! sensor's episode) restarts it, as its start may sit in that fault's
//! unflagged onset; a start older than `MAX_REF_S` is dropped, so a long
//! episode does not judge the level against one from minutes ago. The
//! recent span takes every epoch (`note`). Entries are kept at most one per
//! `STEP_S`, so the cost and the statistics do not depend on the GPS rate.
//!
//! Their σ are learnt the same way too (`learn_ms`): slowly, from a prior,
//! winsorised at 3σ, so a fault growing inside the window cannot teach it
//! its own size. At a call, the window's entries date the change's onset
//! (`onset_age`) for the whole-log reconciled verdict.
use crate::MinMax;
use serde::{Deserialize, Serialize};

/// The window, true s.
pub const SPAN_S: f64 = 30.0;
/// The recent span, true s.
pub const RECENT_S: f64 = 15.0;
/// Time constant of σ's learning, true s.
pub const TAU_S: f64 = 120.0;
/// Spacing of entries, true s.
const STEP_S: f64 = 1.0;
/// A gap this long between normal epochs restarts the window, true s.
const RESTART_S: f64 = 5.0;
/// Oldest window start kept while no normal epoch comes, true s.
const MAX_REF_S: f64 = 120.0;
/// Least share of a level's variance over the window that the hinge of
/// `Window::onset_age` explains for its onset to be dated.
const ONSET_R2: f64 = 0.75;

/// The vehicle's motion at an epoch (what the baro's healthy error moves
/// with; see `drift`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Motion {
    /// Horizontal speed squared, m²/s².
    pub speed2: f64,
    /// Climb rate, m/s (up).
    pub climb: f64,
    /// Height above the first fix, m.
    pub height: f64,
    /// Horizontal ground velocity (north, east), m/s.
    pub v_ne: [f64; 2],
}

/// One entry: true s, the level's components (m), the motion.
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize)]
pub struct Entry {
    /// True time, s.
    pub t: f64,
    /// The level (m): up to three components, unused ones 0.
    pub x: [f64; 3],
    /// The motion at that epoch.
    pub motion: Motion,
}

/// See the module docs.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Window {
    /// Normal epochs' entries, oldest first.
    ring: Vec<Entry>,
    /// Every epoch's entries over the last `RECENT_S`.
    recent: Vec<Entry>,
}

/// Append `e` if it is `STEP_S` past the last entry, then drop the oldest
/// while the next one is at least `span` old.
fn keep(v: &mut Vec<Entry>, e: Entry, span: f64) {
    if v.last().is_none_or(|l| e.t - l.t >= STEP_S) {
        v.push(e);
    }
    while v.len() > 2 && e.t - v[1].t >= span {
        v.remove(0);
    }
}

impl Window {
    /// Empty both spans (the level restarted).
    pub fn clear(&mut self) {
        self.ring.clear();
        self.recent.clear();
    }

    /// A fresh window start (a fault judged on it is over).
    pub fn restart(&mut self) {
        self.ring.clear();
    }

    /// Every epoch: `e` joins the recent span. Returns the window's start
    /// when it is at least `SPAN_S` old, and the recent span's start when
    /// it is at least half of `RECENT_S` old.
    ///
    /// Built for size in the core module: once per GPS epoch (issue 15's
    /// budget).
    #[cfg_attr(navguard_cold_size, optimize(size))]
    pub fn note(&mut self, e: Entry) -> (Option<Entry>, Option<Entry>) {
        keep(&mut self.recent, e, RECENT_S);
        if self.ring.first().is_some_and(|s| e.t - s.t > MAX_REF_S) {
            self.ring.clear();
        }
        let start = self.ring.first().filter(|s| e.t - s.t >= SPAN_S).copied();
        let recent = self.recent.first().filter(|r| e.t - r.t >= 0.5 * RECENT_S).copied();
        (start, recent)
    }

    /// A normal epoch's entry joins the window, whose start is kept at
    /// most `span` true s back (`SPAN_S`; longer holds it, see `drift`).
    /// Built for size in the core module (issue 15's budget: the span
    /// argument cost 11 B over it inlined).
    #[cfg_attr(navguard_cold_size, optimize(size))]
    pub fn enter(&mut self, e: Entry, span: f64) {
        if self.ring.last().is_some_and(|l| e.t - l.t > RESTART_S) {
            self.ring.clear();
        }
        keep(&mut self.ring, e, span);
    }

    /// The window's start (its oldest normal entry), if any.
    pub fn start(&self) -> Option<Entry> {
        self.ring.first().copied()
    }

    /// How long before `e` (true s) the change the window judges at `e`
    /// began: the hinge, flat and then a straight line to `e`, that fits
    /// `level` over the window's entries and `e` best by least squares. A
    /// change under way from the window's start dates from it (the hinge
    /// at the first entry is the straight line). None when the best hinge
    /// explains less than `ONSET_R2` of the level's variance: a healthy
    /// error that wandered before the fault (a Gauss–Markov baro, a
    /// step after a swing) has no onset this shape tells. For the
    /// whole-log reconciled verdict (`Dating`): a slow fault is called
    /// once it has grown over the window, seconds after it began. Only at
    /// a call: O(entries²), at most `MAX_REF_S` entries.
    pub fn onset_age(&self, e: &Entry, level: impl Fn(&Entry) -> f64) -> Option<f64> {
        let pts: Vec<(f64, f64)> = self.ring.iter().chain(core::iter::once(e)).map(|p| (p.t, level(p))).collect();
        let n = pts.len() as f64;
        let sy: f64 = pts.iter().map(|p| p.1).sum();
        let mean = sy / n;
        let syy: f64 = pts.iter().map(|p| (p.1 - mean) * (p.1 - mean)).sum();
        let mut best = (0.0, e.t);
        for &(tau, _) in &pts[..pts.len() - 1] {
            // y regressed on h = max(0, t − τ): the fit's gain over a flat
            // line is cov(h, y)² / var(h) (sums, not means, as n is common).
            let (mut sh, mut shh, mut shy) = (0.0, 0.0, 0.0);
            for &(t, y) in &pts {
                let h = (t - tau).fmax(0.0);
                sh += h;
                shh += h * h;
                shy += h * y;
            }
            let (var, cov) = (shh - sh * sh / n, shy - sh * sy / n);
            if var > 0.0 && cov > 0.0 && cov * cov / var > best.0 {
                best = (cov * cov / var, tau);
            }
        }
        (best.0 >= ONSET_R2 * syy && syy > 0.0).then_some(e.t - best.1)
    }
}

/// The largest of a series over about the last `span` s: the value held
/// until a larger one comes or it is `span` old (then the current value
/// takes over, so an older, smaller peak in between is forgotten early).
/// Two numbers, not a ring: it scales a test's σ by the worst accuracy the
/// receiver claimed over the test's window (see
/// `IndicatorEngine::set_speed_claim`), where a little early forgetting
/// only flags sooner.
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize)]
pub struct RecentMax {
    value: f64,
    t: f64,
}

impl RecentMax {
    /// Note `x` at time `t` (s); returns the held largest (NaN `x` counts
    /// as none: the held value stays).
    pub fn push(&mut self, t: f64, x: f64, span: f64) -> f64 {
        if x >= self.value || (t - self.t > span && !x.is_nan()) {
            (self.value, self.t) = (x, t);
        }
        self.value
    }

    /// The held largest (0 before any).
    pub fn value(&self) -> f64 {
        self.value
    }
}

/// One learning step of a mean square: `ms` (0 before any: the current σ
/// `sg` stands in), from a change `s`, winsorised at 3σ, with weight `w`.
pub fn learn_ms(ms: f64, s: f64, sg: f64, w: f64) -> f64 {
    let ms = if ms > 0.0 { ms } else { sg * sg };
    ms + w * ((s * s).fmin(9.0 * sg * sg) - ms)
}

/// σ (m) of a window test's axis: its learnt mean square `ms` (the prior
/// `sigma0` before any), never below `floor` nor the receiver's accuracy
/// `claim` (NaN when it gives none).
pub fn sigma_of(ms: f64, sigma0: f64, floor: f64, claim: f64) -> f64 {
    let ms = if ms > 0.0 { ms } else { sigma0 * sigma0 };
    let s = ms.sqrt().fmax(floor);
    if claim > s { claim } else { s }
}

/// A normal epoch's learning step on both axes of a window test: each
/// finite change in `last` teaches its mean square in `ms`, winsorised at
/// its σ in `sigma`, with weight `w`.
pub fn learn_axes(ms: &mut [f64; 2], last: &[f64; 2], sigma: [f64; 2], w: f64) {
    for k in 0..2 {
        if last[k].is_finite() {
            ms[k] = learn_ms(ms[k], last[k], sigma[k], w);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(t: f64, x: f64) -> Entry {
        Entry { t, x: [x, 0.0, 0.0], motion: Motion::default() }
    }

    #[test]
    fn recent_max_holds_a_peak_for_its_span_then_follows_the_series() {
        let mut m = RecentMax::default();
        let xs = [1.0, 4.0, 2.0, f64::NAN, 3.0, 1.5, 1.2];
        let held: Vec<f64> = xs.iter().enumerate().map(|(i, &x)| m.push(i as f64, x, 2.5)).collect();
        // 4 at t = 1 is held to t = 3.5; at t = 4 the current 3 takes over
        // (NaN at t = 3 changed nothing), then 3 is held to t = 6.5.
        assert_eq!(held, [1.0, 4.0, 4.0, 4.0, 3.0, 3.0, 3.0]);
        assert_eq!(m.push(7.0, 1.1, 2.5), 1.1);
    }

    #[test]
    fn the_start_is_the_newest_normal_entry_a_span_old_and_restarts_after_a_gap() {
        let mut w = Window::default();
        for i in 0..=400 {
            let e = at(i as f64 * 0.1, i as f64);
            w.note(e);
            w.enter(e, SPAN_S);
        }
        // At 40 s: the start is 30 s back (entries are a second apart).
        let (start, recent) = w.note(at(40.1, 0.0));
        assert_eq!(start.map(|s| s.t), Some(10.0));
        assert_eq!(recent.map(|r| r.t), Some(25.0));
        // No normal epoch for 20 s: the start stays; the first normal one
        // after the gap restarts the window.
        let (start, _) = w.note(at(60.0, 0.0));
        assert_eq!(start.map(|s| s.t), Some(10.0));
        w.enter(at(60.0, 0.0), SPAN_S);
        assert_eq!(w.note(at(60.1, 0.0)).0.map(|s| s.t), None);
        // A start older than MAX_REF_S is dropped.
        let mut w = Window::default();
        w.enter(at(0.0, 0.0), SPAN_S);
        assert!(w.note(at(119.0, 0.0)).0.is_some() && w.note(at(121.0, 0.0)).0.is_none());
    }

    /// A window of `n` entries a second apart, with level `f(t)`.
    fn filled(n: usize, f: impl Fn(f64) -> f64) -> (Window, Entry) {
        let mut w = Window::default();
        for i in 0..n {
            w.enter(at(i as f64, f(i as f64)), f64::INFINITY);
        }
        (w, at(n as f64, f(n as f64)))
    }

    #[test]
    fn the_onset_of_a_change_is_the_hinge_that_fits_it() {
        // Flat at 0 with ±0.3 of alternating noise, then 0.5 per second
        // from 25 s; judged at 40 s: it began 15 s before.
        let noise = |t: f64| if (t as i64) % 2 == 0 { 0.3 } else { -0.3 };
        let (w, e) = filled(40, |t| noise(t) + 0.5 * (t - 25.0).max(0.0));
        let age = w.onset_age(&e, |p| p.x[0]).unwrap();
        assert!((age - 15.0).abs() <= 1.0, "age {age}");
        // A change under way from the start dates from the window's start.
        let (w, e) = filled(30, |t| noise(t) + 0.5 * t);
        let age = w.onset_age(&e, |p| p.x[0]).unwrap();
        assert!((age - 30.0).abs() <= 1.0, "age {age}");
        // A level that wandered up and down before it rose has no onset
        // the hinge tells (it explains under `ONSET_R2` of the variance).
        let (w, e) = filled(40, |t| 5.0 * (t / 5.0).sin() + 0.5 * (t - 30.0).max(0.0));
        assert_eq!(w.onset_age(&e, |p| p.x[0]), None);
    }

    #[test]
    fn learning_is_winsorised_at_three_sigma() {
        assert!((learn_ms(0.0, 1.0, 2.0, 0.5) - (4.0 + 0.5 * (1.0 - 4.0))).abs() < 1e-12);
        assert!((learn_ms(4.0, 100.0, 2.0, 0.1) - (4.0 + 0.1 * (36.0 - 4.0))).abs() < 1e-12);
    }
}

/// The snapshot codec of this file's state ([`crate::codec`]).
mod codec_impls {
    use super::*;
    use crate::codec::impl_codec;

    impl_codec!(Motion { speed2, climb, height, v_ne });
    impl_codec!(Entry { t, x, motion });
    impl_codec!(Window { ring, recent });
    impl_codec!(RecentMax { value, t });
}
