//! The protocols of Lee & Herrmann as runs of the engine, and the dispatch
//! from a scene's run-time choices to the compiled engine for them.
//!
//! [`run`] is the one entry point: it validates the scene, builds the grains
//! and walls, picks the monomorphised engine for the scene's integrator and
//! contact-law options, runs the protocol and returns a [`RunReport`].

use crate::contact::{
    ContactLaw, CundallStrack, Frictionless, HertzDamped, NormalForce, Pairwise, ShearSpringMode,
};
use crate::dim::Vector;
use crate::engine::{Blowup, Outlet, Simulation};
use crate::integrate::{Gear5, Integrator, Scheme, VelocityVerlet};
use crate::measure::{Stats, Surface};
use crate::particles::Particles;
use crate::report::*;
use crate::scene::{Equilibrium, Protocol, Scene, SceneError};
use crate::setup::{random_column, sphere_mass, Stream};
use crate::theory;
use crate::walls::Wall;
use std::collections::HashMap;
use std::time::Instant;

/// What a run reports while it goes, and how it can be stopped.
pub trait Observer {
    /// Called at every equilibrium check; return `false` to stop the run.
    fn progress(&mut self, update: &Progress) -> bool;
}

#[derive(Debug, Clone, Copy)]
pub struct Progress {
    pub phase: Phase,
    pub time: f64,
    pub iteration: u64,
    pub grains: usize,
    pub kinetic_energy: f64,
    pub max_speed: f64,
}

/// An observer that never stops anything.
pub struct Quiet;

impl Observer for Quiet {
    fn progress(&mut self, _update: &Progress) -> bool {
        true
    }
}

/// Runs one sample of the scene.
pub fn run(scene: &Scene, observer: &mut dyn Observer) -> Result<RunReport, SceneError> {
    scene.validate()?;
    let scene = scene.resolved();
    Ok(with_engine(&scene, ProtocolRun { observer }))
}

/// Something to do with a freshly built engine, whatever its concrete type.
pub trait EngineJob {
    type Output;
    fn run<L: ContactLaw<2>, I: Integrator<2>>(
        self,
        scene: &Scene,
        sim: Simulation<2, L, I>,
    ) -> Self::Output;
}

/// Builds the engine the scene asks for (integrator × friction × normal-force
/// floor) and hands it to `job`. The scene must be resolved.
pub fn with_engine<J: EngineJob>(scene: &Scene, job: J) -> J::Output {
    match scene.numerics.integrator {
        Scheme::Gear5 => with_friction::<Gear5, J>(scene, job),
        Scheme::Verlet => with_friction::<VelocityVerlet, J>(scene, job),
    }
}

fn with_friction<I: Integrator<2>, J: EngineJob>(scene: &Scene, job: J) -> J::Output {
    let c = &scene.contact;
    let w = &scene.wall_contact;
    let no_friction = c.mu == 0.0
        && c.gamma_s() == 0.0
        && w.mu.unwrap_or(c.mu) == 0.0
        && w.gamma_s.unwrap_or(c.gamma_s()) == 0.0;
    let cs = |mu: f64, k_s: f64, gamma_s: f64| (mu, k_s, gamma_s);
    let pair = cs(c.mu, c.k_s, c.gamma_s());
    let wall = cs(
        w.mu.unwrap_or(c.mu),
        w.k_s.unwrap_or(c.k_s),
        w.gamma_s.unwrap_or(c.gamma_s()),
    );
    let strack = |(mu, k_s, gamma_s): (f64, f64, f64)| CundallStrack::<false> { k_s, gamma_s, mu };
    let cut = |(mu, k_s, gamma_s): (f64, f64, f64)| CundallStrack::<true> { k_s, gamma_s, mu };
    if no_friction {
        with_normal::<I, Frictionless, J>(scene, Frictionless, Frictionless, job)
    } else {
        match c.shear_spring {
            ShearSpringMode::Paper => {
                with_normal::<I, _, J>(scene, strack(pair), strack(wall), job)
            }
            ShearSpringMode::Truncated => with_normal::<I, _, J>(scene, cut(pair), cut(wall), job),
        }
    }
}

fn with_normal<I, T, J>(scene: &Scene, pair_t: T, wall_t: T, job: J) -> J::Output
where
    I: Integrator<2>,
    T: crate::contact::TangentialLaw<2>,
    J: EngineJob,
{
    let c = &scene.contact;
    let wall_gamma = scene.wall_contact.gamma_n.unwrap_or(c.gamma_n);
    macro_rules! go {
        ($floor:literal) => {{
            let pair = Pairwise {
                normal: HertzDamped::<$floor> {
                    k_n: c.k_n,
                    gamma_n: c.gamma_n,
                },
                tangential: pair_t,
            };
            let wall = Pairwise {
                normal: HertzDamped::<$floor> {
                    k_n: scene.wall_contact.k_n,
                    gamma_n: wall_gamma,
                },
                tangential: wall_t,
            };
            job.run(scene, build::<_, I>(scene, pair, wall))
        }};
    }
    match c.normal_force {
        NormalForce::Floored => go!(true),
        NormalForce::Raw => go!(false),
    }
}

/// Grains and walls of the scene's starting state.
fn build<L: ContactLaw<2>, I: Integrator<2>>(
    scene: &Scene,
    pair: L,
    wall: L,
) -> Simulation<2, L, I> {
    let mut particles = Particles::<2>::default();
    let rho = scene.grains.density;
    let mut stream = Stream::new(scene.seed);
    if !scene.particles.is_empty() {
        for g in &scene.particles {
            particles.push_with_id(
                g.id,
                g.position,
                g.velocity,
                g.radius,
                sphere_mass(rho, g.radius),
            );
        }
        // Explicit ids may repeat the default 0: renumber if they are not unique.
        let mut ids = particles.id.clone();
        ids.sort_unstable();
        ids.dedup();
        if ids.len() != particles.len() {
            for (k, id) in particles.id.iter_mut().enumerate() {
                *id = k as u32;
            }
        }
    } else {
        match scene.protocol {
            Protocol::FillRelease | Protocol::Tilt => {
                let n = scene.grain_count();
                let radii: Vec<f64> = (0..n).map(|_| stream.radius(&scene.grains)).collect();
                let pos = random_column(
                    &mut stream,
                    &radii,
                    scene.container.width,
                    scene.container.placement_fraction,
                );
                for (x, r) in pos.into_iter().zip(radii) {
                    particles.push(x, Vector::zeros(), r, sphere_mass(rho, r));
                }
            }
            Protocol::Flux => {
                // One layer of grains along the floor, each just clear of the last.
                let mut x = 0.0;
                loop {
                    let r = stream.radius(&scene.grains);
                    let centre = x + r * 1.001;
                    if centre + r > scene.container.width {
                        break;
                    }
                    particles.push(
                        Vector::<2>::new(centre, r * 1.001),
                        Vector::zeros(),
                        r,
                        sphere_mass(rho, r),
                    );
                    x = centre + r * 1.001;
                }
            }
            Protocol::FreeRun => {}
        }
    }

    let walls: Vec<(Wall<2>, L)> = match scene.protocol {
        Protocol::FreeRun => scene
            .walls
            .iter()
            .map(|w| {
                (
                    Wall {
                        normal: w.normal.normalize(),
                        ..w.clone()
                    },
                    wall,
                )
            })
            .collect(),
        Protocol::FillRelease | Protocol::Tilt => {
            let width = scene.container.width;
            vec![
                (floor(width), wall),
                (
                    Wall::plane(Vector::<2>::new(0.0, 0.0), Vector::<2>::new(1.0, 0.0)),
                    wall,
                ),
                (
                    Wall::plane(Vector::<2>::new(width, 0.0), Vector::<2>::new(-1.0, 0.0)),
                    wall,
                ),
            ]
        }
        Protocol::Flux => vec![
            (floor(scene.container.width), wall),
            (
                Wall::plane(Vector::<2>::new(0.0, 0.0), Vector::<2>::new(1.0, 0.0)),
                wall,
            ),
        ],
    };
    let gravity = Vector::<2>::new(scene.gravity[0], scene.gravity[1]);
    let dt = scene.time_step();
    let mut sim = Simulation::new(particles, walls, gravity, pair, dt, scene.numerics.skin);
    sim.guards.max_overlap = scene.numerics.max_overlap;
    if scene.protocol == Protocol::Flux {
        sim.outlet = Some(open_side(scene.container.width));
    }
    sim
}

/// The floor of the box: it ends at `x = W`, so grains past the open side fall.
fn floor(width: f64) -> Wall<2> {
    Wall {
        limits: vec![crate::walls::Limit {
            axis: 0,
            min: Some(0.0),
            max: Some(width),
        }],
        ..Wall::plane(Vector::<2>::new(0.0, 0.0), Vector::<2>::new(0.0, 1.0))
    }
}

fn open_side(width: f64) -> Outlet<2> {
    Outlet {
        point: Vector::<2>::new(width, 0.0),
        normal: Vector::<2>::new(1.0, 0.0),
    }
}

/// The size of the region a scene's grains can move in, cm: the box (or
/// the grains' starting spread) for the box protocols; for a free run also
/// the distance the fastest grain can cover in the run's duration.
fn reach<L: ContactLaw<2>, I: Integrator<2>>(sim: &Simulation<2, L, I>, scene: &Scene) -> f64 {
    let p = &sim.particles;
    let (mut lo, mut hi) = (
        Vector::<2>::new(0.0, 0.0),
        Vector::<2>::new(scene.container.width, scene.container.fill_height()),
    );
    for (x, r) in p.pos.iter().zip(&p.radius) {
        lo = lo.inf(&x.add_scalar(-r));
        hi = hi.sup(&x.add_scalar(*r));
    }
    let mut extent = (hi - lo).norm();
    if scene.protocol == Protocol::FreeRun {
        let t = scene.duration.unwrap_or(0.0);
        extent += p.max_speed() * t + 0.5 * sim.gravity.norm() * t * t;
    }
    extent
}

/// Index of the right wall in the box protocols.
const RIGHT_WALL: usize = 2;

/// Why a phase ended early.
enum Stop {
    Blowup(Blowup),
    Cancelled,
    TimedOut,
}

impl From<Blowup> for Stop {
    fn from(b: Blowup) -> Self {
        Stop::Blowup(b)
    }
}

/// The running protocol's bookkeeping around the engine.
pub(crate) struct Runner<'a, L: ContactLaw<2>, I: Integrator<2>> {
    pub(crate) sim: Simulation<2, L, I>,
    scene: &'a Scene,
    observer: &'a mut dyn Observer,
    trace: Vec<TracePoint>,
    check_steps: u64,
}

impl<'a, L: ContactLaw<2>, I: Integrator<2>> Runner<'a, L, I> {
    pub(crate) fn new(
        sim: Simulation<2, L, I>,
        scene: &'a Scene,
        observer: &'a mut dyn Observer,
    ) -> Self {
        let check_steps = ((scene.equilibrium.check_interval / sim.dt).round() as u64).max(1);
        let mut sim = sim;
        sim.set_energy_budget(reach(&sim, scene));
        Runner {
            sim,
            scene,
            observer,
            trace: Vec::new(),
            check_steps,
        }
    }

    /// Settles the filled, closed box.
    pub(crate) fn settle_fill(&mut self) -> Result<(), ()> {
        let cap = self.scene.equilibrium.max_fill_time;
        self.settle(Phase::Fill, cap).map_err(|_| ())
    }
}

impl<L: ContactLaw<2>, I: Integrator<2>> Runner<'_, L, I> {
    fn sample(&mut self, phase: Phase) -> Result<TracePoint, Stop> {
        self.sim.check_energy()?;
        let p = &self.sim.particles;
        let n = p.len().max(1) as f64;
        let point = TracePoint {
            iteration: self.sim.iteration,
            time: self.sim.time,
            kinetic_energy: p.kinetic_energy() / n,
            max_speed: p.max_speed(),
            phase,
        };
        self.trace.push(point);
        let update = Progress {
            phase,
            time: point.time,
            iteration: point.iteration,
            grains: p.len(),
            kinetic_energy: point.kinetic_energy,
            max_speed: point.max_speed,
        };
        if self.observer.progress(&update) {
            Ok(point)
        } else {
            Err(Stop::Cancelled)
        }
    }

    /// Steps until the equilibrium criterion has held over one window of
    /// `hold` seconds (speed and energy low at every check, no grain moved
    /// more than `max_displacement` diameters), or `max_time` has passed.
    fn settle(&mut self, phase: Phase, max_time: f64) -> Result<(), Stop> {
        let start = self.sim.time;
        let mut window = StillWindow::default();
        loop {
            let point = self.sample(phase)?;
            let eq = &self.scene.equilibrium;
            if window.settled(&self.sim.particles, self.sim.time, calm(&point, eq), eq) {
                return Ok(());
            }
            if self.sim.time - start >= max_time {
                return Err(Stop::TimedOut);
            }
            self.sim.run(self.check_steps)?;
        }
    }

    fn surface(&self) -> Surface {
        let p = &self.sim.particles;
        Surface::measure(&p.pos, &p.radius, self.scene.container.width)
    }

    /// Fill the closed box, settle, remove the right wall, settle again.
    fn fill_and_release(&mut self) -> Result<(), (Phase, Stop)> {
        let fill_cap = self.scene.equilibrium.max_fill_time;
        self.settle(Phase::Fill, fill_cap)
            .map_err(|s| (Phase::Fill, s))?;
        self.open_right_side();
        let flow_cap = self.scene.equilibrium.max_flow_time;
        self.settle(Phase::Flow, flow_cap)
            .map_err(|s| (Phase::Flow, s))
    }

    pub(crate) fn open_right_side(&mut self) {
        self.sim.remove_wall(RIGHT_WALL);
        self.sim.outlet = Some(open_side(self.scene.container.width));
    }

    /// Turns gravity at the scene's rate until enough grains have moved.
    fn tilt(&mut self) -> Result<TiltResult, (Phase, Stop)> {
        let t = &self.scene.tilt;
        let p = &self.sim.particles;
        let reach = t.onset_displacement * 2.0 * p.mean_radius();
        let start: Vec<(u32, Vector<2>)> =
            p.id.iter().copied().zip(p.pos.iter().copied()).collect();
        let mut start_of = vec![None; p.id.iter().copied().max().map_or(0, |m| m as usize + 1)];
        for (id, x) in &start {
            start_of[*id as usize] = Some(*x);
        }
        let initial = start.len();
        let needed = (t.onset_fraction * initial as f64).ceil().max(1.0) as usize;
        let g0 = self.sim.gravity;
        let rate = t.rate.to_radians();
        let t0 = self.sim.time;
        let limit = t.max_angle.to_radians();
        loop {
            let angle = rate * (self.sim.time - t0);
            self.sample(Phase::Tilt).map_err(|s| (Phase::Tilt, s))?;
            let p = &self.sim.particles;
            // Grains that left through the open side count as moved.
            let stayed_still =
                p.id.iter()
                    .zip(&p.pos)
                    .filter(|(id, x)| {
                        start_of
                            .get(**id as usize)
                            .copied()
                            .flatten()
                            .is_some_and(|x0| (*x - x0).norm() <= reach)
                    })
                    .count();
            let moved = initial.saturating_sub(stayed_still);
            if moved >= needed {
                return Ok(TiltResult {
                    angle: angle.to_degrees(),
                    moved,
                });
            }
            if angle > limit {
                return Err((Phase::Tilt, Stop::TimedOut));
            }
            for _ in 0..self.check_steps {
                let a = rate * (self.sim.time - t0);
                // Turning the box clockwise turns gravity counter-clockwise in the box frame.
                let (s, c) = a.sin_cos();
                self.sim.gravity = Vector::<2>::new(c * g0.x - s * g0.y, s * g0.x + c * g0.y);
                self.sim
                    .step()
                    .map_err(|b| (Phase::Tilt, Stop::Blowup(b)))?;
            }
        }
    }

    /// Adds grains at the upper-left corner of the pile whenever the fastest
    /// grain is slower than `v_cut`; records the angle before each.
    /// Returns the series so far and, if the run stopped early, why.
    fn flux(&mut self) -> (FluxSummary, Option<Stop>) {
        let f = self.scene.flux.clone();
        let mut series = Vec::with_capacity(f.insertions);
        let mut stream = Stream::new(self.scene.seed ^ 0x9e37_79b9_7f4a_7c15);
        if let Err(s) = self.wait_for_rest(f.v_cut, f.max_wait * 5.0, false) {
            return (summarize_flux(series, f.discard_fraction), Some(s));
        }
        let mut by_speed = 0;
        for k in 0..f.insertions {
            let angle = self.surface().slope_angles().cumulative_fit;
            series.push(FluxPoint {
                insertion: k,
                iteration: self.sim.iteration,
                time: self.sim.time,
                angle,
            });
            let r = stream.radius(&self.scene.grains);
            let p = &self.sim.particles;
            // The upper-left corner: a random spot within one mean diameter of
            // the left wall, just above the grains there. Dropping every grain
            // at the same x would stack them into a column along the wall.
            let diameter = 2.0 * p.mean_radius();
            let x = r * 1.01 + diameter * stream.uniform();
            let top = p
                .pos
                .iter()
                .zip(&p.radius)
                .filter(|(c, a)| (c.x - x).abs() < r + **a)
                .map(|(c, a)| c.y + a)
                .fold(0.0, f64::max);
            let pos = Vector::<2>::new(x, top + r * 1.1);
            self.sim.insert(
                pos,
                Vector::zeros(),
                r,
                sphere_mass(self.scene.grains.density, r),
            );
            match self.wait_for_rest(f.v_cut, f.max_wait, true) {
                Ok(Rest::BySpeed) => by_speed += 1,
                Ok(Rest::ByDisplacement) => {}
                Err(s) => return (summarize_flux(series, f.discard_fraction), Some(s)),
            }
        }
        let mut done = summarize_flux(series, f.discard_fraction);
        done.rest_by_speed = by_speed;
        (done, None)
    }

    /// Steps until the pile is at rest, by the paper's test (the fastest
    /// grain slower than `v_cut`) or, where the paper's shear spring keeps a
    /// faint vibration above `v_cut`, by the equilibrium test (low energy and
    /// no grain moving more than `max_displacement` over the `hold` window).
    /// With `after_motion`, only once something has moved (the new grain
    /// has fallen and landed). Returns which test fired.
    fn wait_for_rest(
        &mut self,
        v_cut: f64,
        max_time: f64,
        after_motion: bool,
    ) -> Result<Rest, Stop> {
        let start = self.sim.time;
        let mut moving = !after_motion;
        let steps = (self.check_steps / 5).max(1);
        let mut window = StillWindow::default();
        loop {
            let v = self.sim.particles.max_speed();
            if v >= v_cut {
                moving = true;
            } else if moving {
                return Ok(Rest::BySpeed);
            }
            if moving && self.sim.iteration % self.check_steps < steps {
                let point = self.sample(Phase::Flux)?;
                let eq = &self.scene.equilibrium;
                if window.settled(&self.sim.particles, self.sim.time, calm(&point, eq), eq) {
                    return Ok(Rest::ByDisplacement);
                }
            }
            if self.sim.time - start >= max_time {
                return Err(Stop::TimedOut);
            }
            self.sim.run(steps)?;
        }
    }
}

/// The speed and energy half of the equilibrium test, at one check.
fn calm(point: &TracePoint, eq: &Equilibrium) -> bool {
    point.max_speed < eq.max_speed && point.kinetic_energy < eq.kinetic_energy
}

/// The displacement half of the equilibrium test: a window opens when the
/// pile is calm, and the pile is settled once it has stayed calm for `hold`
/// seconds with no grain moved more than `max_displacement` mean diameters
/// from where it was when the window opened (grains that left count as
/// moved). A window that fails is replaced by a new one.
#[derive(Default)]
struct StillWindow {
    open: Option<(f64, HashMap<u32, Vector<2>>)>,
}

impl StillWindow {
    fn settled(&mut self, p: &Particles<2>, time: f64, calm: bool, eq: &Equilibrium) -> bool {
        if !calm {
            self.open = None;
            return false;
        }
        if let Some((since, anchor)) = &self.open {
            if time - since < eq.hold {
                return false;
            }
            let limit = eq.max_displacement * 2.0 * p.mean_radius();
            let still =
                p.id.iter()
                    .zip(&p.pos)
                    .all(|(id, x)| anchor.get(id).is_some_and(|x0| (x - x0).norm() <= limit));
            if still {
                return true;
            }
        }
        let anchor = p.id.iter().copied().zip(p.pos.iter().copied()).collect();
        self.open = Some((time, anchor));
        false
    }
}

/// Which test declared the pile at rest in the flux protocol.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Rest {
    BySpeed,
    ByDisplacement,
}

fn summarize_flux(series: Vec<FluxPoint>, discard: f64) -> FluxSummary {
    let skip = (series.len() as f64 * discard).floor() as usize;
    let steady: Vec<f64> = series[skip.min(series.len())..]
        .iter()
        .map(|p| p.angle)
        .collect();
    FluxSummary {
        steady: Stats::of(&steady),
        max: steady.iter().copied().reduce(f64::max),
        series,
        rest_by_speed: 0,
    }
}

struct ProtocolRun<'a> {
    observer: &'a mut dyn Observer,
}

impl EngineJob for ProtocolRun<'_> {
    type Output = RunReport;

    fn run<L: ContactLaw<2>, I: Integrator<2>>(
        self,
        scene: &Scene,
        sim: Simulation<2, L, I>,
    ) -> RunReport {
        let clock = Instant::now();
        let initial = sim.particles.len();
        let mut r = Runner::new(sim, scene, self.observer);
        let mu = scene.contact.mu;
        let mut report_theory = Theory {
            marginal_stability: theory::marginal_stability_angle(mu),
            tilting: None,
        };
        let mut repose = None;
        let mut tilt = None;
        let mut flux = None;
        let mut surface = None;

        let outcome = match scene.protocol {
            Protocol::FillRelease | Protocol::Tilt => match r.fill_and_release() {
                Err((phase, stop)) => outcome_of(phase, stop, scene),
                Ok(()) => {
                    let s = r.surface();
                    let angles = s.slope_angles();
                    if let Err(reason) = s.check(&angles) {
                        surface = Some(s);
                        Outcome::Unmeasurable { reason }
                    } else {
                        repose = Some(angles);
                        surface = Some(s);
                        report_theory.tilting = theory::tilting_angle(mu, angles.cumulative_fit);
                        if scene.protocol == Protocol::Tilt {
                            match r.tilt() {
                                Ok(t) => {
                                    tilt = Some(t);
                                    Outcome::Completed
                                }
                                Err((_, Stop::TimedOut)) => Outcome::NoOnset {
                                    reason: format!(
                                        "the pile did not move before the tilt reached {}°",
                                        scene.tilt.max_angle
                                    ),
                                },
                                Err((phase, stop)) => outcome_of(phase, stop, scene),
                            }
                        } else {
                            Outcome::Completed
                        }
                    }
                }
            },
            Protocol::Flux => match r.flux() {
                (summary, None) => {
                    flux = Some(summary);
                    surface = Some(r.surface());
                    Outcome::Completed
                }
                (partial, Some(stop)) => {
                    // The series up to the failure is kept for inspection; its
                    // statistics are dropped so no number passes as a result.
                    flux = Some(FluxSummary {
                        steady: None,
                        max: None,
                        ..partial
                    });
                    outcome_of(Phase::Flux, stop, scene)
                }
            },
            Protocol::FreeRun => {
                let duration = scene.duration.unwrap_or(0.0);
                let steps = (duration / r.sim.dt).round() as u64;
                let mut done = 0;
                let mut outcome = Outcome::Completed;
                while done < steps {
                    if let Err(stop) = r.sample(Phase::Run) {
                        outcome = outcome_of(Phase::Run, stop, scene);
                        break;
                    }
                    let chunk = r.check_steps.min(steps - done);
                    if let Err(b) = r.sim.run(chunk) {
                        outcome = outcome_of(Phase::Run, Stop::Blowup(b), scene);
                        break;
                    }
                    done += chunk;
                }
                if outcome.is_completed() {
                    let _ = r.sample(Phase::Run);
                }
                outcome
            }
        };

        let wall_time = clock.elapsed().as_secs_f64();
        let sim = &r.sim;
        let p = &sim.particles;
        let final_state = FinalState {
            grains: p.grains(),
            contacts: sim
                .contact_forces()
                .into_iter()
                .map(|(i, j, force)| ContactForce {
                    a: p.id[i],
                    b: p.id[j],
                    force,
                })
                .collect(),
            walls: sim.walls.clone(),
        };
        let inserted = match &flux {
            Some(f) => f.series.len(),
            None => 0,
        };
        RunReport {
            engine: ENGINE.to_string(),
            protocol: scene.protocol,
            seed: scene.seed,
            rng: scene.rng,
            repose,
            tilt,
            flux,
            theory: report_theory,
            grains: GrainCounts {
                initial,
                inserted,
                lost: sim.removed,
                remaining: p.len(),
            },
            iterations: sim.iteration,
            simulated_time: sim.time,
            wall_time,
            particle_steps: sim.counters.particle_steps,
            particle_steps_per_second: sim.counters.particle_steps as f64 / wall_time.max(1e-12),
            options: Options {
                preset: scene.preset.map(|p| p.name().to_string()),
                integrator: scene.numerics.integrator.name().to_string(),
                normal_force: format!("{:?}", scene.contact.normal_force).to_lowercase(),
                shear_spring: format!("{:?}", scene.contact.shear_spring).to_lowercase(),
                dt: sim.dt,
            },
            counters: sim.counters,
            surface,
            energy_trace: downsample(&r.trace, 4000),
            max_overlap: sim.max_overlap_seen,
            scene: scene.clone(),
            final_state: Some(final_state),
            outcome,
        }
    }
}

fn outcome_of(phase: Phase, stop: Stop, scene: &Scene) -> Outcome {
    let phase_name = phase.name().to_string();
    match stop {
        Stop::Blowup(b) => Outcome::Failed {
            phase: phase_name,
            reason: b.to_string(),
        },
        Stop::Cancelled => Outcome::Cancelled { phase: phase_name },
        Stop::TimedOut => {
            let eq = &scene.equilibrium;
            let (cap, what) = match phase {
                Phase::Fill => (
                    eq.max_fill_time,
                    "max speed and kinetic energy below their thresholds",
                ),
                Phase::Flow => (
                    eq.max_flow_time,
                    "max speed and kinetic energy below their thresholds",
                ),
                Phase::Flux => (scene.flux.max_wait, "max speed below v_cut"),
                _ => (0.0, "equilibrium"),
            };
            Outcome::NotSettled {
                phase: phase_name,
                reason: format!("did not settle ({what}) within {cap} s of simulated time"),
            }
        }
    }
}

/// Keeps at most `max` points, evenly strided, always with the last one.
fn downsample(trace: &[TracePoint], max: usize) -> Vec<TracePoint> {
    if trace.len() <= max {
        return trace.to_vec();
    }
    let stride = trace.len().div_ceil(max);
    let mut out: Vec<TracePoint> = trace.iter().step_by(stride).copied().collect();
    if let Some(last) = trace.last() {
        if out.last() != Some(last) {
            out.push(*last);
        }
    }
    out
}
