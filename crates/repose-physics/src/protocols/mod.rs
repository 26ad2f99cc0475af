//! Protocols: the experiments a scene can run, as plug-ins.
//!
//! A protocol is one type implementing [`Protocol`] in its own module. It
//! declares what the rest of the project needs to know about it — its
//! dimensions and models, its scene sections with their defaults and checks,
//! the settings of each fidelity preset, and its metrics (name, unit, label,
//! description and the phase that produces them) — and it runs a scene into
//! a [`RunReport`]. The store, the API, the exports and the results page
//! learn protocols and metrics from the registry ([`crate::registry`]);
//! registering a protocol is its module plus one line there.

pub mod fill_release;
pub mod flux;
pub mod free_run;
pub mod heap;
pub mod packing;
pub mod pile;
pub mod pour;
pub mod resume;
pub mod runner;
pub mod tilt;

pub use resume::Checkpoint;
pub use runner::{Observer, Progress, Quiet};

/// Gravity must point straight down the last axis (y in 2D, z in 3D): the
/// piles and heaps are built on a floor across it and measured along it.
pub fn check_gravity_down(scene: &Scene, c: &mut Checks) {
    let Some((down, across)) = scene.gravity.split_last() else {
        return;
    };
    if across.iter().any(|g| *g != 0.0) || *down >= 0.0 {
        let (axis, form) = match across.len() {
            1 => ("y", "[0, -g]"),
            _ => ("z", "[0, 0, -g]"),
        };
        c.fail(
            "gravity",
            format!("must point down the {axis} axis, {form} with g > 0"),
        );
    }
}

use crate::preset::Preset;
use crate::report::RunReport;
use crate::scene::{Checks, Scene, SceneError, SectionDecl};
use serde::Serialize;
use serde_json::Value;

/// One number a protocol measures per sample.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Metric {
    /// Key in reports, the store and the API, e.g. `theta_r`.
    pub name: &'static str,
    /// Short label for axes and tables, e.g. `θ_R`.
    pub label: &'static str,
    /// Unit, e.g. `°`.
    pub unit: &'static str,
    /// What it is, in a sentence.
    pub description: &'static str,
    /// The phase of the run that produces it.
    pub phase: &'static str,
}

/// An experiment on a scene.
pub trait Protocol: Sync {
    /// The name scenes use (`protocol = "…"`).
    fn name(&self) -> &'static str;
    /// One line on what it measures.
    fn about(&self) -> &'static str;
    /// Dimensions it runs in; the first is the default.
    fn dimensions(&self) -> &'static [usize];
    /// Contact models it runs with.
    fn models(&self) -> &'static [&'static str];
    /// The model a scene of this dimension gets when it names none.
    fn default_model(&self, _dimension: usize) -> &'static str {
        self.models()[0]
    }
    /// The scene sections it owns.
    fn sections(&self) -> Vec<SectionDecl>;
    /// The metrics it reports, the headline first.
    fn metrics(&self) -> &'static [Metric];
    /// The scene values a fidelity preset sets, as dotted keys.
    fn preset(&self, preset: Preset) -> Vec<(&'static str, Value)>;
    /// What a preset sets here, as one line (`key = value, …`).
    fn preset_line(&self, preset: Preset) -> String {
        let parts: Vec<String> = self
            .preset(preset)
            .iter()
            .map(|(k, v)| format!("{k} = {v}"))
            .collect();
        parts.join(", ")
    }
    /// Whether it draws grains from the model's distribution (rather than
    /// only running the listed ones).
    fn draws_grains(&self) -> bool {
        true
    }
    /// Checks across its sections, the model's and the core.
    fn check(&self, scene: &Scene, c: &mut Checks);
    /// Writes out the values derived from others.
    fn resolve(&self, _scene: &mut Scene) {}
    /// The fastest impact the protocol makes happen, if it knows one (a
    /// grain falling from the top of its domain): the time step resolves
    /// collisions at this speed when it exceeds the reference speed.
    fn impact_speed(&self, _scene: &Scene) -> Option<f64> {
        None
    }
    /// An estimate of a sample's particle-steps, if the protocol makes one:
    /// good for ranking the samples of a sweep by cost (a queue runs the
    /// cheap ones first), not for a budget.
    fn cost(&self, _scene: &Scene) -> Option<f64> {
        None
    }
    /// Runs a validated, resolved scene.
    fn run(&self, scene: &Scene, observer: &mut dyn Observer) -> Result<RunReport, SceneError>;
}

/// Runs one sample of the scene.
pub fn run(scene: &Scene, observer: &mut dyn Observer) -> Result<RunReport, SceneError> {
    scene.validate()?;
    let scene = scene.resolved();
    scene.protocol()?.run(&scene, observer)
}

/// The settings of the numerical presets shared by every protocol.
pub fn numeric_preset(preset: Preset) -> Vec<(&'static str, Value)> {
    match preset {
        Preset::Quick => vec![
            ("numerics.integrator", Value::from("verlet")),
            ("numerics.dt_factor", Value::from(0.05)),
        ],
        Preset::Standard => vec![
            ("numerics.integrator", Value::from("verlet")),
            ("numerics.dt_factor", Value::from(0.02)),
        ],
        Preset::Paper => vec![
            ("numerics.integrator", Value::from("gear5")),
            ("numerics.dt_factor", Value::from(0.02)),
        ],
    }
}
