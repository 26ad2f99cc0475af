//! The force stages: gravity, every listed pair, every wall contact.
//!
//! On one thread each pair's response is added to its two grains as it is
//! computed; on several, `share.rs` adds the same numbers in the same order.

use super::{Blowup, Simulation};

use crate::contact::{ContactLaw, Response, Touch};
use crate::dim::{Dim, Space, Vector};
use crate::integrate::Integrator;
use crate::particles::{Grains, Loads};
use crate::walls::Wall;
use std::sync::Arc;

/// A grain's angular quantities (spin, torque) in `D` dimensions.
pub(super) type Angular<const D: usize> = <Dim<D> as Space<D>>::Angular;

impl<const D: usize, L: ContactLaw<D>, I: Integrator<D>> Simulation<D, L, I>
where
    Dim<D>: Space<D>,
{
    /// The separation `x_i − x_j` of listed pair `k` (across a periodic
    /// face if the list found it there).
    #[inline(always)]
    pub(super) fn separation(&self, k: usize, i: usize, j: usize) -> Vector<D> {
        let r = self.particles.pos[i] - self.particles.pos[j];
        if self.neighbors.shifts.is_empty() {
            r
        } else {
            r - self.neighbors.shifts[k]
        }
    }

    /// The pool to share this step's forces on, if it has one and the
    /// step is long enough to pay for waking it.
    pub(super) fn sharing(&self) -> Option<Arc<rayon::ThreadPool>> {
        self.pool
            .clone()
            .filter(|_| self.neighbors.pairs.len() >= self.min_shared_pairs)
    }

    /// Gravity and every pair on one thread; fails if a pair overlaps
    /// beyond the guard.
    pub(super) fn pair_forces(&mut self) -> Result<(), Blowup> {
        if self.rest.is_some() {
            self.wake.resize(self.particles.len());
        }
        let worst = match (self.periodic.is_some(), self.rest.is_some()) {
            (false, false) => self.pair_forces_serial::<false, false>(),
            (true, false) => self.pair_forces_serial::<true, false>(),
            (false, true) => self.pair_forces_serial::<false, true>(),
            (true, true) => self.pair_forces_serial::<true, true>(),
        };
        self.overlap_guard(worst)
    }

    /// Returns the largest overlap fraction and its pair. With `REST`, a
    /// pair of two resting grains is skipped and the others note whom they wake.
    fn pair_forces_serial<const PERIODIC: bool, const REST: bool>(&mut self) -> (f64, usize) {
        let p = &mut self.particles;
        for (f, m) in p.force.iter_mut().zip(&p.mass) {
            *f = self.gravity * *m;
        }
        for (f, load) in p.force.iter_mut().zip(&p.load) {
            *f += load;
        }
        if L::ROTATES {
            p.torque.fill(Default::default());
        }
        let law = self.pair_law;
        let dt = self.dt;
        let mut worst = (0.0f64, 0usize);
        let nl = &mut self.neighbors;
        let shifts = &nl.shifts;
        let wake_speed2 = self.rest.map_or(0.0, |r| r.speed * r.speed);
        let (g, mut out) = p.split(L::ROTATES, REST);
        for (k, (&[i, j], history)) in nl.pairs.iter().zip(nl.history.iter_mut()).enumerate() {
            let (i, j) = (i as usize, j as usize);
            if REST && g.resting[i] && g.resting[j] {
                continue;
            }
            let r = if PERIODIC {
                g.pos[i] - g.pos[j] - shifts[k]
            } else {
                g.pos[i] - g.pos[j]
            };
            if let Some((response, fraction)) = pair_response(&law, &g, i, j, r, history, dt) {
                if fraction > worst.0 {
                    worst = (fraction, k);
                }
                if REST {
                    self.wake.note(&g, i, j, wake_speed2);
                }
                apply(&mut out, i, j, &response, L::ROTATES);
            }
        }
        worst
    }

    pub(super) fn overlap_guard(&mut self, (worst, pair): (f64, usize)) -> Result<(), Blowup> {
        self.max_overlap_seen = self.max_overlap_seen.max(worst);
        if worst > self.guards.max_overlap {
            let [a, b] = self.neighbors.pairs[pair];
            return Err(Blowup::Overlap {
                a: self.particles.id[a as usize],
                b: self.particles.id[b as usize],
                fraction: worst,
                limit: self.guards.max_overlap,
                time: self.time,
            });
        }
        Ok(())
    }

    /// Every grain touching a wall, walls in order.
    pub(super) fn wall_forces(&mut self) -> Result<(), Blowup> {
        let mut force = std::mem::take(&mut self.particles.force);
        let mut torque = std::mem::take(&mut self.particles.torque);
        let contacts = &mut self.wall_contacts;
        let mine = contacts
            .candidates
            .iter()
            .zip(contacts.history.iter_mut())
            .map(|(c, h)| (&c[..], &mut h[..]));
        let p = &self.particles;
        let pass = walls_pass(
            (&self.walls, &self.wall_laws),
            &p.contact_view(L::ROTATES, !p.resting.is_empty()),
            mine,
            (&mut force[..], &mut torque[..], 0),
            self.dt,
        );
        self.particles.force = force;
        self.particles.torque = torque;
        self.finish_walls(pass)
    }

    /// Notes the deepest wall overlap of a step; fails if a grain is past a wall.
    pub(super) fn finish_walls(&mut self, pass: WallPass) -> Result<(), Blowup> {
        self.max_overlap_seen = self.max_overlap_seen.max(pass.deepest);
        match pass.through {
            Some((w, i)) => Err(Blowup::ThroughWall {
                id: self.particles.id[i],
                wall: w,
                time: self.time,
            }),
            None => Ok(()),
        }
    }

    /// Normal force of every touching pair, for drawing force chains:
    /// `(index i, index j, |F_n|)` with the elastic part only (the state is at rest).
    pub fn contact_forces(&self) -> Vec<(usize, usize, f64)> {
        let g = self.particles.contact_view(L::ROTATES, false);
        let mut out = Vec::new();
        for (k, [i, j]) in self.neighbors.pairs.iter().enumerate() {
            let (i, j) = (*i as usize, *j as usize);
            let r = self.separation(k, i, j);
            let dist = r.norm();
            let overlap = g.radius[i] + g.radius[j] - dist;
            if overlap > 0.0 && dist > 0.0 {
                let mut touch = pair_touch(&g, i, j, r, dist, L::ROTATES);
                touch.normal = r / dist;
                let mut h = self.neighbors.history[k];
                let f = self.pair_law.force(&touch, &mut h, 0.0).force;
                out.push((i, j, f.dot(&touch.normal).abs()));
            }
        }
        out
    }
}

/// The larger overlap of two; on a tie the earlier pair, as one thread finds it.
pub(super) fn worse(a: (f64, usize), b: (f64, usize)) -> (f64, usize) {
    if b.0 > a.0 || (b.0 == a.0 && b.1 < a.1) {
        b
    } else {
        a
    }
}

/// The wall contacts of a step, or of one share of it: the deepest
/// overlap (a fraction of the radius) and the first grain found past its
/// wall, as (wall, grain).
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct WallPass {
    pub(super) deepest: f64,
    pub(super) through: Option<(usize, usize)>,
}

impl WallPass {
    /// Both findings; of two grains past a wall, the one a single thread
    /// meets first (walls in order, grains ascending).
    pub(super) fn join(self, other: WallPass) -> WallPass {
        let through = match (self.through, other.through) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        };
        WallPass {
            deepest: self.deepest.max(other.deepest),
            through,
        }
    }
}

/// Every wall in order against its candidate grains (each with its
/// contact history), added into `out = (force, torque, first)` as
/// [`wall_pass`] does; stops at the first grain found past a wall.
#[inline(always)]
pub(super) fn walls_pass<'h, const D: usize, L: ContactLaw<D>>(
    (walls, laws): (&[Wall<D>], &[L]),
    g: &Grains<'_, D>,
    contacts: impl Iterator<Item = (&'h [u32], &'h mut [L::History])>,
    (force, torque, first): (&mut [Vector<D>], &mut [Angular<D>], usize),
    dt: f64,
) -> WallPass
where
    Dim<D>: Space<D>,
    L::History: 'h,
{
    let mut pass = WallPass::default();
    for (w, ((wall, law), mine)) in walls.iter().zip(laws).zip(contacts).enumerate() {
        let out = (&mut *force, &mut *torque, first);
        pass = pass.join(wall_pass(law, (w, wall), g, mine, out, dt));
        if pass.through.is_some() {
            break;
        }
    }
    pass
}

/// The candidate grains of wall `w` (ascending, each with its contact
/// history) against it: each contact's force and torque is added at
/// `grain − first` of `out = (force, torque, first)`; the pass stops at
/// the first grain found past the plane.
#[inline(always)]
fn wall_pass<const D: usize, L: ContactLaw<D>>(
    law: &L,
    (w, wall): (usize, &Wall<D>),
    g: &Grains<'_, D>,
    (candidates, history): (&[u32], &mut [L::History]),
    (force, torque, first): (&mut [Vector<D>], &mut [Angular<D>], usize),
    dt: f64,
) -> WallPass
where
    Dim<D>: Space<D>,
{
    let mut pass = WallPass::default();
    for (&i, h) in candidates.iter().zip(history) {
        let i = i as usize;
        match wall_response(law, wall, g, i, h, dt) {
            Err(()) => {
                pass.through = Some((w, i));
                break;
            }
            Ok(None) => {}
            Ok(Some((r, fraction))) => {
                pass.deepest = pass.deepest.max(fraction);
                force[i - first] += r.force;
                if L::ROTATES {
                    torque[i - first] += r.torque_i;
                }
            }
        }
    }
    pass
}

/// What `wall` does to grain `i`, and its overlap as a fraction of the
/// radius: `None` if the grain rests (its spring keeps what it held) or
/// does not touch (its spring is reset), an error if its centre is past
/// the plane.
#[inline(always)]
fn wall_response<const D: usize, L: ContactLaw<D>>(
    law: &L,
    wall: &Wall<D>,
    g: &Grains<'_, D>,
    i: usize,
    history: &mut L::History,
    dt: f64,
) -> Result<Option<(Response<D>, f64)>, ()>
where
    Dim<D>: Space<D>,
{
    if g.resting.get(i) == Some(&true) {
        return Ok(None);
    }
    let dist = wall.distance(&g.pos[i]);
    let overlap = g.radius[i] - dist;
    if overlap <= 0.0 || !wall.covers(&g.pos[i]) {
        *history = Default::default();
        return Ok(None);
    }
    if dist < 0.0 {
        return Err(());
    }
    let touch = wall_touch(g, i, wall.normal, overlap, L::ROTATES);
    let response = law.force(&touch, history, dt);
    Ok(Some((response, overlap / g.radius[i])))
}

/// The response of pair `(i, j)` at separation `r` and its overlap as a
/// fraction of the smaller radius, or `None` if it neither touches nor
/// attracts across its gap (its history is then reset).
#[inline(always)]
pub(super) fn pair_response<const D: usize, L: ContactLaw<D>>(
    law: &L,
    g: &Grains<'_, D>,
    i: usize,
    j: usize,
    r: Vector<D>,
    history: &mut L::History,
    dt: f64,
) -> Option<(Response<D>, f64)>
where
    Dim<D>: Space<D>,
{
    let dist2 = r.norm_squared();
    let reach = g.radius[i] + g.radius[j];
    if dist2 >= reach * reach {
        // The contact is open: its spring is gone.
        *history = Default::default();
        if L::ACTS_ACROSS_GAPS {
            let limit = reach + law.range();
            let mut near = dist2 < limit * limit;
            if !near && law.sweeps() {
                // A pair beyond the range may sweep into it within the step,
                // if it closes fast enough: its speed bounds its closing rate.
                let wide = reach + law.gap_reach((g.vel[i] - g.vel[j]).norm());
                near = dist2 < wide * wide;
            }
            if near {
                let touch = pair_touch(g, i, j, r, dist2.sqrt(), L::ROTATES);
                return Some((law.gap_force(&touch), 0.0));
            }
        }
        return None;
    }
    let touch = pair_touch(g, i, j, r, dist2.sqrt(), L::ROTATES);
    let fraction = touch.overlap / touch.radius_i.min(touch.radius_j);
    Some((law.force(&touch, history, dt), fraction))
}

/// The pair `(i, j)` with `r = x_i − x_j` at distance `dist`, seen from `i`.
#[inline(always)]
pub(super) fn pair_touch<const D: usize>(
    g: &Grains<'_, D>,
    i: usize,
    j: usize,
    r: Vector<D>,
    dist: f64,
    rotating: bool,
) -> Touch<D>
where
    Dim<D>: Space<D>,
{
    let (ai, aj) = (g.radius[i], g.radius[j]);
    let (mi, mj) = (g.mass[i], g.mass[j]);
    Touch {
        normal: r * (1.0 / dist),
        overlap: (ai + aj) - dist,
        velocity: g.vel[i] - g.vel[j],
        m_eff: mi * mj / (mi + mj),
        r_eff: ai * aj / (ai + aj),
        radius_i: ai,
        radius_j: aj,
        omega_i: if rotating {
            g.omega[i]
        } else {
            Default::default()
        },
        omega_j: if rotating {
            g.omega[j]
        } else {
            Default::default()
        },
    }
}

/// Grain `i` against a wall with unit normal `normal`: a partner of zero
/// radius and infinite mass that does not turn.
#[inline(always)]
pub(super) fn wall_touch<const D: usize>(
    g: &Grains<'_, D>,
    i: usize,
    normal: Vector<D>,
    overlap: f64,
    rotating: bool,
) -> Touch<D>
where
    Dim<D>: Space<D>,
{
    Touch {
        normal,
        overlap,
        velocity: g.vel[i],
        m_eff: g.mass[i],
        r_eff: g.radius[i],
        radius_i: g.radius[i],
        radius_j: 0.0,
        omega_i: if rotating {
            g.omega[i]
        } else {
            Default::default()
        },
        omega_j: Default::default(),
    }
}

/// Adds a pair's response to both grains.
#[inline(always)]
fn apply<const D: usize>(
    out: &mut Loads<'_, D>,
    i: usize,
    j: usize,
    response: &Response<D>,
    rotating: bool,
) where
    Dim<D>: Space<D>,
{
    out.force[i] += response.force;
    out.force[j] -= response.force;
    if rotating {
        out.torque[i] += response.torque_i;
        out.torque[j] += response.torque_j;
    }
}
