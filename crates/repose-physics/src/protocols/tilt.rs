//! The tilting angle (Lee & Herrmann, section 4): a released pile is turned
//! clockwise at a constant rate until it starts to move; θ_T is the tilt at
//! that moment. The run first measures θ_R as fill-and-release does.

use super::fill_release::REPOSE_METRICS;
use super::pile::{self, AfterRelease, Pile};
use super::runner::{Findings, Stop};
use super::{Metric, Observer, Protocol};
use crate::report::{Outcome, Phase, RunReport};
use crate::scene::{Checks, Scene, SceneError, Section, SectionDecl};
use repose_engine::contact::ContactLaw;
use repose_engine::dim::Vector;
use repose_engine::integrate::Integrator;
use serde::{Deserialize, Serialize};
use serde_json::json;

pub struct Tilt;

pub const TILT: Phase = Phase("tilt");

/// The tilt protocol: gravity turns at a constant rate until the pile moves.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TiltSpec {
    /// Rotation rate of the box, degrees per simulated second (clockwise).
    pub rate: f64,
    /// A grain counts as moved once it is this many mean diameters from
    /// where it was when tilting began.
    pub onset_displacement: f64,
    /// The pile "starts to move" once this fraction of grains has moved.
    pub onset_fraction: f64,
    /// Give up (outcome `no_onset`) past this tilt, degrees.
    pub max_angle: f64,
}

impl Default for TiltSpec {
    fn default() -> Self {
        TiltSpec {
            rate: 10.0,
            onset_displacement: 0.5,
            onset_fraction: 0.02,
            max_angle: 45.0,
        }
    }
}

impl Section for TiltSpec {
    const KEY: &'static str = "tilt";
    const ABOUT: &'static str = "how fast the box turns and when the pile counts as moving";

    fn check(&self, _scene: &Scene, c: &mut Checks) {
        c.positive("tilt.rate", self.rate);
        c.positive("tilt.onset_displacement", self.onset_displacement);
        c.fraction("tilt.onset_fraction", self.onset_fraction, false);
        c.positive("tilt.max_angle", self.max_angle);
        if self.max_angle.is_finite() && self.max_angle >= 90.0 {
            c.fail("tilt.max_angle", "must be below 90 degrees");
        }
    }
}

const METRICS: [Metric; 4] = [
    REPOSE_METRICS[0],
    REPOSE_METRICS[1],
    REPOSE_METRICS[2],
    Metric {
        name: "theta_t",
        label: "θ_T",
        unit: "°",
        description: "tilting angle: how far the released pile turns before it starts to move",
        phase: "tilt",
    },
];

impl Protocol for Tilt {
    fn name(&self) -> &'static str {
        "tilt"
    }

    fn about(&self) -> &'static str {
        "fill and release, then tilt the pile until it moves: θ_R and the tilting angle θ_T"
    }

    pile::pile_protocol!(filled: true);

    fn sections(&self) -> Vec<SectionDecl> {
        pile::release_sections(vec![SectionDecl::of::<TiltSpec>()])
    }

    fn metrics(&self) -> &'static [Metric] {
        &METRICS
    }

    fn run(&self, scene: &Scene, observer: &mut dyn Observer) -> Result<RunReport, SceneError> {
        pile::fill_and_release(scene, observer, scene.section::<TiltSpec>()?.clone())
    }
}

/// The tilt stage: turn the released pile until it moves.
impl AfterRelease for TiltSpec {
    fn run<L: ContactLaw<2>, I: Integrator<2>>(
        &self,
        pile: &mut Pile<'_, L, I>,
        findings: &mut Findings,
    ) -> Outcome {
        match tilt(pile, self) {
            Ok((angle, moved)) => {
                findings.metric("theta_t", angle);
                findings.details["tilt"] = json!({"angle": angle, "moved": moved});
                Outcome::Completed
            }
            Err(Stop::TimedOut) => Outcome::NoOnset {
                reason: format!(
                    "the pile did not move before the tilt reached {}°",
                    self.max_angle
                ),
            },
            Err(stop) => stop.outcome(TILT, String::new),
        }
    }
}

/// Turns gravity at the scene's rate until enough grains have moved;
/// returns the tilt (degrees) and the grains counted as moved.
fn tilt<L: ContactLaw<2>, I: Integrator<2>>(
    pile: &mut Pile<'_, L, I>,
    t: &TiltSpec,
) -> Result<(f64, usize), Stop> {
    let run = &mut pile.run;
    let p = &run.sim.particles;
    let reach = t.onset_displacement * 2.0 * p.mean_radius();
    let start: Vec<(u32, Vector<2>)> = p.id.iter().copied().zip(p.pos.iter().copied()).collect();
    let mut start_of = vec![None; p.id.iter().copied().max().map_or(0, |m| m as usize + 1)];
    for (id, x) in &start {
        start_of[*id as usize] = Some(*x);
    }
    let initial = start.len();
    let needed = (t.onset_fraction * initial as f64).ceil().max(1.0) as usize;
    let g0 = run.sim.gravity;
    let rate = t.rate.to_radians();
    let t0 = run.sim.time;
    let limit = t.max_angle.to_radians();
    loop {
        let angle = rate * (run.sim.time - t0);
        run.sample(TILT)?;
        let p = &run.sim.particles;
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
            return Ok((angle.to_degrees(), moved));
        }
        if angle > limit {
            return Err(Stop::TimedOut);
        }
        for _ in 0..run.check_steps {
            let a = rate * (run.sim.time - t0);
            // Turning the box clockwise turns gravity counter-clockwise in the box frame.
            let (s, c) = a.sin_cos();
            run.sim.gravity = Vector::<2>::new(c * g0.x - s * g0.y, s * g0.x + c * g0.y);
            run.sim.step()?;
        }
    }
}
