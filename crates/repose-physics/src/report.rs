//! What one sample produces: the measured angles, the outcome, the cost,
//! and enough state to draw and rerun it.

use crate::engine::StageCounters;
use crate::measure::{SlopeAngles, Stats, Surface};
use crate::particles::Grain;
use crate::scene::{Protocol, RngKind, Scene};
use crate::walls::Wall;
use serde::{Deserialize, Serialize};

/// The engine's name and version, stored with every result.
pub const ENGINE: &str = concat!("repose-physics ", env!("CARGO_PKG_VERSION"));

/// How a run ended. Anything but `completed` carries a reason and no angle.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "status", rename_all = "snake_case")]
pub enum Outcome {
    Completed,
    /// An equilibrium was not reached within its time cap.
    NotSettled {
        phase: String,
        reason: String,
    },
    /// The tilt reached its cap without the pile moving.
    NoOnset {
        reason: String,
    },
    /// The simulation blew up (non-finite values, runaway grain, deep
    /// overlap, grain through a wall).
    Failed {
        phase: String,
        reason: String,
    },
    /// Stopped from outside (a cancelled job).
    Cancelled {
        phase: String,
    },
    /// The run ended cleanly but what it left is not a pile whose slope is
    /// an angle of repose (too few grains left, or a surface rising towards
    /// the open side); no angle is reported.
    Unmeasurable {
        reason: String,
    },
}

impl Outcome {
    pub fn is_completed(&self) -> bool {
        matches!(self, Outcome::Completed)
    }

    pub fn status(&self) -> &'static str {
        match self {
            Outcome::Completed => "completed",
            Outcome::NotSettled { .. } => "not_settled",
            Outcome::NoOnset { .. } => "no_onset",
            Outcome::Failed { .. } => "failed",
            Outcome::Cancelled { .. } => "cancelled",
            Outcome::Unmeasurable { .. } => "unmeasurable",
        }
    }

    pub fn reason(&self) -> Option<String> {
        match self {
            Outcome::Completed => None,
            Outcome::NotSettled { phase, reason } | Outcome::Failed { phase, reason } => {
                Some(format!("{phase}: {reason}"))
            }
            Outcome::NoOnset { reason } | Outcome::Unmeasurable { reason } => Some(reason.clone()),
            Outcome::Cancelled { phase } => Some(format!("cancelled during {phase}")),
        }
    }
}

/// The angle of the tilt protocol.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TiltResult {
    /// Tilting angle θ_T at onset, degrees.
    pub angle: f64,
    /// Grains counted as moved at onset.
    pub moved: usize,
}

/// One point of the constant-flux series: the pile's angle (method 3)
/// just before a grain is added.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FluxPoint {
    pub insertion: usize,
    pub iteration: u64,
    pub time: f64,
    pub angle: f64,
}

/// The constant-flux series and its steady-state statistics (the
/// fluctuation band of the paper's fig. 5 is `mean ± sd`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FluxSummary {
    pub series: Vec<FluxPoint>,
    /// Statistics over the series after the discarded transient.
    pub steady: Option<Stats>,
    /// Largest angle of the steady part, degrees.
    pub max: Option<f64>,
    /// Insertions made because the fastest grain fell below `v_cut` (the
    /// others waited for the displacement test of `[equilibrium]`).
    pub rest_by_speed: usize,
}

/// Predictions of section 6 for this scene's μ (and measured θ_R).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Theory {
    /// Eq. (3), degrees.
    pub marginal_stability: f64,
    /// Eq. (4) with the measured θ_R, degrees.
    pub tilting: Option<f64>,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GrainCounts {
    /// Grains at the start.
    pub initial: usize,
    /// Grains added during the run (flux protocol).
    pub inserted: usize,
    /// Grains that left through the open side.
    pub lost: usize,
    /// Grains at the end.
    #[serde(rename = "final")]
    pub remaining: usize,
}

/// Kinetic energy per grain at one instant (the paper's fig. 1b).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TracePoint {
    pub iteration: u64,
    pub time: f64,
    /// Mean kinetic energy per grain, erg.
    pub kinetic_energy: f64,
    pub max_speed: f64,
    pub phase: Phase,
}

/// The phases of the protocols.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Phase {
    /// Grains fall into the closed box and settle.
    Fill,
    /// The right wall is gone; the pile flows out and settles.
    Flow,
    /// Gravity turns until the pile moves.
    Tilt,
    /// Grains are added one at a time.
    Flux,
    /// A fixed-duration run.
    Run,
}

impl Phase {
    pub fn name(self) -> &'static str {
        match self {
            Phase::Fill => "fill",
            Phase::Flow => "flow",
            Phase::Tilt => "tilt",
            Phase::Flux => "flux",
            Phase::Run => "run",
        }
    }
}

/// The options that change the physics or its numerics, repeated at the top
/// level of a report so no reader has to dig them out of the scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Options {
    /// The fidelity preset the scene named, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub preset: Option<String>,
    pub integrator: String,
    pub normal_force: String,
    pub shear_spring: String,
    pub dt: f64,
}

/// A touching pair at the end of the run (by grain id) and its normal force.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ContactForce {
    pub a: u32,
    pub b: u32,
    /// Normal force, dyn.
    pub force: f64,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FinalState {
    pub grains: Vec<Grain<2>>,
    pub contacts: Vec<ContactForce>,
    pub walls: Vec<Wall<2>>,
}

/// Everything one sample produced.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunReport {
    pub engine: String,
    pub protocol: Protocol,
    pub seed: u64,
    pub rng: RngKind,
    pub outcome: Outcome,
    /// θ_R by the three methods (fill_release and tilt).
    pub repose: Option<SlopeAngles>,
    pub tilt: Option<TiltResult>,
    pub flux: Option<FluxSummary>,
    pub theory: Theory,
    pub grains: GrainCounts,
    pub iterations: u64,
    /// Simulated time, s.
    pub simulated_time: f64,
    /// Wall-clock time of the simulation, s.
    pub wall_time: f64,
    pub particle_steps: u64,
    pub particle_steps_per_second: f64,
    pub options: Options,
    pub counters: StageCounters,
    /// Surface profile the angles were measured on.
    pub surface: Option<Surface>,
    pub energy_trace: Vec<TracePoint>,
    /// Largest overlap seen, as a fraction of the smaller radius.
    pub max_overlap: f64,
    /// The fully resolved scene: rerunning it gives the same numbers.
    pub scene: Scene,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub final_state: Option<FinalState>,
}
