//! Throughput measurement: particle-steps per second, with per-stage
//! times, on the fill-and-release scene of Lee & Herrmann (the settled pile
//! with all walls, and the flow right after the side wall is removed) and
//! on the poured 3D heap of the LIGGGHTS peer run ([`heap`]).

pub mod heap;

use crate::models::{with_engine, EngineJob, Laws};
use crate::protocols::pile::{self, Pile, PileSpec, FILL};
use crate::protocols::Quiet;
use crate::scene::{Scene, SceneError};
use repose_engine::contact::ContactLaw;
use repose_engine::dim::{Dim, Space};
use repose_engine::integrate::Integrator;
use repose_engine::simulation::{Simulation, StageCounters};
use serde::Serialize;
use std::time::Instant;

/// Throughput of one phase.
#[derive(Debug, Clone, Serialize)]
pub struct PhaseThroughput {
    pub phase: &'static str,
    pub grains_start: usize,
    pub grains_end: usize,
    pub steps: u64,
    pub particle_steps: u64,
    /// Wall-clock seconds of the timed steps.
    pub seconds: f64,
    pub particle_steps_per_second: f64,
    /// Grain pairs touching at the end of the phase: the work per step.
    pub touching_end: usize,
    pub counters: StageCounters,
}

/// Settles the scene's filled box (untimed), then times `settled_steps`
/// steps of the closed box and `flow_steps` steps after release.
pub fn throughput(
    scene: &Scene,
    settled_steps: u64,
    flow_steps: u64,
) -> Result<Vec<PhaseThroughput>, SceneError> {
    if scene.protocol != "fill_release" {
        return Err(SceneError::single(
            "protocol",
            "the benchmark runs a fill_release scene",
        ));
    }
    scene.validate()?;
    let scene = scene.resolved();
    let spec = PileSpec::of(&scene)?;
    with_engine::<2, _>(
        &scene,
        Job {
            scene: &scene,
            spec,
            settled_steps,
            flow_steps,
        },
    )?
    .map_err(|reason| SceneError::single("(run)", reason))
}

struct Job<'a> {
    scene: &'a Scene,
    spec: PileSpec,
    settled_steps: u64,
    flow_steps: u64,
}

/// Runs `steps` steps and times them.
pub fn timed<const D: usize, L: ContactLaw<D>, I: Integrator<D>>(
    sim: &mut Simulation<D, L, I>,
    phase: &'static str,
    steps: u64,
) -> Result<PhaseThroughput, String>
where
    Dim<D>: Space<D>,
{
    sim.counters = StageCounters::default();
    let grains_start = sim.particles.len();
    let clock = Instant::now();
    sim.run(steps).map_err(|e| e.to_string())?;
    let seconds = clock.elapsed().as_secs_f64();
    let c = sim.counters;
    Ok(PhaseThroughput {
        phase,
        grains_start,
        grains_end: sim.particles.len(),
        steps,
        particle_steps: c.particle_steps,
        seconds,
        particle_steps_per_second: c.particle_steps as f64 / seconds,
        touching_end: sim.contact_forces().len(),
        counters: c,
    })
}

impl EngineJob<2> for Job<'_> {
    type Output = Result<Vec<PhaseThroughput>, String>;

    fn run<L: ContactLaw<2>, I: Integrator<2>>(self, laws: Laws<L>) -> Self::Output {
        let mut quiet = Quiet;
        let sim = pile::closed_box::<L, I>(self.scene, &self.spec, laws);
        let cap = self.spec.eq.max_fill_time;
        let mut pile = Pile::new(sim, self.scene, self.spec, &mut quiet);
        // Settle with the right wall in place, then time the closed box.
        pile.settle(FILL, cap)
            .map_err(|_| format!("the filled box did not settle within {cap} s"))?;
        let settled = timed(&mut pile.run.sim, "settled", self.settled_steps)?;
        pile.open_right_side();
        let flow = timed(&mut pile.run.sim, "flow", self.flow_steps)?;
        Ok(vec![settled, flow])
    }
}
