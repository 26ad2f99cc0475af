//! The 3D heap of the LIGGGHTS peer benchmark (`bench/liggghts-heap.in`),
//! built with this engine's Elekes–Parteli contacts: 2000 spheres of radii
//! 1.8, 2.0 and 2.2 mm (25/50/25 %) poured at 4000 per second from a
//! cylinder 12–15 cm above the floor of a 0.2 m square box, then settled.
//! The same grains, material, time step, neighbour skin and step counts; the
//! contact laws differ in detail (see `docs/benchmarks.md`), so the
//! comparison is of cost per particle-step, not of angles.

use super::{timed, PhaseThroughput};
use crate::models::elekes_parteli::Grains;
use crate::models::{with_engine, EngineJob, Laws};
use crate::protocols::pour::{draw_diameter, Placer};
use crate::scene::{Scene, SceneError};
use crate::setup::Stream;
use repose_engine::contact::ContactLaw;
use repose_engine::dim::Vector;
use repose_engine::integrate::Integrator;
use repose_engine::particles::Particles;
use repose_engine::simulation::Simulation;
use repose_engine::walls::Wall;

/// The peer run's grains and material as a scene (a free run, whose one
/// listed grain the benchmark replaces by its own pour).
pub const LIGGGHTS_HEAP: &str = r#"
protocol = "free_run"
dimension = 3
duration = 1.0
seed = 1

[numerics]
integrator = "verlet"
dt = 1e-5
skin = 0.001

[grains]
diameter = 0.004
density = 2500.0
mix = [
    { diameter = 0.0036, fraction = 0.25 },
    { diameter = 0.0040, fraction = 0.5 },
    { diameter = 0.0044, fraction = 0.25 },
]

[material]
youngs_modulus = 5e6
poisson_ratio = 0.45
restitution = 0.3
friction = 0.5
rolling_friction = 0.3
surface_energy = 0.0
tangential_cap = "spring"

[[particles]]
position = [0.0, 0.0, 0.1]
radius = 0.002
"#;

/// Step counts of the three stages of the peer run.
#[derive(Debug, Clone, Copy)]
pub struct HeapSteps {
    /// Timed: from an empty box while all grains are poured.
    pub pour: u64,
    /// Untimed: the heap comes to rest.
    pub settle: u64,
    /// Timed: the heap at rest.
    pub settled: u64,
}

impl Default for HeapSteps {
    fn default() -> Self {
        HeapSteps {
            pour: 60_000,
            settle: 60_000,
            settled: 30_000,
        }
    }
}

/// Grains poured in all, per insertion, and steps between insertions.
const GRAINS: usize = 2000;
const PER_INSERTION: usize = 20;
const INSERT_EVERY: u64 = 500;

/// Pours and settles the heap; times the pour and the settled heap.
pub fn heap_throughput(
    scene: &Scene,
    steps: HeapSteps,
) -> Result<Vec<PhaseThroughput>, SceneError> {
    scene.validate()?;
    let scene = scene.resolved();
    let grains = scene.section::<Grains>()?.clone();
    with_engine::<3, _>(
        &scene,
        Job {
            scene: &scene,
            grains,
            steps,
        },
    )?
    .map_err(|reason| SceneError::single("(run)", reason))
}

struct Job<'a> {
    scene: &'a Scene,
    grains: Grains,
    steps: HeapSteps,
}

impl EngineJob<3> for Job<'_> {
    type Output = Result<Vec<PhaseThroughput>, String>;

    fn run<L: ContactLaw<3>, I: Integrator<3>>(self, laws: Laws<L>) -> Self::Output {
        let mut sim = walled_box::<L, I>(self.scene, laws);
        let mut stream = Stream::new(self.scene.seed);
        let clock = std::time::Instant::now();
        let mut pour = Vec::new();
        let mut done = 0;
        while done < self.steps.pour {
            if sim.particles.len() < GRAINS {
                pour_some(&mut sim, &self.grains, &mut stream);
            }
            let chunk = INSERT_EVERY.min(self.steps.pour - done);
            pour.push(timed(&mut sim, "pour", chunk)?);
            done += chunk;
        }
        let poured = merge(&pour, clock.elapsed().as_secs_f64());
        sim.run(self.steps.settle).map_err(|e| e.to_string())?;
        let settled = timed(&mut sim, "settled", self.steps.settled)?;
        Ok(vec![poured, settled])
    }
}

/// The floor and four side walls of the 0.2 m box, with the grains' material.
fn walled_box<L: ContactLaw<3>, I: Integrator<3>>(
    scene: &Scene,
    laws: Laws<L>,
) -> Simulation<3, L, I> {
    let plane = |p: [f64; 3], n: [f64; 3]| {
        (
            Wall::<3>::plane(Vector::<3>::from(p), Vector::<3>::from(n)),
            laws.wall,
        )
    };
    let walls = vec![
        plane([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
        plane([-0.1, 0.0, 0.0], [1.0, 0.0, 0.0]),
        plane([0.1, 0.0, 0.0], [-1.0, 0.0, 0.0]),
        plane([0.0, -0.1, 0.0], [0.0, 1.0, 0.0]),
        plane([0.0, 0.1, 0.0], [0.0, -1.0, 0.0]),
    ];
    let gravity = Vector::<3>::new(0.0, 0.0, -9.81);
    let particles = Particles::<3>::new(L::ROTATES);
    crate::protocols::runner::engine(scene, particles, walls, gravity, laws.pair)
}

/// Inserts the next batch, wholly inside the cylinder of radius 2 cm from
/// 12 to 15 cm, without overlaps, moving down at 0.5 m/s.
fn pour_some<L: ContactLaw<3>, I: Integrator<3>>(
    sim: &mut Simulation<3, L, I>,
    grains: &Grains,
    stream: &mut Stream,
) {
    let largest = grains.diameter_range().1;
    let mut placer = Placer::new(largest, Vector::<3>::zeros(), [0.0; 3]);
    for (x, r) in sim.particles.pos.iter().zip(&sim.particles.radius) {
        if x.z > 0.12 - largest {
            placer.add(*x, *r);
        }
    }
    let mut added = 0;
    for _ in 0..100 * PER_INSERTION {
        if added == PER_INSERTION || sim.particles.len() >= GRAINS {
            break;
        }
        let d = draw_diameter(grains, stream);
        let reach = 0.02 - 0.5 * d;
        let (u, v) = (2.0 * stream.uniform() - 1.0, 2.0 * stream.uniform() - 1.0);
        let z = 0.12 + 0.5 * d + (0.03 - d) * stream.uniform();
        if u * u + v * v > 1.0 {
            continue;
        }
        let x = Vector::<3>::new(reach * u, reach * v, z);
        if placer.fits(&x, 0.5 * d) {
            placer.add(x, 0.5 * d);
            sim.insert(x, Vector::<3>::new(0.0, 0.0, -0.5), 0.5 * d, grains.mass(d));
            added += 1;
        }
    }
}

/// The pour as one phase: the sums of its chunks, timed as a whole.
fn merge(parts: &[PhaseThroughput], seconds: f64) -> PhaseThroughput {
    let mut counters = parts[0].counters;
    for p in &parts[1..] {
        counters += p.counters;
    }
    PhaseThroughput {
        phase: "pour",
        grains_start: parts[0].grains_start,
        grains_end: parts[parts.len() - 1].grains_end,
        steps: counters.steps,
        particle_steps: counters.particle_steps,
        seconds,
        particle_steps_per_second: counters.particle_steps as f64 / seconds,
        touching_end: parts[parts.len() - 1].touching_end,
        counters,
    }
}
