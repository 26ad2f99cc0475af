//! A paper as data: its study sweeps, its figures, how its stated
//! results compare with ours, the quantities its figures compute from a
//! point's axes, its report and how its reports name a point.

use crate::compare::Comparison;
use crate::data::StudyData;
use crate::figure::{Figure, FigureSummary};
use crate::quantity::Quantity;
use repose_physics::doc::{self, DocError};
use repose_physics::Preset;
use repose_sweeps::{Order, SweepSpec};
use serde::Serialize;
use serde_json::{Map, Value};
use std::collections::BTreeMap;

/// A paper whose figures repose reproduces.
pub struct Paper {
    /// Short key, e.g. `lh93`.
    pub key: &'static str,
    pub title: &'static str,
    pub citation: &'static str,
    /// The sweeps behind the figures.
    pub sweeps: fn() -> Vec<StudySweep>,
    /// The figures, in the paper's order.
    pub figures: fn() -> Vec<Figure>,
    /// The paper's stated results against ours.
    pub compare: fn(&StudyData) -> Vec<Comparison>,
    /// Quantities its figures plot that are computed from a point's axis
    /// values (the Bond number from d and g, say).
    pub quantities: &'static [Quantity],
    /// The file stem of its reproduction report in `docs/`.
    pub report: &'static str,
    /// What a fidelity preset gives up on this paper's scenes, from the
    /// speed/accuracy study whose files lie in the given folder.
    pub accuracy: fn(&std::path::Path, Preset) -> Option<String>,
    /// How its reports name a point, in the paper's quantities (`d = 60 µm,
    /// g̃ = 0.063`); `None` leaves the axis values as they are.
    pub point_label: fn(&Map<String, Value>) -> Option<String>,
}

impl Paper {
    pub fn sweep(&self, key: &str) -> Option<StudySweep> {
        (self.sweeps)().into_iter().find(|s| s.key == key)
    }

    pub fn figure(&self, key: &str) -> Option<Figure> {
        (self.figures)().into_iter().find(|f| f.key == key)
    }

    /// What the API lists about the paper.
    pub fn summary(&self) -> PaperSummary {
        PaperSummary {
            key: self.key.into(),
            title: self.title.into(),
            citation: self.citation.into(),
            report: self.report.into(),
            sweeps: (self.sweeps)(),
            figures: (self.figures)()
                .iter()
                .map(|f| FigureSummary {
                    key: f.key.into(),
                    title: f.title.into(),
                    caption: f.caption.into(),
                    sweeps: f.sweeps(),
                })
                .collect(),
        }
    }
}

/// One sweep of a paper's study.
#[derive(Debug, Clone, Serialize, utoipa::ToSchema)]
pub struct StudySweep {
    /// Key within the paper, e.g. `fig347`.
    #[schema(value_type = String)]
    pub key: &'static str,
    #[schema(value_type = String)]
    pub title: &'static str,
    #[schema(value_type = String)]
    pub protocol: &'static str,
    /// Scene values shared by every point.
    #[schema(value_type = Object)]
    pub base: Value,
    /// Values swept, by dotted scene key.
    #[schema(value_type = HashMap<String, Vec<Object>>)]
    pub axes: BTreeMap<String, Vec<Value>>,
    /// Samples a point (the paper's count).
    pub samples: u32,
    /// Higher runs first.
    pub priority: i64,
    /// A small version of the same sweep for tests and previews.
    pub reduced: Reduced,
}

/// The small version of a study sweep: smaller boxes, fewer points.
#[derive(Debug, Clone, Serialize, utoipa::ToSchema)]
pub struct Reduced {
    #[schema(value_type = Object)]
    pub base: Value,
    #[schema(value_type = HashMap<String, Vec<Object>>)]
    pub axes: BTreeMap<String, Vec<Value>>,
    pub samples: u32,
}

/// How to queue a study sweep.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Queue {
    pub fidelity: Preset,
    /// Samples a point, if not the paper's count.
    pub samples: Option<u32>,
    /// The small version.
    pub reduced: bool,
    /// A variant of the model: dotted scene paths and the values every
    /// scene of the sweep takes (`material.limit_load = "net"`), over the
    /// paper's base; not an axis of the sweep.
    pub set: Vec<(String, Value)>,
    /// The claim priority, if not the study sweep's own.
    pub priority: Option<i64>,
    /// The order of its jobs in the queue.
    pub order: Order,
}

/// A variant of the model as a list, `material.limit_load = "net", …`
/// (empty for the paper's own model).
pub fn variant_label(set: &[(String, Value)]) -> String {
    let parts: Vec<String> = set.iter().map(|(k, v)| format!("{k} = {v}")).collect();
    parts.join(", ")
}

impl StudySweep {
    /// The sweep spec that queues it: the same for the page, the API and
    /// `repose reproduce`. Fails, naming the path, where a setting of the
    /// variant cannot be set or sets one of the sweep's axes.
    pub fn spec(&self, paper: &str, q: &Queue) -> Result<SweepSpec, DocError> {
        let (base, axes, samples) = if q.reduced {
            let r = &self.reduced;
            (r.base.clone(), r.axes.clone(), r.samples)
        } else {
            (self.base.clone(), self.axes.clone(), self.samples)
        };
        let mut base = base.as_object().cloned().unwrap_or_else(Map::new);
        for (key, value) in &q.set {
            if axes.contains_key(key) {
                return Err(DocError {
                    field: key.clone(),
                    message: format!("is an axis of the sweep `{}`, not a setting", self.key),
                });
            }
            doc::set(&mut base, key, value.clone())?;
        }
        let name = match variant_label(&q.set) {
            v if v.is_empty() => format!("{paper}: {}", self.title),
            v => format!("{paper}: {} [{v}]", self.title),
        };
        Ok(SweepSpec {
            name: Some(name),
            protocol: self.protocol.to_string(),
            base,
            axes,
            samples: q.samples.unwrap_or(samples),
            target_sem: None,
            target_metric: None,
            max_samples: None,
            fidelity: q.fidelity,
            seed_base: 0,
            priority: q.priority.unwrap_or(self.priority),
            order: q.order,
            study: Some(format!("{paper}/{}", self.key)),
        })
    }
}

/// A paper as the API lists it.
#[derive(Debug, Clone, Serialize, utoipa::ToSchema)]
pub struct PaperSummary {
    pub key: String,
    pub title: String,
    pub citation: String,
    /// Its reproduction report, served at `/docs/<report>.md`.
    pub report: String,
    pub sweeps: Vec<StudySweep>,
    pub figures: Vec<FigureSummary>,
}
