//! Throughput measurement on the fill-and-release scene: particle-steps per
//! second of the settled pile (all walls, nothing moving) and of the flow
//! right after the side wall is removed, with per-stage times.

use crate::contact::ContactLaw;
use crate::engine::{Simulation, StageCounters};
use crate::integrate::Integrator;
use crate::protocol::{with_engine, EngineJob, Quiet, Runner};
use crate::scene::{Protocol, Scene, SceneError};
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
    pub counters: StageCounters,
}

/// Settles the scene's filled box (untimed), then times `settled_steps`
/// steps of the closed box and `flow_steps` steps after release.
pub fn throughput(
    scene: &Scene,
    settled_steps: u64,
    flow_steps: u64,
) -> Result<Vec<PhaseThroughput>, SceneError> {
    if scene.protocol != Protocol::FillRelease {
        return Err(SceneError::single(
            "protocol",
            "the benchmark runs a fill_release scene",
        ));
    }
    scene.validate()?;
    let scene = scene.resolved();
    with_engine(
        &scene,
        Job {
            settled_steps,
            flow_steps,
        },
    )
    .map_err(|reason| SceneError::single("(run)", reason))
}

struct Job {
    settled_steps: u64,
    flow_steps: u64,
}

fn timed<L: ContactLaw<2>, I: Integrator<2>>(
    sim: &mut Simulation<2, L, I>,
    phase: &'static str,
    steps: u64,
) -> Result<PhaseThroughput, String> {
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
        counters: c,
    })
}

impl EngineJob for Job {
    type Output = Result<Vec<PhaseThroughput>, String>;

    fn run<L: ContactLaw<2>, I: Integrator<2>>(
        self,
        scene: &Scene,
        sim: Simulation<2, L, I>,
    ) -> Self::Output {
        let mut quiet = Quiet;
        let mut runner = Runner::new(sim, scene, &mut quiet);
        // Settle with the right wall in place, then time the closed box.
        let cap = scene.equilibrium.max_fill_time;
        runner
            .settle_fill()
            .map_err(|_| format!("the filled box did not settle within {cap} s"))?;
        let settled = timed(&mut runner.sim, "settled", self.settled_steps)?;
        runner.open_right_side();
        let flow = timed(&mut runner.sim, "flow", self.flow_steps)?;
        Ok(vec![settled, flow])
    }
}
