//! What every protocol does around the engine: step in chunks, sample the
//! kinetic energy and let the observer stop the run, turn early stops into
//! outcomes, and assemble the report.

use super::resume::{self, Checkpoint, Header, Saved, SavedPoint, SavedProtocol};
use crate::report::{
    ContactForce, Curve, FinalState, GrainCounts, Options, Outcome, Phase, Profile, Quantity,
    RunReport, TracePoint, ENGINE,
};
use crate::scene::Scene;
use repose_engine::contact::ContactLaw;
use repose_engine::dim::{Dim, Space, Vector};
use repose_engine::integrate::Integrator;
use repose_engine::particles::Particles;
use repose_engine::simulation::{Blowup, Simulation};
use repose_engine::walls::{Wall, WallSpec};
use serde::Serialize;
use serde_json::Value;
use std::collections::BTreeMap;
use std::time::Instant;

/// What a run reports while it goes, and how it can be stopped.
pub trait Observer {
    /// Called at every check; return `false` to stop the run.
    fn progress(&mut self, update: &Progress) -> bool;

    /// Asked at each resumable point of a protocol that can resume:
    /// whether to save the run now.
    fn checkpoint_due(&mut self) -> bool {
        false
    }

    /// Keeps a checkpoint (the latest replaces any earlier one).
    fn save(&mut self, _checkpoint: Checkpoint) {}

    /// The checkpoint to continue from, if any (asked once, at the start
    /// of a resumable run).
    fn saved(&mut self) -> Option<Checkpoint> {
        None
    }

    /// Told whether the checkpoint it handed over was used: the step it
    /// resumed from, or why the run started over.
    fn resumed(&mut self, _result: Result<u64, String>) {}

    /// Asked at every check: the threads the run may compute on from now
    /// on (`None` keeps those it has). Every number of the run is the same
    /// on any number of threads, so this changes its speed alone.
    fn threads(&mut self) -> Option<usize> {
        None
    }
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

/// Why a phase ended early.
pub enum Stop {
    Blowup(Blowup),
    Cancelled,
    /// The phase's time cap passed.
    TimedOut,
}

impl From<Blowup> for Stop {
    fn from(b: Blowup) -> Self {
        Stop::Blowup(b)
    }
}

impl Stop {
    /// The outcome of a run stopped in `phase`; a time-out becomes
    /// "not settled" with the given reason.
    pub fn outcome(self, phase: Phase, timed_out: impl FnOnce() -> String) -> Outcome {
        let phase_name = phase.name().to_string();
        match self {
            Stop::Blowup(b) => Outcome::Failed {
                phase: phase_name,
                reason: b.to_string(),
            },
            Stop::Cancelled => Outcome::Cancelled { phase: phase_name },
            Stop::TimedOut => Outcome::NotSettled {
                phase: phase_name,
                reason: timed_out(),
            },
        }
    }
}

/// A running protocol: the engine, the scene and the bookkeeping around them.
pub struct Runner<'a, const D: usize, L: ContactLaw<D>, I: Integrator<D>>
where
    Dim<D>: Space<D>,
{
    pub sim: Simulation<D, L, I>,
    pub scene: &'a Scene,
    observer: &'a mut dyn Observer,
    trace: Vec<TracePoint>,
    /// Steps between two checks.
    pub check_steps: u64,
    clock: Instant,
    /// Wall-clock seconds spent before a resumed run's checkpoint.
    earlier: f64,
    initial: usize,
}

/// Most steps between two checks: however long a scene's check interval,
/// the observer is asked at least this often whether the run goes on.
const MAX_CHECK_STEPS: u64 = 100_000_000;

impl<'a, const D: usize, L: ContactLaw<D>, I: Integrator<D>> Runner<'a, D, L, I>
where
    Dim<D>: Space<D>,
{
    /// Takes over a built engine; checks come every `check_interval`
    /// seconds, and the energy guard allows what gravity can give a grain
    /// moving within a region of size `extent`.
    pub fn new(
        mut sim: Simulation<D, L, I>,
        scene: &'a Scene,
        observer: &'a mut dyn Observer,
        check_interval: f64,
        extent: f64,
    ) -> Self {
        let check_steps = ((check_interval / sim.dt).round() as u64).clamp(1, MAX_CHECK_STEPS);
        sim.set_energy_budget(extent);
        let initial = sim.particles.len();
        Runner {
            sim,
            scene,
            observer,
            trace: Vec::new(),
            check_steps,
            clock: Instant::now(),
            earlier: 0.0,
            initial,
        }
    }

    /// Checks the energy guard, records a trace point and asks the observer
    /// whether to go on.
    pub fn sample(&mut self, phase: Phase) -> Result<TracePoint, Stop> {
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
        if !self.observer.progress(&update) {
            return Err(Stop::Cancelled);
        }
        if let Some(threads) = self.observer.threads().filter(|&t| t >= 1) {
            if threads != self.sim.threads() {
                // A pool that cannot be built leaves the threads as they are.
                let _ = self.sim.set_threads(threads);
            }
        }
        Ok(point)
    }

    /// Runs `steps` steps, sampling at every check.
    pub fn advance(&mut self, phase: Phase, steps: u64) -> Result<(), Stop> {
        let mut done = 0;
        while done < steps {
            self.sample(phase)?;
            let chunk = self.check_steps.min(steps - done);
            self.sim.run(chunk)?;
            done += chunk;
        }
        Ok(())
    }

    /// At a resumable point of the protocol, whose own state there is
    /// `state`: saves the run if the observer asks for it.
    pub fn checkpoint<P: Serialize>(&mut self, state: &P) {
        if !self.observer.checkpoint_due() {
            return;
        }
        let saved = Saved {
            header: self.header(),
            engine: self.sim.save_state(),
            trace: self.trace.iter().map(SavedPoint::of).collect(),
            wall_time: self.earlier + self.clock.elapsed().as_secs_f64(),
            protocol: state,
        };
        // A state that cannot be encoded is not saved; the run goes on.
        if let Ok(bytes) = resume::encode(&saved) {
            self.observer.save(Checkpoint {
                time: self.sim.time,
                iteration: self.sim.iteration,
                state: bytes,
            });
        }
    }

    /// Continues from the observer's checkpoint, if it has one that this
    /// scene and build wrote: restores the engine and the trace (whose
    /// phases are among `phases`) and returns the protocol's state. A
    /// checkpoint that does not fit is set aside, the observer told why,
    /// and the run starts from the beginning.
    pub fn resume<P: SavedProtocol>(&mut self, phases: &[Phase]) -> Option<P> {
        let checkpoint = self.observer.saved()?;
        let result = self.restore::<P>(&checkpoint.state, phases);
        let answer = result
            .as_ref()
            .map(|_| self.sim.iteration)
            .map_err(Clone::clone);
        self.observer.resumed(answer);
        result.ok()
    }

    fn restore<P: SavedProtocol>(&mut self, bytes: &[u8], phases: &[Phase]) -> Result<P, String> {
        use repose_engine::simulation::{EngineState, StateFormat2Of, StateOf};
        let saved: Saved<StateOf<D, L, I>, P> =
            resume::decode(bytes, &self.header(), |old: StateFormat2Of<D, L, I>| {
                EngineState::upgrade(old)
            })?;
        let trace = saved
            .trace
            .iter()
            .map(|p| p.point(phases))
            .collect::<Result<Vec<_>, _>>()?;
        self.sim.restore_state(saved.engine)?;
        self.trace = trace;
        self.earlier = saved.wall_time;
        self.clock = Instant::now();
        Ok(saved.protocol)
    }

    fn header(&self) -> Header {
        Header::new(
            std::any::type_name::<(L, I)>(),
            &self.scene.protocol,
            self.scene.seed,
        )
    }

    /// The report of the run so far, with the protocol's findings.
    pub fn report(&self, outcome: Outcome, findings: Findings) -> RunReport {
        let wall_time = self.earlier + self.clock.elapsed().as_secs_f64();
        let sim = &self.sim;
        let p = &sim.particles;
        let scene = self.scene;
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
            walls: sim.walls.iter().map(WallSpec::from).collect(),
        };
        let physics = scene.model().map(|m| m.options(scene)).unwrap_or_default();
        RunReport {
            engine: ENGINE.to_string(),
            protocol: scene.protocol.clone(),
            model: scene.model.clone(),
            dimension: D,
            seed: scene.seed,
            rng: scene.rng,
            outcome,
            metrics: findings.metrics,
            theory: findings.theory,
            series: findings.series,
            profiles: findings.profiles,
            details: findings.details,
            grains: GrainCounts {
                initial: self.initial,
                inserted: findings.inserted,
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
                dt: sim.dt,
                physics,
            },
            counters: sim.counters,
            energy_trace: downsample(&self.trace, 4000),
            max_overlap: sim.max_overlap_seen,
            scene: scene.clone(),
            final_state: Some(final_state),
        }
    }
}

/// What a protocol found, for its report.
#[derive(Debug, Clone, Default)]
pub struct Findings {
    pub metrics: BTreeMap<String, f64>,
    pub theory: Vec<Quantity>,
    pub series: Vec<Curve>,
    pub profiles: Vec<Profile>,
    pub details: Value,
    /// Grains added during the run.
    pub inserted: usize,
}

impl Findings {
    /// Records a measured metric.
    pub fn metric(&mut self, name: &str, value: f64) {
        self.metrics.insert(name.to_string(), value);
    }
}

/// An engine with the scene's time step, skin and overlap guard.
pub fn engine<const D: usize, L: ContactLaw<D>, I: Integrator<D>>(
    scene: &Scene,
    particles: Particles<D>,
    walls: Vec<(Wall<D>, L)>,
    gravity: Vector<D>,
    pair_law: L,
) -> Simulation<D, L, I>
where
    Dim<D>: Space<D>,
{
    let dt = scene.time_step();
    let mut sim = Simulation::new(particles, walls, gravity, pair_law, dt, scene.numerics.skin);
    sim.guards.max_overlap = scene.numerics.max_overlap;
    if let Ok(model) = scene.model() {
        sim.units = model.units();
        sim.sort_every = model.sort_every();
    }
    // A pool that cannot be built leaves the run on one thread: same results.
    let _ = sim.set_threads(scene.numerics.threads);
    sim
}

/// The size of the region a set of grains and a box `[0, size]` span.
pub fn extent<const D: usize>(pos: &[Vector<D>], radius: &[f64], size: Vector<D>) -> f64 {
    let (mut lo, mut hi) = (Vector::<D>::zeros(), size);
    for (x, r) in pos.iter().zip(radius) {
        lo = lo.inf(&x.add_scalar(-r));
        hi = hi.sup(&x.add_scalar(*r));
    }
    (hi - lo).norm()
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
