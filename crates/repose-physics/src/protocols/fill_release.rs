//! Fill and release (Lee & Herrmann, section 3): grains settle in a closed
//! box, the right wall is removed, and the pile that stays has the angle of
//! repose θ_R, measured by the paper's three methods.

use super::pile;
use super::{Metric, Observer, Protocol};
use crate::report::RunReport;
use crate::scene::{Scene, SceneError, SectionDecl};

pub struct FillRelease;

/// θ_R by the paper's three slope methods, method 3 (its headline) first.
pub const REPOSE_METRICS: [Metric; 3] = [
    Metric {
        name: "theta_r",
        label: "θ_R",
        unit: "°",
        description: "angle of repose by method 3: the curvature of a parabola fitted to the running sum of the surface height",
        phase: "flow",
    },
    Metric {
        name: "theta_r_line",
        label: "θ_R (method 2)",
        unit: "°",
        description: "angle of repose by method 2: a least-squares line through the surface height",
        phase: "flow",
    },
    Metric {
        name: "theta_r_endpoints",
        label: "θ_R (method 1)",
        unit: "°",
        description: "angle of repose by method 1: the line through the first and last columns of the surface",
        phase: "flow",
    },
];

impl Protocol for FillRelease {
    fn name(&self) -> &'static str {
        "fill_release"
    }

    fn about(&self) -> &'static str {
        "fill a box, remove its right wall, measure the angle of repose θ_R"
    }

    pile::pile_protocol!(filled: true);

    fn sections(&self) -> Vec<SectionDecl> {
        pile::release_sections(Vec::new())
    }

    fn metrics(&self) -> &'static [Metric] {
        &REPOSE_METRICS
    }

    fn run(&self, scene: &Scene, observer: &mut dyn Observer) -> Result<RunReport, SceneError> {
        pile::fill_and_release(scene, observer, ())
    }
}
