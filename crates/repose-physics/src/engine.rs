//! The simulation pipeline.
//!
//! [`Simulation::step`] runs four named stages in a fixed order:
//!
//! 1. **integrate (predict)**: positions and velocities at which forces are evaluated;
//! 2. **neighbours**: grains past the outlet leave, and the Verlet list and
//!    wall candidates are rebuilt if any grain moved more than half the skin;
//! 3. **contacts**: gravity, then every touching pair (springs of opened
//!    contacts are reset here), and every pair across a gap within the
//!    law's range when the law acts at a distance;
//! 4. **walls**: every grain touching a wall;
//!
//! then **integrate (correct)** and the guards. [`StageCounters`] times each
//! stage so the benchmark can show where the time goes.
//!
//! Determinism: a step is a pure function of the state. All loops run in
//! index order on one thread, so the same scene and seed give bit-identical
//! results on the same build and machine.

use crate::contact::{ContactLaw, Response, Touch};
use crate::dim::{Dim, Space, Vector};
use crate::integrate::Integrator;
use crate::neighbors::NeighborList;
use crate::particles::Particles;
use crate::walls::{Wall, WallContacts};
use serde::{Deserialize, Serialize};
use std::time::{Duration, Instant};

/// Why a simulation stopped early.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Blowup {
    #[error("grain {id} has a non-finite or runaway velocity at t = {time:.6} s (speed {speed:.3e} cm/s; a grain crossing half its radius in one step means the time step cannot resolve its contacts)")]
    Runaway { id: u32, speed: f64, time: f64 },
    #[error("grains {a} and {b} overlap by {fraction:.3} of the smaller radius at t = {time:.6} s (limit {limit})")]
    Overlap {
        a: u32,
        b: u32,
        fraction: f64,
        limit: f64,
        time: f64,
    },
    #[error("grain {id} passed through wall {wall} at t = {time:.6} s")]
    ThroughWall { id: u32, wall: usize, time: f64 },
    #[error("energy blow-up at t = {time:.6} s: kinetic energy {kinetic:.3e} erg exceeds the {limit:.3e} erg that gravity and the initial state can supply (the time step is too coarse for these contacts)")]
    Energy { kinetic: f64, limit: f64, time: f64 },
}

/// Safety limits checked every step.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Guards {
    /// Largest overlap allowed, as a fraction of the smaller radius.
    pub max_overlap: f64,
    /// Largest distance a grain may travel in one step, as a fraction of its radius.
    pub max_step_travel: f64,
    /// Energy budget: the kinetic energy may not exceed
    /// `energy_per_mass · Σm + energy_offset` (see [`Simulation::set_energy_budget`]).
    pub energy_per_mass: f64,
    pub energy_offset: f64,
}

impl Default for Guards {
    fn default() -> Self {
        Guards {
            max_overlap: 0.5,
            max_step_travel: 0.5,
            energy_per_mass: f64::INFINITY,
            energy_offset: 0.0,
        }
    }
}

/// Wall-clock time spent in each stage (seconds), and how much work was done.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct StageCounters {
    pub integrate: f64,
    pub neighbours: f64,
    pub contacts: f64,
    pub walls: f64,
    /// Verlet-list builds.
    pub list_builds: u64,
    /// Sum over steps of the number of grains (the throughput unit).
    pub particle_steps: u64,
    pub steps: u64,
}

impl StageCounters {
    pub fn total(&self) -> f64 {
        self.integrate + self.neighbours + self.contacts + self.walls
    }
}

/// Grains whose centre lies beyond this plane leave the simulation
/// (the open side of the box after the wall is removed).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Outlet<const D: usize> {
    pub point: Vector<D>,
    /// Unit normal pointing out of the region grains may stay in.
    pub normal: Vector<D>,
}

/// A running simulation: the state of every grain and wall, the contact
/// laws, the integrator and the bookkeeping of one sample.
#[derive(Debug)]
pub struct Simulation<const D: usize, L: ContactLaw<D>, I: Integrator<D>>
where
    Dim<D>: Space<D>,
{
    pub particles: Particles<D>,
    pub walls: Vec<Wall<D>>,
    pub gravity: Vector<D>,
    pub pair_law: L,
    pub wall_laws: Vec<L>,
    pub integrator: I,
    pub neighbors: NeighborList<D, L::History>,
    pub wall_contacts: WallContacts<L::History>,
    pub outlet: Option<Outlet<D>>,
    pub guards: Guards,
    pub dt: f64,
    pub time: f64,
    pub iteration: u64,
    /// Grains that left through the outlet.
    pub removed: usize,
    pub counters: StageCounters,
    /// Largest overlap seen since the last reset, as a fraction of the smaller radius.
    pub max_overlap_seen: f64,
    primed: bool,
}

/// How often (in steps) the outlet is checked when nothing else forces it.
const OUTLET_EVERY: u64 = 50;

impl<const D: usize, L: ContactLaw<D>, I: Integrator<D>> Simulation<D, L, I>
where
    Dim<D>: Space<D>,
{
    pub fn new(
        particles: Particles<D>,
        walls: Vec<(Wall<D>, L)>,
        gravity: Vector<D>,
        pair_law: L,
        dt: f64,
        skin: f64,
    ) -> Self {
        let mut particles = particles;
        if particles.rotating() != L::ROTATES {
            particles.set_rotating(L::ROTATES);
        }
        let integrator = I::new(&particles, dt);
        let (walls, wall_laws): (Vec<_>, Vec<_>) = walls.into_iter().unzip();
        let nwalls = walls.len();
        Simulation {
            particles,
            walls,
            gravity,
            pair_law,
            wall_laws,
            integrator,
            neighbors: NeighborList::new(skin),
            wall_contacts: WallContacts::new(nwalls),
            outlet: None,
            guards: Guards::default(),
            dt,
            time: 0.0,
            iteration: 0,
            removed: 0,
            counters: StageCounters::default(),
            max_overlap_seen: 0.0,
            primed: false,
        }
    }

    /// Evaluates forces for the current state without moving anything, so
    /// the first step starts from consistent accelerations.
    fn prime(&mut self) -> Result<(), Blowup> {
        self.rebuild_lists();
        self.compute_forces()?;
        self.integrator.restart(&self.particles, self.dt);
        self.primed = true;
        Ok(())
    }

    /// Advances by one time step.
    pub fn step(&mut self) -> Result<(), Blowup> {
        if !self.primed {
            self.prime()?;
        }
        let t0 = Instant::now();
        self.integrator.predict(&mut self.particles, self.dt);
        let t1 = Instant::now();

        let outlet_due = self.outlet.is_some() && self.iteration % OUTLET_EVERY == 0;
        let left = outlet_due && self.drain_outlet();
        if left || self.neighbors.is_stale(&self.particles) {
            self.rebuild_lists();
        }
        let t2 = Instant::now();

        let (contacts_time, walls_time) = self.compute_forces_timed()?;
        let t3 = Instant::now();
        self.integrator.correct(&mut self.particles, self.dt);
        let t4 = Instant::now();

        self.time += self.dt;
        self.iteration += 1;
        let c = &mut self.counters;
        c.integrate += ((t1 - t0) + (t4 - t3)).as_secs_f64();
        c.neighbours += (t2 - t1).as_secs_f64();
        c.contacts += contacts_time.as_secs_f64();
        c.walls += walls_time.as_secs_f64();
        c.steps += 1;
        c.particle_steps += self.particles.len() as u64;
        self.check_speeds()
    }

    /// Runs `n` steps.
    pub fn run(&mut self, n: u64) -> Result<(), Blowup> {
        for _ in 0..n {
            self.step()?;
        }
        Ok(())
    }

    fn compute_forces_timed(&mut self) -> Result<(Duration, Duration), Blowup> {
        let t0 = Instant::now();
        self.pair_forces()?;
        let t1 = Instant::now();
        self.wall_forces()?;
        Ok((t1 - t0, t1.elapsed()))
    }

    fn compute_forces(&mut self) -> Result<(), Blowup> {
        self.pair_forces()?;
        self.wall_forces()
    }

    /// Rebuilds the Verlet list and wall candidates now (normally done only
    /// when a grain has moved half the skin).
    pub fn rebuild_lists(&mut self) {
        let range = if L::ACTS_ACROSS_GAPS {
            self.pair_law.range()
        } else {
            0.0
        };
        self.neighbors.rebuild(&self.particles, range);
        self.wall_contacts
            .rebuild(&self.walls, &self.particles, self.neighbors.skin);
        self.counters.list_builds += 1;
    }

    /// Removes grains beyond the outlet; true if any left.
    fn drain_outlet(&mut self) -> bool {
        let Some(outlet) = self.outlet else {
            return false;
        };
        let keep: Vec<bool> = self
            .particles
            .pos
            .iter()
            .map(|x| (x - outlet.point).dot(&outlet.normal) <= 0.0)
            .collect();
        let gone = keep.iter().filter(|k| !**k).count();
        if gone > 0 {
            self.remove(&keep);
        }
        gone > 0
    }

    /// Removes the grains whose `keep` flag is false, keeping every contact
    /// history of the grains that stay.
    pub fn remove(&mut self, keep: &[bool]) {
        let mut new_index = Vec::with_capacity(keep.len());
        let mut next = 0u32;
        for &k in keep {
            if k {
                new_index.push(next);
                next += 1;
            } else {
                new_index.push(u32::MAX);
            }
        }
        self.removed += keep.len() - next as usize;
        self.neighbors.renumber(&new_index);
        self.wall_contacts.renumber(&new_index);
        self.particles.retain(keep);
        self.integrator.on_retain(keep);
        // `renumber` marked the list stale: the next step rebuilds it.
    }

    /// Takes wall `k` away (the side wall of the fill-and-release box).
    pub fn remove_wall(&mut self, k: usize) {
        self.walls.remove(k);
        self.wall_laws.remove(k);
        self.wall_contacts.candidates.remove(k);
        self.wall_contacts.history.remove(k);
    }

    /// Kinetic energy of translation and rotation.
    pub fn kinetic_energy(&self) -> f64 {
        self.particles.kinetic_energy() + self.particles.rotational_energy()
    }

    /// Adds a grain (at rest or moving) during a run; returns its id.
    pub fn insert(&mut self, pos: Vector<D>, vel: Vector<D>, radius: f64, mass: f64) -> u32 {
        let id = self.particles.push(pos, vel, radius, mass);
        let last = self.particles.len() - 1;
        self.particles.force[last] = self.gravity * mass;
        self.integrator.on_insert(&self.particles, self.dt);
        // The grain count changed, so the next step rebuilds the lists.
        id
    }

    /// Tells the integrator that velocities or positions were set from outside.
    pub fn restart_integrator(&mut self) {
        self.integrator.restart(&self.particles, self.dt);
    }

    fn pair_forces(&mut self) -> Result<(), Blowup> {
        let p = &mut self.particles;
        for i in 0..p.len() {
            p.force[i] = self.gravity * p.mass[i];
        }
        if L::ROTATES {
            p.torque.fill(Default::default());
        }
        let law = self.pair_law;
        let dt = self.dt;
        let mut worst = 0.0f64;
        let mut worst_pair = 0usize;
        let pairs = &self.neighbors.pairs;
        let history = &mut self.neighbors.history;
        for k in 0..pairs.len() {
            let [i, j] = pairs[k];
            let (i, j) = (i as usize, j as usize);
            let r = p.pos[i] - p.pos[j];
            let dist2 = r.norm_squared();
            let reach = p.radius[i] + p.radius[j];
            if dist2 >= reach * reach {
                // The contact is open: its spring is gone.
                history[k] = Default::default();
                if L::ACTS_ACROSS_GAPS {
                    let limit = reach + law.range();
                    if dist2 < limit * limit {
                        let touch = pair_touch(p, i, j, r, dist2.sqrt(), L::ROTATES);
                        apply(p, i, j, &law.gap_force(&touch), L::ROTATES);
                    }
                }
                continue;
            }
            let dist = dist2.sqrt();
            let touch = pair_touch(p, i, j, r, dist, L::ROTATES);
            let fraction = touch.overlap / touch.radius_i.min(touch.radius_j);
            if fraction > worst {
                worst = fraction;
                worst_pair = k;
            }
            let response = law.force(&touch, &mut history[k], dt);
            apply(p, i, j, &response, L::ROTATES);
        }
        self.max_overlap_seen = self.max_overlap_seen.max(worst);
        if worst > self.guards.max_overlap {
            let [a, b] = pairs[worst_pair];
            return Err(Blowup::Overlap {
                a: p.id[a as usize],
                b: p.id[b as usize],
                fraction: worst,
                limit: self.guards.max_overlap,
                time: self.time,
            });
        }
        Ok(())
    }

    fn wall_forces(&mut self) -> Result<(), Blowup> {
        let p = &mut self.particles;
        let dt = self.dt;
        for (w, wall) in self.walls.iter().enumerate() {
            let law = self.wall_laws[w];
            let cands = &self.wall_contacts.candidates[w];
            let history = &mut self.wall_contacts.history[w];
            for k in 0..cands.len() {
                let i = cands[k] as usize;
                let dist = wall.distance(&p.pos[i]);
                let overlap = p.radius[i] - dist;
                if overlap <= 0.0 || !wall.covers(&p.pos[i]) {
                    history[k] = Default::default();
                    continue;
                }
                if dist < 0.0 {
                    return Err(Blowup::ThroughWall {
                        id: p.id[i],
                        wall: w,
                        time: self.time,
                    });
                }
                let fraction = overlap / p.radius[i];
                self.max_overlap_seen = self.max_overlap_seen.max(fraction);
                let touch = wall_touch(p, i, wall.normal, overlap, L::ROTATES);
                let response = law.force(&touch, &mut history[k], dt);
                p.force[i] += response.force;
                if L::ROTATES {
                    p.torque[i] += response.torque_i;
                }
            }
        }
        Ok(())
    }

    fn check_speeds(&self) -> Result<(), Blowup> {
        let p = &self.particles;
        let factor = self.guards.max_step_travel / self.dt;
        for i in 0..p.len() {
            let limit = factor * p.radius[i];
            let v2 = p.vel[i].norm_squared();
            if v2.is_nan() || v2 >= limit * limit {
                return Err(Blowup::Runaway {
                    id: p.id[i],
                    speed: v2.sqrt(),
                    time: self.time,
                });
            }
        }
        Ok(())
    }

    /// Kinetic plus elastic energy plus gravitational potential (erg), the
    /// zero of height at the origin.
    pub fn total_energy(&self) -> f64 {
        let p = &self.particles;
        let mut e = p.kinetic_energy() + self.elastic_energy();
        for i in 0..p.len() {
            e -= p.mass[i] * self.gravity.dot(&p.pos[i]);
        }
        e
    }

    /// Energy stored in the contact springs (normal and shear), erg.
    pub fn elastic_energy(&self) -> f64 {
        let p = &self.particles;
        let mut e = 0.0;
        for (k, [i, j]) in self.neighbors.pairs.iter().enumerate() {
            let (i, j) = (*i as usize, *j as usize);
            let overlap = p.radius[i] + p.radius[j] - (p.pos[i] - p.pos[j]).norm();
            if overlap > 0.0 {
                e += self
                    .pair_law
                    .elastic_energy(overlap, &self.neighbors.history[k]);
            }
        }
        for (w, wall) in self.walls.iter().enumerate() {
            for (k, &i) in self.wall_contacts.candidates[w].iter().enumerate() {
                let i = i as usize;
                let overlap = p.radius[i] - wall.distance(&p.pos[i]);
                if overlap > 0.0 && wall.covers(&p.pos[i]) {
                    e += self.wall_laws[w]
                        .elastic_energy(overlap, &self.wall_contacts.history[w][k]);
                }
            }
        }
        e
    }

    /// Arms the energy guard. A grain that moves within a region of size
    /// `extent` under gravity can gain at most `|g|·extent` per unit mass, and
    /// the stored kinetic and elastic energy can only be released once; a
    /// kinetic energy above twice that budget can only come from the
    /// integrator itself, so [`Simulation::check_energy`] fails the run.
    pub fn set_energy_budget(&mut self, extent: f64) {
        self.rebuild_lists();
        let stored = self.particles.kinetic_energy() + self.elastic_energy();
        self.guards.energy_per_mass = 2.0 * self.gravity.norm() * extent;
        self.guards.energy_offset = 2.0 * stored;
    }

    /// Fails with [`Blowup::Energy`] when the kinetic energy exceeds the budget.
    pub fn check_energy(&self) -> Result<(), Blowup> {
        let p = &self.particles;
        let kinetic = p.kinetic_energy();
        let mass: f64 = p.mass.iter().sum();
        let limit = self.guards.energy_per_mass * mass + self.guards.energy_offset;
        // A budget of zero (no gravity, nothing moving) still allows rounding.
        if kinetic > limit * (1.0 + 1e-9) + f64::MIN_POSITIVE || kinetic.is_nan() {
            return Err(Blowup::Energy {
                kinetic,
                limit,
                time: self.time,
            });
        }
        Ok(())
    }

    /// Normal force of every touching pair, for drawing force chains:
    /// `(index i, index j, |F_n|)` with the elastic part only (the state is at rest).
    pub fn contact_forces(&self) -> Vec<(usize, usize, f64)> {
        let p = &self.particles;
        let mut out = Vec::new();
        for (k, [i, j]) in self.neighbors.pairs.iter().enumerate() {
            let (i, j) = (*i as usize, *j as usize);
            let r = p.pos[i] - p.pos[j];
            let dist = r.norm();
            let overlap = p.radius[i] + p.radius[j] - dist;
            if overlap > 0.0 && dist > 0.0 {
                let mut touch = pair_touch(p, i, j, r, dist, L::ROTATES);
                touch.normal = r / dist;
                let mut h = self.neighbors.history[k];
                let f = self.pair_law.force(&touch, &mut h, 0.0).force;
                out.push((i, j, f.dot(&touch.normal).abs()));
            }
        }
        out
    }
}

/// The pair `(i, j)` with `r = x_i − x_j` at distance `dist`, seen from `i`.
#[inline(always)]
fn pair_touch<const D: usize>(
    p: &Particles<D>,
    i: usize,
    j: usize,
    r: Vector<D>,
    dist: f64,
    rotating: bool,
) -> Touch<D>
where
    Dim<D>: Space<D>,
{
    let (ai, aj) = (p.radius[i], p.radius[j]);
    let (mi, mj) = (p.mass[i], p.mass[j]);
    Touch {
        normal: r * (1.0 / dist),
        overlap: (ai + aj) - dist,
        velocity: p.vel[i] - p.vel[j],
        m_eff: mi * mj / (mi + mj),
        r_eff: ai * aj / (ai + aj),
        radius_i: ai,
        radius_j: aj,
        omega_i: if rotating {
            p.omega[i]
        } else {
            Default::default()
        },
        omega_j: if rotating {
            p.omega[j]
        } else {
            Default::default()
        },
    }
}

/// Grain `i` against a wall with unit normal `normal`: a partner of zero
/// radius and infinite mass that does not turn.
#[inline(always)]
fn wall_touch<const D: usize>(
    p: &Particles<D>,
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
        velocity: p.vel[i],
        m_eff: p.mass[i],
        r_eff: p.radius[i],
        radius_i: p.radius[i],
        radius_j: 0.0,
        omega_i: if rotating {
            p.omega[i]
        } else {
            Default::default()
        },
        omega_j: Default::default(),
    }
}

/// Adds a pair's response to both grains.
#[inline(always)]
fn apply<const D: usize>(
    p: &mut Particles<D>,
    i: usize,
    j: usize,
    response: &Response<D>,
    rotating: bool,
) where
    Dim<D>: Space<D>,
{
    p.force[i] += response.force;
    p.force[j] -= response.force;
    if rotating {
        p.torque[i] += response.torque_i;
        p.torque[j] += response.torque_j;
    }
}
