//! The simulation pipeline.
//!
//! [`Simulation::step`] runs four named stages in a fixed order:
//!
//! 1. **integrate (predict)**: positions and velocities at which forces are evaluated;
//! 2. **neighbours**: grains past an outlet leave, and the Verlet list and
//!    wall candidates are rebuilt if any grain moved more than half the skin
//!    (grains are first put back into the cell along periodic axes);
//! 3. **contacts**: gravity, then every touching pair (springs of opened
//!    contacts are reset here), and every pair across a gap within the
//!    law's range when the law acts at a distance;
//! 4. **walls**: every grain touching a wall;
//!
//! then **integrate (correct)** and the guards. [`StageCounters`] times each
//! stage so the benchmark can show where the time goes.
//!
//! Determinism: a step is a pure function of the state. Every sum runs in
//! index order: on several threads each pair's response is computed on its
//! own and each grain then adds up its pairs in list order, the order of a
//! single thread, so the same scene and seed give bit-identical results on
//! the same build and machine whatever the number of threads.

pub(crate) mod boundary;
mod energy;
mod forces;
mod order;
mod rest;
mod share;
mod state;

pub use boundary::{Outlet, Periodic};
pub use rest::RestRule;
pub use state::{CountersFormat2, EngineState, SavedCounters, StateFormat2Of, StateOf};

use crate::contact::ContactLaw;
use crate::dim::{Dim, Space, Vector};
use crate::integrate::Integrator;
use crate::neighbors::NeighborList;
use crate::particles::Particles;
use crate::walls::{Wall, WallContacts};
use serde::{Deserialize, Serialize};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// The names of the units a model works in, for messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Units {
    pub speed: &'static str,
    pub energy: &'static str,
}

impl Units {
    /// Centimetre, gram, second (Lee & Herrmann).
    pub const CGS: Units = Units {
        speed: "cm/s",
        energy: "erg",
    };
    /// SI (Elekes & Parteli).
    pub const SI: Units = Units {
        speed: "m/s",
        energy: "J",
    };
}

/// Why a simulation stopped early.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Blowup {
    #[error("grain {id} has a non-finite or runaway velocity at t = {time:.6} s (speed {speed:.3e} {}; a grain crossing half its radius in one step means the time step cannot resolve its contacts)", units.speed)]
    Runaway {
        id: u32,
        speed: f64,
        time: f64,
        units: Units,
    },
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
    #[error("energy blow-up at t = {time:.6} s: kinetic energy {kinetic:.3e} {e} exceeds the {limit:.3e} {e} that gravity and the initial state can supply (the time step is too coarse for these contacts)", e = units.energy)]
    Energy {
        kinetic: f64,
        limit: f64,
        time: f64,
        units: Units,
    },
}

/// Safety limits checked every step.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
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
    /// Of those, the grains at rest (see [`RestRule`]): not integrated,
    /// and their pairs with each other not evaluated.
    #[serde(default)]
    pub resting_steps: u64,
    pub steps: u64,
    /// Force computations (one a step, and one as a run starts) whose
    /// contacts were shared among threads (see [`Simulation::set_threads`];
    /// a step with few listed pairs is not shared).
    #[serde(default)]
    pub shared_steps: u64,
}

impl StageCounters {
    pub fn total(&self) -> f64 {
        self.integrate + self.neighbours + self.contacts + self.walls
    }
}

/// The counters of two runs (or two parts of one) summed.
impl std::ops::AddAssign for StageCounters {
    fn add_assign(&mut self, c: StageCounters) {
        self.integrate += c.integrate;
        self.neighbours += c.neighbours;
        self.contacts += c.contacts;
        self.walls += c.walls;
        self.list_builds += c.list_builds;
        self.particle_steps += c.particle_steps;
        self.resting_steps += c.resting_steps;
        self.steps += c.steps;
        self.shared_steps += c.shared_steps;
    }
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
    /// Planes through which grains leave.
    pub outlets: Vec<Outlet<D>>,
    /// Periodic axes, if any (see [`Simulation::set_periodic`]).
    pub periodic: Option<Periodic<D>>,
    pub guards: Guards,
    /// Units of the messages of a blow-up.
    pub units: Units,
    pub dt: f64,
    pub time: f64,
    pub iteration: u64,
    /// Grains that left through the outlet.
    pub removed: usize,
    pub counters: StageCounters,
    /// Largest overlap seen since the last reset, as a fraction of the smaller radius.
    pub max_overlap_seen: f64,
    primed: bool,
    /// Renumber the grains in space at the first list build this many
    /// steps after the last renumbering (0: never).
    pub sort_every: u64,
    /// The step of the last renumbering.
    sorted_at: Option<u64>,
    /// Below this many listed pairs a step is too short to share among
    /// threads: waking them would cost more than it saves.
    pub min_shared_pairs: usize,
    /// Threads for the force loop (none: one thread, no pool).
    pool: Option<Arc<rayon::ThreadPool>>,
    /// How the pairs are shared among the threads, for the current list.
    shares: share::Shares,
    /// When grains are put to rest (none: never; see [`RestRule`]).
    rest: Option<RestRule>,
    /// Grains the pair loop found to wake at the end of the step.
    wake: rest::Wake,
}

/// Runs `f` on a pool thread while the pool's other threads keep looking
/// for work instead of going to sleep. A shared step hands its threads two
/// passes of some 50–100 µs; a sleeping thread is woken through the kernel,
/// which on a virtual machine can take as long as the pass, so that the
/// thread that shares the work finds none left.
fn awake<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    let caller = rayon::current_thread_index();
    let done = std::sync::atomic::AtomicBool::new(false);
    rayon::scope(|s| {
        s.spawn_broadcast(|_, ctx| {
            if Some(ctx.index()) != caller {
                while !done.load(std::sync::atomic::Ordering::Acquire) {
                    if rayon::yield_now() != Some(rayon::Yield::Executed) {
                        // Nothing to do: let any other program's thread on
                        // this core run, and look again.
                        std::thread::yield_now();
                    }
                }
            }
        });
        // Set however `f` ends, so that the scope can close.
        let _release = Release(&done);
        f()
    })
}

/// Sets its flag when dropped.
struct Release<'a>(&'a std::sync::atomic::AtomicBool);

impl Drop for Release<'_> {
    fn drop(&mut self) {
        self.0.store(true, std::sync::atomic::Ordering::Release);
    }
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
            outlets: Vec::new(),
            periodic: None,
            guards: Guards::default(),
            units: Units::CGS,
            dt,
            time: 0.0,
            iteration: 0,
            removed: 0,
            counters: StageCounters::default(),
            max_overlap_seen: 0.0,
            primed: false,
            sort_every: 0,
            sorted_at: None,
            min_shared_pairs: 2048,
            pool: None,
            shares: share::Shares::default(),
            rest: None,
            wake: rest::Wake::default(),
        }
    }

    /// The threads the force loop runs on.
    pub fn threads(&self) -> usize {
        self.pool.as_ref().map_or(1, |p| p.current_num_threads())
    }

    /// Computes forces on `threads` threads (1: on the calling thread),
    /// from the next step on. Results are bit-identical for any number, and
    /// for a run whose number changes between steps.
    pub fn set_threads(&mut self, threads: usize) -> Result<(), rayon::ThreadPoolBuildError> {
        self.pool = if threads > 1 {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()?;
            Some(Arc::new(pool))
        } else {
            None
        };
        Ok(())
    }

    /// Makes the axes with a positive length periodic, with the cell
    /// starting at `origin`. Each period must exceed twice the reach of
    /// the neighbour search, so that a grain meets at most one image of another.
    pub fn set_periodic(&mut self, origin: Vector<D>, lengths: [f64; D]) -> Result<(), String> {
        let max_radius = self.particles.radius.iter().copied().fold(0.0, f64::max);
        let reach = 2.0 * max_radius + self.neighbors.skin + self.law_range();
        let p = Periodic { origin, lengths };
        if p.shortest() <= 2.0 * reach {
            return Err(format!(
                "a period of {:.3e} is too short: it must exceed twice the neighbour reach {reach:.3e}",
                p.shortest()
            ));
        }
        self.periodic = Some(p);
        self.primed = false;
        Ok(())
    }

    /// How far beyond touching the pair law acts.
    fn law_range(&self) -> f64 {
        if L::ACTS_ACROSS_GAPS {
            self.pair_law.range()
        } else {
            0.0
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

        let outlet_due = !self.outlets.is_empty() && self.iteration % OUTLET_EVERY == 0;
        let left = outlet_due && self.drain_outlet();
        if left || self.neighbors.is_stale(&self.particles) {
            self.rebuild_lists();
        }
        let t2 = Instant::now();

        let (contacts_time, walls_time) = self.compute_forces_timed()?;
        let t3 = Instant::now();
        self.integrator.correct(&mut self.particles, self.dt);
        self.counters.resting_steps += self.update_rest();
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
        if let Some(pool) = self.pool.clone() {
            // On one of the pool's threads, the others kept awake meanwhile.
            return pool.install(|| awake(|| self.run_here(n)));
        }
        self.run_here(n)
    }

    fn run_here(&mut self, n: u64) -> Result<(), Blowup> {
        for _ in 0..n {
            self.step()?;
        }
        Ok(())
    }

    /// Forces of this step, with the time of the contact and the wall
    /// stages (shared among threads, both are one pass, timed as contacts).
    fn compute_forces_timed(&mut self) -> Result<(Duration, Duration), Blowup> {
        let t0 = Instant::now();
        if let Some(pool) = self.sharing() {
            self.shared_forces(&pool)?;
            self.counters.shared_steps += 1;
            return Ok((t0.elapsed(), Duration::ZERO));
        }
        self.pair_forces()?;
        let t1 = Instant::now();
        self.wall_forces()?;
        Ok((t1 - t0, t1.elapsed()))
    }

    fn compute_forces(&mut self) -> Result<(), Blowup> {
        self.compute_forces_timed().map(|_| ())
    }

    /// Rebuilds the Verlet list and wall candidates now (normally done only
    /// when a grain has moved half the skin).
    pub fn rebuild_lists(&mut self) {
        let range = self.law_range();
        if let Some(per) = &self.periodic {
            for x in &mut self.particles.pos {
                per.wrap(x);
            }
        }
        let due = self
            .sorted_at
            .is_none_or(|at| self.iteration >= at + self.sort_every);
        if self.sort_every > 0 && due {
            self.sort_spatially();
            self.sorted_at = Some(self.iteration);
        }
        self.neighbors.rebuild(
            &self.particles,
            range,
            self.periodic.as_ref(),
            self.pool.as_deref(),
        );
        self.wall_contacts
            .rebuild(&self.walls, &self.particles, self.neighbors.skin);
        self.counters.list_builds += 1;
    }

    /// Removes grains beyond any outlet; true if any left.
    fn drain_outlet(&mut self) -> bool {
        let outlets = &self.outlets;
        let keep: Vec<bool> = self
            .particles
            .pos
            .iter()
            .map(|x| !outlets.iter().any(|o| o.passed(x)))
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

    fn check_speeds(&self) -> Result<(), Blowup> {
        let p = &self.particles;
        let factor = self.guards.max_step_travel / self.dt;
        let runaway = |(radius, vel): (&f64, &Vector<D>)| {
            let limit = factor * radius;
            let v2 = vel.norm_squared();
            v2.is_nan() || v2 >= limit * limit
        };
        match p.radius.iter().zip(&p.vel).position(runaway) {
            Some(i) => Err(Blowup::Runaway {
                id: p.id[i],
                speed: p.vel[i].norm(),
                time: self.time,
                units: self.units,
            }),
            None => Ok(()),
        }
    }
}
