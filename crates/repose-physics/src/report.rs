//! What one sample produces: the protocol's metrics, the outcome, the cost,
//! and enough state to draw and rerun it.
//!
//! The report is one document for every protocol: metrics by name (as the
//! protocol declares them), theory values, curves and surface profiles for
//! the page to draw, and the protocol's own details. Reports stored by
//! version 0.1 of the engine read back in this shape through [`upgrade`].

use crate::scene::{RngKind, Scene};
use repose_engine::particles::Grain;
use repose_engine::simulation::StageCounters;
use repose_engine::walls::WallSpec;
use serde::{Serialize, Serializer};
use serde_json::{json, Map, Value};
use std::collections::BTreeMap;

/// The engine's name and version, stored with every result.
pub const ENGINE: &str = concat!("repose-physics ", env!("CARGO_PKG_VERSION"));

/// How a run ended. Anything but `completed` carries a reason and no angle.
#[derive(Debug, Clone, PartialEq, Serialize)]
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
    /// The run ended cleanly but what it left cannot be measured (too few
    /// grains, or a surface rising towards the open side); no metric is reported.
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

/// A phase of a protocol, by name (each protocol names its own).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Phase(pub &'static str);

impl Phase {
    pub fn name(self) -> &'static str {
        self.0
    }
}

impl Serialize for Phase {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.0)
    }
}

/// A value a theory predicts for this scene, e.g. eq. (3) of the paper.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Quantity {
    pub name: String,
    pub label: String,
    pub value: f64,
}

/// A curve the run recorded, for the page to draw as a line.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Curve {
    pub name: String,
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    /// `[x, y]` pairs.
    pub points: Vec<[f64; 2]>,
    /// A band to shade (e.g. the steady mean ± sd), if any.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub band: Option<Band>,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Band {
    pub lo: f64,
    pub hi: f64,
    pub mean: f64,
}

/// The surface of a pile along one horizontal axis: the highest grain top
/// in each column.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Profile {
    /// The horizontal axis (0 = x, 1 = y).
    pub axis: usize,
    /// Column width, adjusted to tile the measured span.
    pub cell_width: f64,
    /// Column centres.
    pub x: Vec<f64>,
    /// Highest grain top in each column (0 for an empty column).
    pub h: Vec<f64>,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct GrainCounts {
    /// Grains at the start.
    pub initial: usize,
    /// Grains added during the run.
    pub inserted: usize,
    /// Grains that left the simulation.
    pub lost: usize,
    /// Grains at the end.
    #[serde(rename = "final")]
    pub remaining: usize,
}

/// Kinetic energy per grain at one instant (the paper's fig. 1b).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TracePoint {
    pub iteration: u64,
    pub time: f64,
    /// Mean kinetic energy per grain.
    pub kinetic_energy: f64,
    pub max_speed: f64,
    pub phase: Phase,
}

/// The options that change the physics or its numerics, repeated at the top
/// level of a report so no reader has to dig them out of the scene.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Options {
    /// The fidelity preset the scene named, if any.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub preset: Option<String>,
    pub integrator: String,
    pub dt: f64,
    /// The model's physics choices (e.g. `normal_force`, `shear_spring`).
    pub physics: BTreeMap<String, String>,
}

/// A touching pair at the end of the run (by grain id) and its normal force.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ContactForce {
    pub a: u32,
    pub b: u32,
    pub force: f64,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FinalState {
    pub grains: Vec<Grain>,
    pub contacts: Vec<ContactForce>,
    pub walls: Vec<WallSpec>,
}

/// Everything one sample produced.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunReport {
    pub engine: String,
    pub protocol: String,
    pub model: String,
    pub dimension: usize,
    pub seed: u64,
    pub rng: RngKind,
    pub outcome: Outcome,
    /// The protocol's metrics that this run measured, by name.
    pub metrics: BTreeMap<String, f64>,
    /// What theory predicts for this scene.
    pub theory: Vec<Quantity>,
    /// Curves recorded during the run.
    pub series: Vec<Curve>,
    /// Surface profiles the metrics were measured on.
    pub profiles: Vec<Profile>,
    /// The protocol's own findings beyond its metrics.
    pub details: Value,
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
    pub energy_trace: Vec<TracePoint>,
    /// Largest overlap seen, as a fraction of the smaller radius.
    pub max_overlap: f64,
    /// The fully resolved scene: rerunning it gives the same numbers.
    pub scene: Scene,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub final_state: Option<FinalState>,
}

impl RunReport {
    /// A measured metric, if this run has it.
    pub fn metric(&self, name: &str) -> Option<f64> {
        self.metrics.get(name).copied()
    }
}

/// Leaves out of a report's JSON what says how its run was computed (the
/// clock's times, the threads that shared its steps) rather than what it
/// computed: two runs of the same scene and seed then compare equal to the
/// bit, on any machine and thread count.
pub fn simulated_numbers(mut report: Value) -> Value {
    if let Some(o) = report.as_object_mut() {
        o.remove("wall_time");
        o.remove("particle_steps_per_second");
        if let Some(c) = o.get_mut("counters").and_then(Value::as_object_mut) {
            for how in [
                "integrate",
                "neighbours",
                "contacts",
                "walls",
                "shared_steps",
            ] {
                c.remove(how);
            }
        }
    }
    report
}

/// Reads a stored report in the current shape. Reports of version 0.1 kept
/// each protocol's numbers in fields of their own (`repose`, `tilt`,
/// `flux`, `surface`, `theory`); they are rewritten here, nothing dropped.
pub fn upgrade(report: Value) -> Value {
    let Value::Object(mut r) = report else {
        return report;
    };
    if r.contains_key("metrics") {
        return Value::Object(r);
    }
    let mut metrics = Map::new();
    let mut details = Map::new();
    if let Some(slopes) = r.remove("repose").filter(|v| !v.is_null()) {
        for (metric, key) in [
            ("theta_r_endpoints", "endpoints"),
            ("theta_r_line", "line_fit"),
            ("theta_r", "cumulative_fit"),
        ] {
            if let Some(v) = slopes.get(key).filter(|v| v.is_number()) {
                metrics.insert(metric.into(), v.clone());
            }
        }
        details.insert("slopes".into(), slopes);
    }
    if let Some(tilt) = r.remove("tilt").filter(|v| !v.is_null()) {
        if let Some(a) = tilt.get("angle").filter(|v| v.is_number()) {
            metrics.insert("theta_t".into(), a.clone());
        }
        details.insert("tilt".into(), tilt);
    }
    let mut series = Vec::new();
    if let Some(mut flux) = r.remove("flux").filter(|v| !v.is_null()) {
        let steady = &flux["steady"];
        for (metric, v) in [
            ("theta_ms_mean", &steady["mean"]),
            ("theta_ms_sd", &steady["sd"]),
            ("theta_ms_max", &flux["max"]),
        ] {
            if v.is_number() {
                metrics.insert(metric.into(), v.clone());
            }
        }
        let points: Vec<Value> = flux["series"]
            .as_array()
            .into_iter()
            .flatten()
            .map(|p| json!([p["iteration"], p["angle"]]))
            .collect();
        let band = steady["mean"]
            .as_f64()
            .zip(steady["sd"].as_f64())
            .map(|(m, sd)| json!({"lo": m - sd, "hi": m + sd, "mean": m}));
        let mut curve = json!({
            "name": "pile_angle", "title": "Pile angle before each insertion (fig. 5)",
            "x_label": "iteration", "y_label": "pile angle (°)", "points": points,
        });
        if let Some(b) = band {
            curve["band"] = b;
        }
        series.push(curve);
        if let Some(f) = flux.as_object_mut() {
            f.remove("series");
        }
        details.insert("flux".into(), flux);
    }
    let theory = r.remove("theory").unwrap_or(Value::Null);
    let mut quantities = Vec::new();
    if let Some(v) = theory["marginal_stability"].as_f64() {
        quantities
            .push(json!({"name": "theta_ms_eq3", "label": "θ_MS = atan(3μ), eq. (3)", "value": v}));
    }
    if let Some(v) = theory["tilting"].as_f64() {
        quantities.push(json!({"name": "theta_t_eq4", "label": "θ_T by eq. (4)", "value": v}));
    }
    let profiles = match r.remove("surface") {
        Some(Value::Object(mut s)) => {
            s.insert("axis".into(), json!(0));
            vec![Value::Object(s)]
        }
        // Null, or not a profile any build wrote: no profile.
        _ => Vec::new(),
    };
    if let Some(Value::Object(o)) = r.get_mut("options") {
        let mut physics = Map::new();
        for key in ["normal_force", "shear_spring"] {
            if let Some(v) = o.remove(key) {
                physics.insert(key.into(), v);
            }
        }
        o.insert("physics".into(), Value::Object(physics));
    }
    // Version 0.1 had one model, Lee & Herrmann's, under this name.
    r.insert("model".into(), json!("lee_herrmann"));
    r.insert("dimension".into(), json!(2));
    r.insert("metrics".into(), Value::Object(metrics));
    r.insert("theory".into(), Value::Array(quantities));
    r.insert("series".into(), Value::Array(series));
    r.insert("profiles".into(), Value::Array(profiles));
    r.insert("details".into(), Value::Object(details));
    Value::Object(r)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_old_reports_surface_becomes_a_profile_whatever_its_shape() {
        let profile = upgrade(json!({ "surface": { "heights": [1.0, 2.0] } }));
        assert_eq!(
            profile["profiles"],
            json!([{ "heights": [1.0, 2.0], "axis": 0 }])
        );
        // A surface no build wrote (a number) is no profile, and no panic.
        let odd = upgrade(json!({ "surface": 3.5 }));
        assert_eq!(odd["profiles"], json!([]));
        let none = upgrade(json!({ "surface": null }));
        assert_eq!(none["profiles"], json!([]));
    }
}
