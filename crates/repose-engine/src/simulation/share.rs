//! The pair loop on several threads, with the bits of one thread.
//!
//! The grains are cut into contiguous index ranges, one per thread, with
//! about as many pairs each; after spatial ordering a range is a slab of
//! space. Pairs are sorted by their first grain, so each range owns a
//! contiguous block of pairs. A pair whose second grain lies in a later
//! range crosses. One thread adds its pairs to each grain in list order;
//! to add the same numbers in the same order:
//!
//! 1. every thread computes the responses of its crossing pairs;
//! 2. every thread starts its grains from gravity (and load), adds what
//!    the crossing pairs of earlier ranges give them (those pairs come
//!    first in list order), then walks its own block in order: a pair
//!    inside the range is computed and added to both grains, a crossing
//!    pair adds its stored response to its first grain; then the range's
//!    grains meet the walls, wall by wall, as the wall stage of one thread
//!    adds them after every pair. A step so makes two passes over the pool,
//!    not one for the pairs and another for the walls.

use super::forces::{pair_response, walls_pass, worse, Angular, WallPass};
use super::rest::Wake;
use super::{Blowup, Simulation};
use crate::contact::{ContactLaw, Response};
use crate::dim::{Dim, Space, Vector};
use crate::integrate::Integrator;
use crate::particles::{Grains, Particles};
use crate::walls::Wall;
use rayon::prelude::*;
use std::ops::Range;

/// A share's crossing responses and its largest overlap.
type Crossing<const D: usize> = (Vec<Option<Response<D>>>, (f64, usize));

/// Shares of the grains per thread: two let a thread that finishes a cheap
/// share take another (a dense bed below, falling grains above), and each
/// share more adds a boundary whose crossing pairs cost a second visit
/// (two ran the bench heap 10–15 % faster than four; `docs/benchmarks.md`).
const SHARES_PER_THREAD: usize = 2;

/// How the current pair list is shared among the threads.
#[derive(Debug, Default)]
pub(super) struct Shares {
    /// The list build, grain count and thread count these shares were planned for.
    planned_for: Option<(u64, usize, usize)>,
    parts: Vec<Share>,
}

/// One thread's grains and pairs.
#[derive(Debug, Clone, Default)]
struct Share {
    grains: Range<usize>,
    pairs: Range<usize>,
    /// Pairs of the block whose second grain lies in a later share, ascending.
    cross: Vec<usize>,
    /// Crossing pairs of earlier shares that end in this one, as
    /// (share, index into its `cross`), sorted by (second grain, pair).
    incoming: Vec<(usize, usize)>,
}

impl Shares {
    /// Cuts `n` grains and their sorted `pairs` into `count` shares.
    fn plan(pairs: &[[u32; 2]], n: usize, count: usize) -> Vec<Share> {
        let total = pairs.len();
        let mut bounds = vec![0usize];
        for t in 1..count {
            let k = t * total / count;
            let start = pairs.get(k).map_or(n, |p| p[0] as usize);
            bounds.push(start.max(*bounds.last().unwrap_or(&0)));
        }
        bounds.push(n);
        let mut parts: Vec<Share> = bounds
            .windows(2)
            .map(|w| {
                let first = pairs.partition_point(|p| (p[0] as usize) < w[0]);
                let last = pairs.partition_point(|p| (p[0] as usize) < w[1]);
                let cross = (first..last)
                    .filter(|&k| pairs[k][1] as usize >= w[1])
                    .collect();
                Share {
                    grains: w[0]..w[1],
                    pairs: first..last,
                    cross,
                    incoming: Vec::new(),
                }
            })
            .collect();
        let owner = |g: usize| bounds[1..].partition_point(|&b| b <= g);
        // (second grain, pair, share, index into the share's crossing pairs)
        let mut incoming: Vec<Vec<(usize, usize, usize, usize)>> = vec![Vec::new(); parts.len()];
        for (t, share) in parts.iter().enumerate() {
            for (idx, &k) in share.cross.iter().enumerate() {
                let j = pairs[k][1] as usize;
                incoming[owner(j)].push((j, k, t, idx));
            }
        }
        for (share, mut list) in parts.iter_mut().zip(incoming) {
            list.sort_unstable_by_key(|e| (e.0, e.1));
            share.incoming = list.into_iter().map(|e| (e.2, e.3)).collect();
        }
        parts
    }
}

impl<const D: usize, L: ContactLaw<D>, I: Integrator<D>> Simulation<D, L, I>
where
    Dim<D>: Space<D>,
{
    /// Gravity, every pair and every wall contact on the thread pool, in
    /// one pass: each share ends with its grains' wall contacts, in wall
    /// order, as the wall stage of one thread adds them after every pair.
    pub(super) fn shared_forces(&mut self, pool: &rayon::ThreadPool) -> Result<(), Blowup> {
        let n = self.particles.len();
        if self.rest.is_some() {
            self.wake.resize(n);
        }
        let key = (self.neighbors.builds, n, pool.current_num_threads());
        if self.shares.planned_for != Some(key) {
            // More shares than threads: the pool balances shares of unequal
            // cost (a dense bed below, falling grains above).
            let shares = SHARES_PER_THREAD * pool.current_num_threads();
            self.shares.parts = Shares::plan(&self.neighbors.pairs, n, shares);
            self.shares.planned_for = Some(key);
        }
        // Forces and torques are written share by share; everything else is read.
        let mut force = std::mem::take(&mut self.particles.force);
        let mut torque = std::mem::take(&mut self.particles.torque);
        let p = &self.particles;
        let ctx = Context {
            p,
            g: p.contact_view(L::ROTATES, !p.resting.is_empty()),
            law: self.pair_law,
            dt: self.dt,
            gravity: self.gravity,
            pairs: &self.neighbors.pairs,
            shifts: &self.neighbors.shifts,
            parts: &self.shares.parts,
            rest: self.rest.map(|r| (&self.wake, r.speed * r.speed)),
            walls: &self.walls,
            wall_laws: &self.wall_laws,
            candidates: &self.wall_contacts.candidates,
        };
        let out = Out {
            history: &mut self.neighbors.history,
            force: &mut force,
            torque: &mut torque,
            walls: &mut self.wall_contacts.history,
        };
        let (worst, walls) = pool.install(|| ctx.run(out));
        self.particles.force = force;
        self.particles.torque = torque;
        self.overlap_guard(worst)?;
        self.finish_walls(walls)
    }
}

/// What every share reads.
struct Context<'a, const D: usize, L: ContactLaw<D>>
where
    Dim<D>: Space<D>,
{
    p: &'a Particles<D>,
    /// The grains as contacts read them (forces and torques are taken out).
    g: Grains<'a, D>,
    law: L,
    dt: f64,
    gravity: Vector<D>,
    pairs: &'a [[u32; 2]],
    shifts: &'a [Vector<D>],
    parts: &'a [Share],
    /// With grains at rest: where to note whom a pair wakes, and the
    /// squared speed that wakes.
    rest: Option<(&'a Wake, f64)>,
    walls: &'a [Wall<D>],
    wall_laws: &'a [L],
    /// Each wall's candidate grains, ascending.
    candidates: &'a [Vec<u32>],
}

/// What the shares write: pair histories, forces, torques and wall
/// contact histories, whole (`W` = one `Vec` per wall) or one share's piece
/// (`W` = for each wall, the share's candidates and their histories).
struct Writes<'a, const D: usize, H, W>
where
    Dim<D>: Space<D>,
{
    history: &'a mut [H],
    force: &'a mut [Vector<D>],
    torque: &'a mut [Angular<D>],
    walls: W,
}

/// Everything the shares write; `run` cuts it into one piece per share.
type Out<'a, const D: usize, H> = Writes<'a, D, H, &'a mut [Vec<H>]>;

/// One share's block of pairs, its grains, and for each wall its grains' contacts.
type Piece<'a, const D: usize, H> = Writes<'a, D, H, ShareWalls<'a, H>>;

/// For each wall, a share's candidate grains and their contact histories.
type ShareWalls<'a, H> = Vec<(&'a [u32], &'a mut [H])>;

/// Cuts `v` into consecutive pieces of the given ranges (empty if `v` is).
fn pieces<T>(mut v: &mut [T], ranges: impl Iterator<Item = Range<usize>>) -> Vec<&mut [T]> {
    let mut out = Vec::new();
    let mut at = 0;
    for r in ranges {
        if v.is_empty() {
            out.push(v);
            v = &mut [];
            continue;
        }
        let (_, rest) = std::mem::take(&mut v).split_at_mut(r.start - at);
        let (mine, rest) = rest.split_at_mut(r.end - r.start);
        out.push(mine);
        v = rest;
        at = r.end;
    }
    out
}

impl<const D: usize, L: ContactLaw<D>> Context<'_, D, L>
where
    Dim<D>: Space<D>,
{
    fn run(&self, out: Out<'_, D, L::History>) -> ((f64, usize), WallPass) {
        let blocks = || self.parts.iter().map(|s| s.pairs.clone());
        let mut hist = pieces(out.history, blocks());
        // 1. The crossing pairs.
        let crossing: Vec<Crossing<D>> = hist
            .par_iter_mut()
            .zip(self.parts)
            .map(|(h, share)| self.crossing(share, h))
            .collect();
        // 2. Each share's grains.
        let grains = || self.parts.iter().map(|s| s.grains.clone());
        let forces = pieces(out.force, grains());
        let torques = pieces(out.torque, grains());
        let mut walls: Vec<ShareWalls<L::History>> =
            self.parts.iter().map(|_| Vec::new()).collect();
        for (cands, h) in self.candidates.iter().zip(out.walls.iter_mut()) {
            let ranges: Vec<Range<usize>> = grains().map(|g| candidates_in(cands, g)).collect();
            let histories = pieces(h, ranges.iter().cloned());
            for ((mine, r), piece) in walls.iter_mut().zip(ranges).zip(histories) {
                mine.push((&cands[r], piece));
            }
        }
        let responses: Vec<&[Option<Response<D>>]> = crossing.iter().map(|c| &c.0[..]).collect();
        let (inner, wall_pass) = hist
            .into_par_iter()
            .zip(forces)
            .zip(torques)
            .zip(walls)
            .zip(self.parts)
            .enumerate()
            .map(|(t, ((((history, force), torque), walls), share))| {
                let mut piece = Piece {
                    history,
                    force,
                    torque,
                    walls,
                };
                let worst = self.own(t, share, &mut piece, &responses);
                (worst, self.wall_contacts(share, &mut piece))
            })
            .reduce(
                || ((0.0, usize::MAX), WallPass::default()),
                |a, b| (worse(a.0, b.0), a.1.join(b.1)),
            );
        (crossing.iter().map(|c| c.1).fold(inner, worse), wall_pass)
    }

    /// The response of pair `k` = `(i, j)`, as one thread computes it:
    /// none for two resting grains (their spring keeps what it held).
    #[inline(always)]
    fn response(
        &self,
        k: usize,
        i: usize,
        j: usize,
        history: &mut L::History,
    ) -> Option<(Response<D>, f64)> {
        if let Some((wake, speed2)) = self.rest {
            if self.g.resting[i] && self.g.resting[j] {
                return None;
            }
            let r = self.separation(k, i, j);
            let found = pair_response(&self.law, &self.g, i, j, r, history, self.dt);
            if found.is_some() {
                wake.note(&self.g, i, j, speed2);
            }
            return found;
        }
        let r = self.separation(k, i, j);
        pair_response(&self.law, &self.g, i, j, r, history, self.dt)
    }

    fn separation(&self, k: usize, i: usize, j: usize) -> Vector<D> {
        let r = self.g.pos[i] - self.g.pos[j];
        if self.shifts.is_empty() {
            r
        } else {
            r - self.shifts[k]
        }
    }

    /// Responses of a share's crossing pairs.
    fn crossing(&self, share: &Share, history: &mut [L::History]) -> Crossing<D> {
        let mut worst = (0.0, usize::MAX);
        let out = share
            .cross
            .iter()
            .map(|&k| {
                let [i, j] = self.pairs[k];
                let (i, j) = (i as usize, j as usize);
                let h = &mut history[k - share.pairs.start];
                let found = self.response(k, i, j, h);
                if let Some((_, fraction)) = found {
                    worst = worse(worst, (fraction, k));
                }
                found.map(|f| f.0)
            })
            .collect();
        (out, worst)
    }

    /// A share's grains: gravity, what earlier shares give them, its own block.
    fn own(
        &self,
        t: usize,
        share: &Share,
        piece: &mut Piece<'_, D, L::History>,
        responses: &[&[Option<Response<D>>]],
    ) -> (f64, usize) {
        let (history, force, torque) = (&mut *piece.history, &mut *piece.force, &mut *piece.torque);
        let p = self.p;
        let g0 = share.grains.start;
        for (x, f) in share.grains.clone().zip(force.iter_mut()) {
            *f = self.gravity * p.mass[x];
            if let Some(load) = p.load.get(x) {
                *f += load;
            }
        }
        torque.fill(Default::default());
        for &(from, idx) in &share.incoming {
            let k = self.parts[from].cross[idx];
            if let Some(r) = &responses[from][idx] {
                let j = self.pairs[k][1] as usize - g0;
                force[j] -= r.force;
                if L::ROTATES {
                    torque[j] += r.torque_j;
                }
            }
        }
        let mut worst = (0.0, usize::MAX);
        let mut c = 0;
        for k in share.pairs.clone() {
            let [i, j] = self.pairs[k];
            let (i, j) = (i as usize, j as usize);
            if share.cross.get(c) == Some(&k) {
                if let Some(r) = &responses[t][c] {
                    force[i - g0] += r.force;
                    if L::ROTATES {
                        torque[i - g0] += r.torque_i;
                    }
                }
                c += 1;
                continue;
            }
            let h = &mut history[k - share.pairs.start];
            if let Some((resp, fraction)) = self.response(k, i, j, h) {
                worst = worse(worst, (fraction, k));
                force[i - g0] += resp.force;
                force[j - g0] -= resp.force;
                if L::ROTATES {
                    torque[i - g0] += resp.torque_i;
                    torque[j - g0] += resp.torque_j;
                }
            }
        }
        worst
    }

    /// A share's grains against every wall, walls in order.
    fn wall_contacts(&self, share: &Share, piece: &mut Piece<'_, D, L::History>) -> WallPass {
        let mine = piece.walls.iter_mut().map(|(c, h)| (*c, &mut **h));
        walls_pass(
            (self.walls, self.wall_laws),
            &self.g,
            mine,
            (&mut *piece.force, &mut *piece.torque, share.grains.start),
            self.dt,
        )
    }
}

/// The positions in a wall's ascending candidates of the grains in `grains`.
fn candidates_in(candidates: &[u32], grains: Range<usize>) -> Range<usize> {
    let lo = candidates.partition_point(|&c| (c as usize) < grains.start);
    let hi = candidates.partition_point(|&c| (c as usize) < grains.end);
    lo..hi
}
