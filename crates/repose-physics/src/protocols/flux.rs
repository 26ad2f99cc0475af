//! Constant flux (Lee & Herrmann, section 5): grains are added one at a
//! time at the upper-left corner of an open pile whenever it has come to
//! rest; the pile's angle just before each insertion traces the angle of
//! marginal stability θ_MS (the paper's fig. 5).

use super::pile::{self, calm, BoxSpec, Equilibrium, Pile, PileSpec, StillWindow};
use super::runner::{Findings, Stop};
use super::{Metric, Observer, Protocol};
use crate::measure::Stats;
use crate::models::{self, EngineJob, Laws};
use crate::report::{Band, Curve, Outcome, Phase, Quantity, RunReport};
use crate::scene::{Checks, Scene, SceneError, Section, SectionDecl, MAX_GRAINS};
use crate::setup::{sphere_mass, Stream};
use repose_engine::contact::ContactLaw;
use repose_engine::dim::Vector;
use repose_engine::integrate::Integrator;
use repose_engine::particles::Particles;
use serde::{Deserialize, Serialize};
use serde_json::{json, Value};

pub struct Flux;

pub const FLUX: Phase = Phase("flux");

/// The constant-flux protocol of section 5.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FluxSpec {
    /// A new grain is added once the fastest grain is slower than this, cm/s.
    pub v_cut: f64,
    /// How many grains to add.
    pub insertions: usize,
    /// Cap on the simulated time spent waiting after one insertion, s.
    pub max_wait: f64,
    /// Leading fraction of the series left out of the steady-state statistics.
    pub discard_fraction: f64,
}

impl Default for FluxSpec {
    fn default() -> Self {
        FluxSpec {
            v_cut: 0.1,
            insertions: 300,
            max_wait: 2.0,
            discard_fraction: 0.5,
        }
    }
}

impl Section for FluxSpec {
    const KEY: &'static str = "flux";
    const ABOUT: &'static str =
        "when the next grain goes in, how many, and the transient to leave out";

    fn check(&self, _scene: &Scene, c: &mut Checks) {
        c.positive("flux.v_cut", self.v_cut);
        if self.insertions == 0 {
            c.fail("flux.insertions", "must be at least 1");
        }
        if self.insertions > MAX_GRAINS {
            c.fail("flux.insertions", format!("must be at most {MAX_GRAINS}"));
        }
        c.positive("flux.max_wait", self.max_wait);
        if c.finite("flux.discard_fraction", self.discard_fraction)
            && !(0.0..1.0).contains(&self.discard_fraction)
        {
            c.fail("flux.discard_fraction", "must lie in [0, 1)");
        }
    }
}

const METRICS: [Metric; 3] = [
    Metric {
        name: "theta_ms_mean",
        label: "θ pile, steady mean",
        unit: "°",
        description: "mean pile angle (method 3) before each insertion, after the transient",
        phase: "flux",
    },
    Metric {
        name: "theta_ms_sd",
        label: "θ pile, steady sd",
        unit: "°",
        description: "standard deviation of the pile angle after the transient (the fluctuation band of fig. 5)",
        phase: "flux",
    },
    Metric {
        name: "theta_ms_max",
        label: "θ pile, largest",
        unit: "°",
        description: "largest pile angle after the transient",
        phase: "flux",
    },
];

impl Protocol for Flux {
    fn name(&self) -> &'static str {
        "flux"
    }

    fn about(&self) -> &'static str {
        "add grains one at a time to an open pile: the angle of marginal stability θ_MS"
    }

    pile::pile_protocol!(filled: false);

    fn sections(&self) -> Vec<SectionDecl> {
        vec![
            SectionDecl::of::<BoxSpec>(),
            SectionDecl::of::<Equilibrium>(),
            SectionDecl::of::<FluxSpec>(),
        ]
    }

    fn metrics(&self) -> &'static [Metric] {
        &METRICS
    }

    fn run(&self, scene: &Scene, observer: &mut dyn Observer) -> Result<RunReport, SceneError> {
        let spec = PileSpec::of(scene)?;
        let flux = scene.section::<FluxSpec>()?.clone();
        models::with_engine::<2, _>(
            scene,
            Job {
                scene,
                spec,
                flux,
                observer,
            },
        )
    }
}

struct Job<'a> {
    scene: &'a Scene,
    spec: PileSpec,
    flux: FluxSpec,
    observer: &'a mut dyn Observer,
}

/// One layer of grains along the floor, each just clear of the last (or the listed grains).
fn floor_layer(scene: &Scene, spec: &PileSpec) -> Particles<2> {
    let rho = spec.grains.density;
    if !scene.particles.is_empty() {
        return pile::listed_grains(scene, rho);
    }
    let mut stream = Stream::new(scene.seed);
    let mut particles = Particles::<2>::default();
    let mut x = 0.0;
    loop {
        let r = spec.grains.draw_radius(&mut stream);
        let centre = x + r * 1.001;
        if centre + r > spec.cell.width {
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
    particles
}

impl EngineJob<2> for Job<'_> {
    type Output = RunReport;

    fn run<L: ContactLaw<2>, I: Integrator<2>>(self, laws: Laws<L>) -> RunReport {
        let width = self.spec.cell.width;
        let particles = floor_layer(self.scene, &self.spec);
        let walls = vec![
            (pile::floor(width), laws.wall),
            (
                pile::plane(Vector::<2>::new(0.0, 0.0), Vector::<2>::new(1.0, 0.0)),
                laws.wall,
            ),
        ];
        let mut sim = pile::engine::<L, I>(self.scene, particles, walls, laws);
        sim.outlets = vec![pile::open_side(width)];
        let mu = self.spec.mu;
        let mut pile = Pile::new(sim, self.scene, self.spec, self.observer);
        let (series, by_speed, stop) = feed(&mut pile, &self.flux);
        let mut findings = Findings {
            inserted: series.len(),
            ..Findings::default()
        };
        findings.theory.push(Quantity {
            name: "theta_ms_eq3".into(),
            label: "θ_MS = atan(3μ), eq. (3)".into(),
            value: crate::theory::marginal_stability_angle(mu),
        });
        let outcome = match stop {
            None => {
                let summary = summarize(&series, &self.flux, by_speed, &mut findings);
                findings.details = json!({ "flux": summary, "series": series });
                findings.profiles.push(pile.surface());
                Outcome::Completed
            }
            Some(stop) => {
                // The series up to the failure is kept for inspection; its
                // statistics are dropped so no number passes as a result.
                findings.details = json!({ "series": series });
                let cap = self.flux.max_wait;
                stop.outcome(FLUX, || {
                    format!(
                        "did not settle (max speed below v_cut) within {cap} s of simulated time"
                    )
                })
            }
        };
        pile.run.report(outcome, findings)
    }
}

/// One point of the series: the pile's angle (method 3) just before a grain is added.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
struct FluxPoint {
    insertion: usize,
    iteration: u64,
    time: f64,
    angle: f64,
}

/// The steady statistics (after the transient), as metrics and a curve.
fn summarize(series: &[FluxPoint], f: &FluxSpec, by_speed: usize, out: &mut Findings) -> Value {
    let skip = (series.len() as f64 * f.discard_fraction).floor() as usize;
    let steady: Vec<f64> = series[skip.min(series.len())..]
        .iter()
        .map(|p| p.angle)
        .collect();
    let stats = Stats::of(&steady);
    let max = steady.iter().copied().reduce(f64::max);
    if let Some(s) = stats {
        out.metric("theta_ms_mean", s.mean);
        out.metric("theta_ms_sd", s.sd);
    }
    if let Some(m) = max {
        out.metric("theta_ms_max", m);
    }
    out.series.push(Curve {
        name: "pile_angle".into(),
        title: "Pile angle before each insertion (fig. 5)".into(),
        x_label: "iteration".into(),
        y_label: "pile angle (°)".into(),
        points: series
            .iter()
            .map(|p| [p.iteration as f64, p.angle])
            .collect(),
        band: stats.map(|s| Band {
            lo: s.mean - s.sd,
            hi: s.mean + s.sd,
            mean: s.mean,
        }),
    });
    json!({ "steady": stats, "max": max, "rest_by_speed": by_speed })
}

/// Adds grains at the upper-left corner of the pile whenever it has come to
/// rest; records the angle before each. Returns the series, how many
/// insertions the speed test allowed, and why the run stopped early, if it did.
fn feed<L: ContactLaw<2>, I: Integrator<2>>(
    pile: &mut Pile<'_, L, I>,
    f: &FluxSpec,
) -> (Vec<FluxPoint>, usize, Option<Stop>) {
    let mut series = Vec::with_capacity(f.insertions);
    let mut stream = Stream::new(pile.run.scene.seed ^ 0x9e37_79b9_7f4a_7c15);
    if let Err(s) = wait_for_rest(pile, f.v_cut, f.max_wait * 5.0, false) {
        return (series, 0, Some(s));
    }
    let mut by_speed = 0;
    for k in 0..f.insertions {
        let angle = pile.surface().slope_angles().cumulative_fit;
        let sim = &pile.run.sim;
        series.push(FluxPoint {
            insertion: k,
            iteration: sim.iteration,
            time: sim.time,
            angle,
        });
        let r = pile.spec.grains.draw_radius(&mut stream);
        let p = &sim.particles;
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
        let mass = sphere_mass(pile.spec.grains.density, r);
        pile.run.sim.insert(pos, Vector::zeros(), r, mass);
        match wait_for_rest(pile, f.v_cut, f.max_wait, true) {
            Ok(Rest::BySpeed) => by_speed += 1,
            Ok(Rest::ByDisplacement) => {}
            Err(s) => return (series, by_speed, Some(s)),
        }
    }
    (series, by_speed, None)
}

/// Which test declared the pile at rest.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Rest {
    BySpeed,
    ByDisplacement,
}

/// Steps until the pile is at rest, by the paper's test (the fastest
/// grain slower than `v_cut`) or, where the paper's shear spring keeps a
/// faint vibration above `v_cut`, by the equilibrium test (low energy and
/// no grain moving more than `max_displacement` over the `hold` window).
/// With `after_motion`, only once something has moved (the new grain
/// has fallen and landed). Returns which test fired.
fn wait_for_rest<L: ContactLaw<2>, I: Integrator<2>>(
    pile: &mut Pile<'_, L, I>,
    v_cut: f64,
    max_time: f64,
    after_motion: bool,
) -> Result<Rest, Stop> {
    let run = &mut pile.run;
    let eq = &pile.spec.eq;
    let start = run.sim.time;
    let mut moving = !after_motion;
    let steps = (run.check_steps / 5).max(1);
    let mut window = StillWindow::default();
    loop {
        let v = run.sim.particles.max_speed();
        if v >= v_cut {
            moving = true;
        } else if moving {
            return Ok(Rest::BySpeed);
        }
        if moving && run.sim.iteration % run.check_steps < steps {
            let point = run.sample(FLUX)?;
            let calm = calm(point.max_speed, point.kinetic_energy, eq);
            if window.settled(&run.sim.particles, run.sim.time, calm, eq) {
                return Ok(Rest::ByDisplacement);
            }
        }
        if run.sim.time - start >= max_time {
            return Err(Stop::TimedOut);
        }
        run.sim.run(steps)?;
    }
}
