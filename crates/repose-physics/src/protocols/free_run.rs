//! A free run: the listed grains and walls, under gravity, for a fixed
//! duration, in 2D or 3D. For single-contact checks (a collision, a grain
//! on an incline) and anything that is not a pile protocol.

use super::runner::{extent, Findings, Runner};
use super::{Metric, Observer, Protocol};
use crate::models::{self, elekes_parteli, lee_herrmann, EngineJob, Laws, Models};
use crate::preset::Preset;
use crate::report::{Outcome, Phase, RunReport};
use crate::scene::{Checks, Scene, SceneError, SectionDecl};
use crate::setup::sphere_mass;
use repose_engine::contact::ContactLaw;
use repose_engine::dim::{Dim, Space, Vector};
use repose_engine::integrate::Integrator;
use repose_engine::particles::{vector_from, Particles};
use repose_engine::simulation::Simulation;
use repose_engine::walls::Wall;
use serde_json::Value;

pub struct FreeRun;

pub const RUN: Phase = Phase("run");

/// How often a free run samples its kinetic energy, s.
const CHECK_INTERVAL: f64 = 0.005;

impl Protocol for FreeRun {
    fn name(&self) -> &'static str {
        "free_run"
    }

    fn about(&self) -> &'static str {
        "integrate the listed grains and walls for a fixed duration"
    }

    fn dimensions(&self) -> &'static [usize] {
        &[2, 3]
    }

    fn models(&self) -> &'static [&'static str] {
        &[lee_herrmann::NAME, elekes_parteli::NAME]
    }

    /// Lee & Herrmann's discs in 2D, Elekes & Parteli's spheres in 3D.
    fn default_model(&self, dimension: usize) -> &'static str {
        if dimension == 3 {
            elekes_parteli::NAME
        } else {
            lee_herrmann::NAME
        }
    }

    fn sections(&self) -> Vec<SectionDecl> {
        Vec::new()
    }

    fn metrics(&self) -> &'static [Metric] {
        &[]
    }

    fn preset(&self, preset: Preset) -> Vec<(&'static str, Value)> {
        super::numeric_preset(preset)
    }

    fn draws_grains(&self) -> bool {
        false
    }

    fn check(&self, scene: &Scene, c: &mut Checks) {
        if scene.particles.is_empty() {
            c.fail("particles", "a free_run needs at least one listed grain");
        }
        match scene.duration {
            None => c.fail("duration", "a free_run needs a duration (s)"),
            Some(d) => c.positive("duration", d),
        }
    }

    fn run(&self, scene: &Scene, observer: &mut dyn Observer) -> Result<RunReport, SceneError> {
        match scene.dimension {
            3 => go::<3>(scene, observer),
            _ => go::<2>(scene, observer),
        }
    }
}

fn go<const D: usize>(scene: &Scene, observer: &mut dyn Observer) -> Result<RunReport, SceneError>
where
    Dim<D>: Space<D> + Models<D>,
{
    models::with_engine::<D, _>(scene, Job { scene, observer })?
}

struct Job<'a> {
    scene: &'a Scene,
    observer: &'a mut dyn Observer,
}

impl<const D: usize> EngineJob<D> for Job<'_>
where
    Dim<D>: Space<D>,
{
    type Output = Result<RunReport, SceneError>;

    fn run<L: ContactLaw<D>, I: Integrator<D>>(self, laws: Laws<L>) -> Self::Output {
        let scene = self.scene;
        let sim = build::<D, L, I>(scene, laws)?;
        let duration = scene.duration.unwrap_or(0.0);
        let steps = (duration / sim.dt).round() as u64;
        let p = &sim.particles;
        let travel = p.max_speed() * duration + 0.5 * sim.gravity.norm() * duration * duration;
        let size = extent(&p.pos, &p.radius, Vector::<D>::zeros()) + travel;
        let mut run = Runner::new(sim, scene, self.observer, CHECK_INTERVAL, size);
        // The engine is all the state: every check is a resumable point.
        run.resume::<()>(&[RUN]);
        let outcome = loop {
            let done = run.sim.iteration;
            if done >= steps {
                let _ = run.sample(RUN);
                break Outcome::Completed;
            }
            run.checkpoint(&());
            let chunk = run.check_steps.min(steps - done);
            if let Err(stop) = run.advance(RUN, chunk) {
                break stop.outcome(RUN, String::new);
            }
        };
        Ok(run.report(outcome, Findings::default()))
    }
}

/// The listed grains and walls, in dimension `D`.
fn build<const D: usize, L: ContactLaw<D>, I: Integrator<D>>(
    scene: &Scene,
    laws: Laws<L>,
) -> Result<Simulation<D, L, I>, SceneError>
where
    Dim<D>: Space<D>,
{
    let rho = scene.model()?.density(scene);
    let mut particles = Particles::<D>::new(L::ROTATES);
    for (i, g) in scene.particles.iter().enumerate() {
        let bad = || SceneError::single(format!("particles[{i}]"), format!("needs {D} components"));
        let x = g.position_in::<D>().ok_or_else(bad)?;
        let v = g.velocity_in::<D>().ok_or_else(bad)?;
        particles.push_with_id(g.id, x, v, g.radius, sphere_mass(rho, g.radius));
        if !g.load.is_empty() {
            let f = vector_from::<D>(&g.load).ok_or_else(bad)?;
            let last = particles.len() - 1;
            particles.set_load(last, f);
        }
        if L::ROTATES && !g.angular_velocity.is_empty() {
            let w = <Dim<D> as Space<D>>::angular_from(&g.angular_velocity).ok_or_else(bad)?;
            let last = particles.len() - 1;
            particles.omega[last] = w;
        }
    }
    particles.make_ids_unique();
    let mut walls: Vec<(Wall<D>, L)> = Vec::new();
    for (i, w) in scene.walls.iter().enumerate() {
        let wall = w.to_wall::<D>().ok_or_else(|| {
            SceneError::single(
                format!("walls[{i}]"),
                format!("needs {D} components and a normal"),
            )
        })?;
        walls.push((wall, laws.wall));
    }
    let gravity = vector_from::<D>(&scene.gravity)
        .ok_or_else(|| SceneError::single("gravity", format!("needs {D} components")))?;
    Ok(super::runner::engine(
        scene, particles, walls, gravity, laws.pair,
    ))
}
