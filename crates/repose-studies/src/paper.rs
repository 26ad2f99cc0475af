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
    /// A slice of the sweep: only these values of the named axes (each one
    /// of the axis's own values), e.g. the points on Earth, to run ahead of
    /// the rest. Empty: the whole sweep. A slice's scenes are those of the
    /// whole sweep, so a whole sweep queued beside it shares its samples.
    pub only: BTreeMap<String, Vec<Value>>,
}

/// A variant of the model as a list, `material.limit_load = "net", …`
/// (empty for the paper's own model). A setting that changes a sample's
/// speed alone, such as its thread count, is no variant and is left out.
pub fn variant_label(set: &[(String, Value)]) -> String {
    let parts: Vec<String> = set
        .iter()
        .filter(|(k, _)| !repose_sweeps::spec::speed_only(k))
        .map(|(k, v)| format!("{k} = {v}"))
        .collect();
    parts.join(", ")
}

impl StudySweep {
    /// The sweep spec that queues it: the same for the page, the API and
    /// `repose reproduce`. Fails, naming the path (`set.<key>` or
    /// `only.<axis>`), where a setting of the variant cannot be set or sets
    /// one of the sweep's axes, or a slice names what is not on an axis.
    ///
    /// A slice (`q.only`) is not the study's sweep: the figures read the
    /// whole sweep, which takes the slice's finished samples as its own.
    pub fn spec(&self, paper: &str, q: &Queue) -> Result<SweepSpec, DocError> {
        let (base, mut axes, samples) = if q.reduced {
            let r = &self.reduced;
            (r.base.clone(), r.axes.clone(), r.samples)
        } else {
            (self.base.clone(), self.axes.clone(), self.samples)
        };
        let mut base = base.as_object().cloned().unwrap_or_else(Map::new);
        for (key, value) in &q.set {
            if axes.contains_key(key) {
                return Err(DocError {
                    field: format!("set.{key}"),
                    message: format!("is an axis of the sweep `{}`, not a setting", self.key),
                });
            }
            doc::set(&mut base, key, value.clone()).map_err(|e| DocError {
                field: format!("set.{}", e.field),
                message: e.message,
            })?;
        }
        self.slice(&mut axes, &q.only)?;
        let mut name = match variant_label(&q.set) {
            v if v.is_empty() => format!("{paper}: {}", self.title),
            v => format!("{paper}: {} [{v}]", self.title),
        };
        if !q.only.is_empty() {
            let sliced = axes.iter().filter(|(k, _)| q.only.contains_key(*k));
            let sliced: BTreeMap<String, Vec<Value>> =
                sliced.map(|(k, v)| (k.clone(), v.clone())).collect();
            name.push_str(&format!(", only {}", slice_label(&sliced)));
        }
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
            study: q.only.is_empty().then(|| format!("{paper}/{}", self.key)),
        })
    }

    /// The slice of this sweep that `wanted` picks (axis → values): the
    /// points whose value on each named axis is one of those wanted. None
    /// where the sweep lacks a named axis or holds none of its values.
    pub fn slice_of(
        &self,
        reduced: bool,
        wanted: &BTreeMap<String, Vec<Value>>,
    ) -> Option<BTreeMap<String, Vec<Value>>> {
        let axes = if reduced {
            &self.reduced.axes
        } else {
            &self.axes
        };
        let mut slice = BTreeMap::new();
        for (axis, values) in wanted {
            let on: Vec<Value> = axes
                .get(axis)?
                .iter()
                .filter(|v| values.iter().any(|w| same(v, w)))
                .cloned()
                .collect();
            if on.is_empty() {
                return None;
            }
            slice.insert(axis.clone(), on);
        }
        (!slice.is_empty()).then_some(slice)
    }

    /// Cuts `axes` down to the values `only` names, keeping the axis's own
    /// spelling of each value (so that the scenes, and their samples, are
    /// the whole sweep's).
    fn slice(
        &self,
        axes: &mut BTreeMap<String, Vec<Value>>,
        only: &BTreeMap<String, Vec<Value>>,
    ) -> Result<(), DocError> {
        for (axis, wanted) in only {
            let field = format!("only.{axis}");
            let Some(values) = axes.get_mut(axis) else {
                let names: Vec<&str> = axes.keys().map(String::as_str).collect();
                return Err(DocError {
                    field,
                    message: format!(
                        "is not an axis of the sweep `{}` (its axes: {})",
                        self.key,
                        names.join(", ")
                    ),
                });
            };
            if wanted.is_empty() {
                return Err(DocError {
                    field,
                    message: "names no value".into(),
                });
            }
            if let Some(w) = wanted.iter().find(|w| !values.iter().any(|v| same(v, w))) {
                return Err(DocError {
                    field,
                    message: format!("{w} is not a value of the sweep `{}`", self.key),
                });
            }
            values.retain(|v| wanted.iter().any(|w| same(v, w)));
        }
        Ok(())
    }
}

/// Whether two axis values are the same, numbers compared by value
/// (`1` and `1.0`, `1e-4` and `0.0001`).
fn same(a: &Value, b: &Value) -> bool {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => x.as_f64() == y.as_f64(),
        (Value::Array(x), Value::Array(y)) => {
            x.len() == y.len() && x.iter().zip(y).all(|(p, q)| same(p, q))
        }
        _ => a == b,
    }
}

/// A slice as a list, `gravity = [0.0,0.0,-9.81]; grains.diameter = 0.001`.
pub fn slice_label(only: &BTreeMap<String, Vec<Value>>) -> String {
    let parts: Vec<String> = only
        .iter()
        .map(|(k, vs)| {
            let vs: Vec<String> = vs.iter().map(Value::to_string).collect();
            format!("{k} = {}", vs.join(" or "))
        })
        .collect();
    parts.join("; ")
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

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn axis_values_are_the_same_by_number_not_by_spelling() {
        assert!(same(&json!(1), &json!(1.0)));
        assert!(same(&json!(1e-4), &json!(0.0001)));
        assert!(same(&json!([0, 0, -9.81]), &json!([0.0, 0.0, -9.81])));
        assert!(!same(&json!([0, 0, -9.81]), &json!([0.0, -9.81])));
        assert!(!same(&json!("1"), &json!(1)));
    }

    #[test]
    fn a_variant_names_what_changes_the_numbers_and_not_the_thread_count() {
        let set = |pairs: &[(&str, Value)]| -> Vec<(String, Value)> {
            pairs
                .iter()
                .map(|(k, v)| (k.to_string(), v.clone()))
                .collect()
        };
        let label = variant_label(&set(&[
            ("material.limit_load", json!("net")),
            ("numerics.threads", json!(2)),
            ("material.contact_attraction", json!("fading")),
        ]));
        assert_eq!(
            label,
            r#"material.limit_load = "net", material.contact_attraction = "fading""#
        );
        assert_eq!(variant_label(&set(&[("numerics.threads", json!(2))])), "");
    }

    #[test]
    fn a_slice_takes_the_sweeps_own_values_and_only_where_it_has_them() {
        let sweeps = (crate::papers::find("ep21").unwrap().sweeps)();
        let heaps = sweeps.iter().find(|s| s.key == "heaps").unwrap();
        let earth: BTreeMap<String, Vec<Value>> =
            [("gravity".to_string(), vec![json!([0, 0, -9.81])])].into();
        let slice = heaps.slice_of(false, &earth).unwrap();
        assert_eq!(slice["gravity"], vec![json!([0.0, 0.0, -9.81])]);
        let spec = heaps
            .spec(
                "ep21",
                &Queue {
                    only: earth.clone(),
                    ..Queue::default()
                },
            )
            .unwrap();
        assert_eq!(spec.axes["gravity"].len(), 1);
        assert_eq!(spec.axes["grains.diameter"], heaps.axes["grains.diameter"]);
        assert_eq!(spec.study, None);
        let moon: BTreeMap<String, Vec<Value>> =
            [("gravity".to_string(), vec![json!([0, 0, -1.62])])].into();
        assert_eq!(heaps.slice_of(false, &moon), None);
        let seed: BTreeMap<String, Vec<Value>> = [("seed".to_string(), vec![json!(1)])].into();
        assert_eq!(heaps.slice_of(false, &seed), None);
        let err = heaps
            .spec(
                "ep21",
                &Queue {
                    only: seed,
                    ..Queue::default()
                },
            )
            .unwrap_err();
        assert_eq!(err.field, "only.seed");
    }
}
