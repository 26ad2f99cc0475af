//! Grains at rest, as rigid-body engines put bodies to sleep.
//!
//! A poured heap is mostly still: only its surface and the falling grains
//! move. With a [`RestRule`], a grain that has stayed slower than the
//! rule's speed (in translation and at its rim in rotation) for the rule's
//! number of steps is put to rest: its velocities are set to zero, the
//! integrator skips it, and a pair of two resting grains is not evaluated
//! at all (its spring keeps what it held). A pair with one resting grain is
//! evaluated as usual, and wakes the resting grain when the other grain
//! touches it (or attracts it across a gap) while moving faster than the
//! rule's speed. So a resting bed holds whatever lands on it gently, and an
//! avalanche or an impact wakes what it reaches.
//!
//! What this costs in accuracy: a resting grain does not respond to slow
//! loading (a grain creeping onto it below the threshold, or the slow
//! rearrangement of the bed under a growing heap). How much that moves an
//! angle of repose or a packing fraction is measured, not assumed
//! (`docs/benchmarks.md`). The decisions are taken once a step, in index
//! order, from the state alone: a run with rest is as deterministic, and as
//! independent of the thread count, as one without.

use super::Simulation;
use crate::contact::ContactLaw;
use crate::dim::{Dim, Space, Vector};
use crate::integrate::Integrator;
use crate::particles::Grains;
use std::sync::atomic::{AtomicBool, Ordering};

/// When grains are put to rest and woken.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RestRule {
    /// A grain slower than this (centre, and rim from its spin) is still;
    /// a grain faster than this wakes the resting grains it touches.
    pub speed: f64,
    /// Steps a grain must stay still in a row before it is put to rest:
    /// longer than `2 speed / g`, or a grain at the top of its flight (or
    /// released from rest in the air) is put to rest there.
    pub steps: u32,
}

/// Per-grain flags raised during the pair loop for grains to wake at the
/// end of the step (set from any thread; the order of setting is irrelevant).
#[derive(Debug, Default)]
pub(super) struct Wake {
    flags: Vec<AtomicBool>,
}

impl Wake {
    pub(super) fn resize(&mut self, n: usize) {
        if self.flags.len() != n {
            self.flags = (0..n).map(|_| AtomicBool::new(false)).collect();
        }
    }

    /// Notes a pair `(i, j)` that touches or attracts: if exactly one of
    /// the two rests and the other moves faster than `speed2` (squared),
    /// the resting one is to wake.
    #[inline(always)]
    pub(super) fn note<const D: usize>(&self, g: &Grains<'_, D>, i: usize, j: usize, speed2: f64)
    where
        Dim<D>: Space<D>,
    {
        let (ri, rj) = (g.resting[i], g.resting[j]);
        if ri != rj {
            let (sleeper, mover) = if ri { (i, j) } else { (j, i) };
            if g.vel[mover].norm_squared() > speed2 {
                self.flags[sleeper].store(true, Ordering::Relaxed);
            }
        }
    }

    fn take(&mut self, i: usize) -> bool {
        std::mem::replace(self.flags[i].get_mut(), false)
    }
}

impl<const D: usize, L: ContactLaw<D>, I: Integrator<D>> Simulation<D, L, I>
where
    Dim<D>: Space<D>,
{
    /// Puts grains to rest by `rule` from now on (none: every grain is
    /// integrated, the default). Every grain starts awake.
    pub fn set_rest(&mut self, rule: Option<RestRule>) {
        self.rest = rule;
        self.particles.track_rest(rule.is_some());
    }

    /// How many grains are at rest.
    pub fn resting(&self) -> usize {
        self.particles.resting.iter().filter(|r| **r).count()
    }

    /// The end of a step: wakes the grains flagged by the pair loop, and
    /// puts to rest those that have been still long enough. Returns how
    /// many grains rested during the step.
    pub(super) fn update_rest(&mut self) -> u64 {
        let Some(rule) = self.rest else {
            return 0;
        };
        let mut rested = 0;
        let p = &mut self.particles;
        let limit = rule.speed * rule.speed;
        for i in 0..p.len() {
            if p.resting[i] {
                rested += 1;
                if self.wake.take(i) {
                    p.resting[i] = false;
                    p.still[i] = 0;
                    // What the loop left here lacks the resting pairs.
                    p.force[i] = Vector::<D>::zeros();
                    if p.rotating() {
                        p.torque[i] = Default::default();
                    }
                }
                continue;
            }
            let mut still = p.vel[i].norm_squared() < limit;
            if still && p.rotating() {
                let spin = <Dim<D> as Space<D>>::angular_norm_squared(p.omega[i]);
                still = spin * p.radius[i] * p.radius[i] < limit;
            }
            p.still[i] = if still { p.still[i] + 1 } else { 0 };
            if p.still[i] >= rule.steps {
                p.resting[i] = true;
                p.vel[i] = Vector::<D>::zeros();
                if p.rotating() {
                    p.omega[i] = Default::default();
                }
            }
        }
        rested
    }
}
