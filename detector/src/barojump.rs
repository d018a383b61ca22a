//! A baro step held from its jump for as long as the baro keeps it.
//!
//! A withheld baro is held off while its levels (`track::VelocityTrack`:
//! the baro against the GPS altitude, and against the GPS vertical
//! velocity integrated) still see it off: `FAR` σ off the Doppler level
//! and `NEAR` σ off the GPS altitude. The second is the witness that tells
//! a baro fault from the end of a GPS vertical drag-off (the Doppler level
//! keeps what a dragged velocity integrated). But a receiver's altitude
//! wanders by metres: at 2.5–3 m horizontal σ, `NEAR` σ of the GPS level
//! is 10–15 m, and a 9–12 m baro step was flagged for its first second and
//! then passed as normal for a minute (battery tune #1316: 9.2 m for 60 s
//! under a 10 Hz Gauss–Markov receiver, 11 of 554 epochs flagged; #455,
//! a 9.9 m step from 28 s for 54 s under a white 3 m receiver, 1 of 544).
//!
//! The step's onset shows what the levels' noise hides later: a jump, in
//! one epoch, of the Doppler level by `FAR` times its own epoch-to-epoch
//! change (the baro's noise and the integral's; a climb moves the baro and
//! the integral alike), matched by the GPS level's jump (within `NEAR`
//! times its own epoch-to-epoch σ, or `BARO_JUMP_AGREE` of the jump: the
//! baro moved, not the GPS). A drag-off integrates; it does not jump. A
//! GPS velocity spike moves the Doppler level alone.
//!
//! Such a jump is remembered, with the Doppler level just before it, when
//! it takes that level further from both its baseline and where it began
//! (a departure: the end of a fault the level learnt jumps back toward
//! them). While the baro is withheld, it stays off for as long as the
//! Doppler level still holds at least `KEPT` of the jump, and not more than
//! `2 − KEPT` of it (a level that went on moving holds a drift or a
//! manoeuvre, not this step: battery eval #275, a fixed wing's Doppler
//! level drifting 10 m after a 2.7 m jump). The Doppler level is precise
//! to decimetres over a minute, so this needs no σ of the GPS altitude.
//!
//! A jump that takes back most of the remembered one (within
//! `track::RETURN_UNDONE` of it), while the level still held it, is its
//! end: it is forgotten, so the end of a step is not remembered as a new
//! one; while the baro is withheld, it is the baro's return (`ended`).
//! The detector usually withholds the baro at the jump's epoch or within a
//! second, so a jump is kept `WAIT_S` while the baro is still fed, and
//! longer while the level holds it. A baro that revives from stuck jumps
//! back onto the truth: that jump is its return (`block`), not a new step.
//!
//! A jump holds for at most `track::RELEARN_S` (120 s), the time after
//! which a level re-learns an outlying baseline as the sensor's new one:
//! the end of a fault the levels learnt (one from the flight's first
//! seconds, or one whose onset was lost) jumps away from them like an
//! onset and is held like one (battery tune #1046, #855, #775: 170–600
//! false-positive epochs each), and the cap bounds what such a hold
//! costs. The detector keeps a baro that is still off withheld when a GPS
//! episode ends or the filter re-anchors (`Withheld::release_unless_baro_off`).
//!
//! While a jump is remembered, the Doppler level integrates the GPS
//! vertical velocity even when the detector withheld it (see the
//! detector's `baro_levels`): the baro's jump moved the filter's climb
//! before the baro was withheld, the GPS velocity then disagreed with the
//! filter, and the filter's climb, integrated instead, took the jump into
//! the level within seconds (battery tune #1617: a 13.6 m step, its
//! Doppler level back to a quarter of it 3 s later; #628).
use crate::drift::{allowance, net_of, K_CLIMB, K_DYN};
use crate::track::{VelocityTrack, FAR, NEAR, RELEARN_S, RETURN_UNDONE};
use crate::window::Motion;
use crate::MinMax;
use serde::{Deserialize, Serialize};

/// Share of the jump the Doppler level must still hold (and at most
/// `2 − KEPT` of it).
const KEPT: f64 = 0.5;
/// Floor of the Doppler level's epoch-to-epoch σ a jump is measured on, m:
/// a level's first epochs learn a σ of centimetres from one change, and a
/// take-off's 0.5 m then passed for a jump (battery tune #1171).
const STEP_FLOOR_M: f64 = 0.3;
/// A jump waits this long for the baro to be withheld, s.
const WAIT_S: f64 = 2.0;
/// A baro jump seen on both levels: they moved by the same amount, within
/// this share of the jump, or within `NEAR` times the GPS level's
/// epoch-to-epoch σ here (the detector's `vertical_return` bounds the
/// difference by the Doppler level's σ: the GPS altitude's own noise at
/// that epoch is in the difference).
pub const BARO_JUMP_AGREE: f64 = 0.3;

/// See the module docs.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BaroJump {
    /// The remembered jump: its size on the Doppler level m, that level
    /// just before it m, and when it came (true s).
    jump: Option<(f64, f64, f64)>,
    /// The baro revived from stuck: its next jump is its return.
    blocked: bool,
    /// The last epoch judged while the baro was withheld jumped back by
    /// most of the remembered jump: the step's end (`epoch`).
    ended: bool,
    /// The motion at the remembered jump: how far the baro's healthy
    /// error may have moved since (`drift::allowance`).
    motion: Motion,
}

impl BaroJump {
    /// The baro revived from stuck (see the module docs).
    pub fn block(&mut self) {
        self.blocked = true;
    }

    /// The levels restarted: nothing they held is left to compare.
    pub fn clear(&mut self) {
        self.jump = None;
    }

    /// Observe the levels at a GPS epoch at `t` s. A jump that takes back
    /// most of the remembered one, while the level still held it, is its
    /// end, and it is forgotten; while the baro is `withheld`, that is the
    /// baro's return (`ended`), which the levels cannot tell when the step
    /// held them from learning for their first 30 s (battery tune #270: a
    /// 12.2 m step from 8 s to 107 s, held to its end, whose return was
    /// then in the baro's 6 s windows for 32 epochs). While the baro is
    /// fed: remember a departing jump, keep the last one while it waits or
    /// holds, or forget it.
    ///
    /// Built for size in the core module: once per GPS epoch (issue 15's
    /// budget).
    #[cfg_attr(navguard_cold_size, optimize(size))]
    pub fn epoch(&mut self, t: f64, gps: &VelocityTrack, dop: &VelocityTrack, withheld: bool, motion: &Motion) {
        let seen = if self.blocked { None } else { jump_of(gps, dop) };
        let undone = match (seen, self.jump) {
            (Some((jn, d0, _)), Some((j, dl, _))) => {
                // `track::undoes` on one axis, written out: calling it
                // costs 33 B of core (issue 15's budget).
                let undo = -jn / j;
                undo >= RETURN_UNDONE.0 && undo <= RETURN_UNDONE.1 && self.kept(d0 - dl, j, dop, motion) > KEPT
            }
            _ => false,
        };
        self.ended = withheld && undone;
        if undone {
            self.clear();
        } else if !withheld {
            let keep = !self.blocked && (self.jump.is_some_and(|(_, _, tj)| t - tj < WAIT_S) || self.held(t, dop, motion) > 1.0);
            if let Some((j, d0, departing)) = seen {
                if departing {
                    self.jump = Some((j, d0, t));
                    self.motion = *motion;
                } else if !keep {
                    self.jump = None;
                }
            } else if !keep {
                self.jump = None;
            }
            self.blocked = false;
        }
    }

    /// The last epoch judged while the baro was withheld was the step's end.
    pub fn ended(&self) -> bool {
        self.ended
    }

    /// A jump is remembered.
    pub fn remembered(&self) -> bool {
        self.jump.is_some()
    }

    /// How much of the remembered jump the Doppler level `dop` still
    /// holds at `t` s, over `KEPT` (so 1 at `KEPT`); NaN with no jump,
    /// `RELEARN_S` after it, or when the level holds more than `2 − KEPT`
    /// of it. The level's change beyond the jump counts net of what the
    /// motion since the jump (from the jump's motion to `now`) moved the
    /// baro's healthy error: by the level's own error model once it has
    /// one (`VelocityTrack::moved_by_motion`), and within the physical
    /// bound (`drift::allowance`) before. A fixed wing's take-off roll
    /// moves its static port's error by metres (battery tune #1379: an
    /// 8.2 m step from 9 s, its Doppler level 4 m further off 6 s later at
    /// 15 m/s, was let go there and missed for 104 s). The bound alone, on
    /// a level that has learnt its model, excused manoeuvres for as long as
    /// a jump may hold (312 more false-positive epochs over six battery
    /// sets, most on tune #1047, #731, #296, #107 and eval #224). Neither tells the
    /// return of a drift the levels learnt from a step (tune #1110, held
    /// for its last 80 s).
    #[inline(never)]
    #[cfg_attr(navguard_cold_size, optimize(size))]
    pub fn held(&self, t: f64, dop: &VelocityTrack, now: &Motion) -> f64 {
        let share = self.jump.filter(|(_, _, tj)| t - tj < RELEARN_S).map_or(f64::NAN, |(j, d0, _)| self.kept(dop.level().unwrap_or(d0) - d0, j, dop, now));
        if share < 2.0 - KEPT { share / KEPT } else { f64::NAN }
    }

    /// The share of the jump `j` m that a change `moved` m of the Doppler
    /// level `dop` since it holds, net of the motion since the jump (see
    /// `held`): 1 when the level moved by the jump give or take what the
    /// motion explains.
    fn kept(&self, moved: f64, j: f64, dop: &VelocityTrack, now: &Motion) -> f64 {
        let (from, to) = ([self.motion.speed2, self.motion.climb], [now.speed2, now.climb]);
        let (model, slack) = match dop.moved_by_motion([K_DYN, K_CLIMB], from, to) {
            Some(m) => (m, 0.0),
            None => (0.0, allowance(&self.motion, now)),
        };
        1.0 + net_of(moved - j - model, slack.fmax(0.0)) / j
    }
}

/// This epoch's jump of the baro on both levels (see the module docs): its
/// size on the Doppler level m, that level before it m, and whether it
/// departs from the level's baseline and origin.
fn jump_of(gps: &VelocityTrack, dop: &VelocityTrack) -> Option<(f64, f64, bool)> {
    let ((jg, ..), (jd, d0, departs)) = (gps.jump_on_first_axis()?, dop.jump_on_first_axis()?);
    let agree = (jd - jg).abs() < (NEAR * gps.step_sigma()).fmax(BARO_JUMP_AGREE * jd.abs());
    (jd.abs() > FAR * dop.step_sigma().fmax(STEP_FLOOR_M) && agree).then_some((jd, d0, departs))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two levels fed `n` epochs of 5 Hz hover from epoch `k0`: the GPS
    /// level's value is the baro offset plus the GPS altitude's noise
    /// `g(k)`, the Doppler level's the offset plus a small noise `e(k)`.
    /// Returns `held` at each epoch, the baro counted withheld from the
    /// jump's epoch on when `withhold`.
    fn run(levels: &mut (VelocityTrack, VelocityTrack), bj: &mut BaroJump, k0: usize, n: usize, off: &dyn Fn(usize) -> f64, withhold: bool) -> Vec<f64> {
        let dt = 0.2;
        let mut rng = crate::rng::Rng::new(7 + k0 as u64);
        let mut withheld = false;
        (k0..k0 + n)
            .map(|k| {
                let (g, e) = (3.0 * rng.normal(), 0.05 * rng.normal());
                levels.0.step(dt, [off(k) + g, 0.0, 0.0], [0.0; 3], [0.0; 3]);
                levels.1.step(dt, [off(k) + e, 0.0, 0.0], [0.0; 3], [0.0; 3]);
                bj.epoch(k as f64 * dt, &levels.0, &levels.1, withheld, &Motion::default());
                withheld |= withhold && bj.jump.is_some();
                if !withheld {
                    levels.0.learn();
                    levels.1.learn();
                }
                bj.held(k as f64 * dt, &levels.1, &Motion::default())
            })
            .collect()
    }

    /// A 10 m step under a 3 m noisy GPS altitude is held, by the Doppler
    /// level, for the whole 60 s (300 epochs) of it, well above 1; with no
    /// step nothing is remembered; a jump back forgets it.
    #[test]
    fn a_step_is_held_until_its_return() {
        let mut levels = (VelocityTrack::default(), VelocityTrack::default());
        let mut bj = BaroJump::default();
        let calm = run(&mut levels, &mut bj, 0, 300, &|_| 0.0, true);
        assert!(calm.iter().all(|h| h.is_nan()), "a healthy baro remembered a jump");
        let step = run(&mut levels, &mut bj, 300, 300, &|_| 10.0, true);
        assert!(step.iter().all(|h| (1.8..2.2).contains(h)), "held {:?}", &step[..5]);
        // The step's end: the baro jumps back (observed while fed again).
        let back = run(&mut levels, &mut bj, 600, 5, &|_| 0.0, false);
        assert!(back.iter().all(|h| h.is_nan()), "the return was kept: {back:?}");
        assert_eq!(bj.jump, None);
    }

    /// A baro that revives from stuck jumps back onto the truth: that jump
    /// is not remembered. Without `block` it is (the test fails).
    #[test]
    fn a_revived_baro_is_not_a_new_step() {
        for (blocked, want) in [(false, true), (true, false)] {
            let mut levels = (VelocityTrack::default(), VelocityTrack::default());
            let mut bj = BaroJump::default();
            run(&mut levels, &mut bj, 0, 300, &|_| 0.0, false);
            if blocked {
                bj.block();
            }
            run(&mut levels, &mut bj, 300, 1, &|_| 12.0, false);
            assert_eq!(bj.jump.is_some(), want, "blocked {blocked}");
        }
    }

    /// A step longer than `RELEARN_S` is held for that long, then no more.
    #[test]
    fn a_jump_holds_for_at_most_relearn_s() {
        let mut levels = (VelocityTrack::default(), VelocityTrack::default());
        let mut bj = BaroJump::default();
        run(&mut levels, &mut bj, 0, 300, &|_| 0.0, true);
        let h = run(&mut levels, &mut bj, 300, 650, &|_| 10.0, true);
        // 5 Hz: epoch 595 is 119 s after the jump, 605 is 121 s.
        assert!(h[595] > 1.8 && h[605].is_nan(), "{} {}", h[595], h[605]);
    }

    /// A level that goes on moving past `2 − KEPT` of the jump holds more
    /// than this step: not held by it.
    #[test]
    fn a_level_that_kept_moving_is_not_held_by_the_jump() {
        let mut levels = (VelocityTrack::default(), VelocityTrack::default());
        let mut bj = BaroJump::default();
        run(&mut levels, &mut bj, 0, 300, &|_| 0.0, true);
        let h = run(&mut levels, &mut bj, 300, 100, &|k| 5.0 + 0.1 * (k - 300) as f64, true);
        assert!(h[0] > 1.0 && h[4] > 1.0, "{:?}", &h[..5]);
        assert!(h[99].is_nan(), "a 15 m level held by a 5 m jump: {}", h[99]);
    }
}

/// The snapshot codec of this file's state type ([`crate::codec`]).
mod codec_impls {
    use super::*;
    use crate::codec::impl_codec;

    impl_codec!(BaroJump { jump, blocked, ended, motion });
}
