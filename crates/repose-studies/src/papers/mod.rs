//! Each paper's study as data: the sweeps behind its figures, the figures
//! (which metric against which axis, the theory curves, the values the
//! paper quotes) and the comparison of its stated results with ours.
//!
//! A figure names the sweeps it draws from by their key within the paper;
//! [`crate::figure`] turns a figure and the data of those sweeps into what
//! the API serves, the page draws and the reproduction report prints, so
//! all three show the same thing. Adding a figure is one entry in its
//! paper's list; adding a paper is a module and one line in [`PAPERS`].

pub mod ep21;
pub mod lh93;

use crate::compare::Comparison;
use crate::data::{StudyData, SweepData};
use crate::figure::{FitData, SeriesData};
use crate::fit::Model;
use repose_physics::Preset;
use repose_store::Point;
use repose_sweeps::SweepSpec;
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

/// A quantity computed from the axis values of a point.
pub struct Quantity {
    /// The name figures use in place of an axis, e.g. `ep21.bond`.
    pub name: &'static str,
    /// Its symbol in labels, e.g. `Bo`.
    pub symbol: &'static str,
    pub f: fn(&Map<String, Value>) -> Option<f64>,
}

/// Every paper. Registering one is one line here.
pub static PAPERS: &[&Paper] = &[&lh93::PAPER, &ep21::PAPER];

/// The value of `x` at a point: the axis of that name, or a paper's
/// quantity of that name computed from the point's axes.
pub fn x_value(point: &Map<String, Value>, x: &str) -> Option<f64> {
    if let Some(v) = point.get(x) {
        return v.as_f64();
    }
    PAPERS
        .iter()
        .flat_map(|p| p.quantities)
        .find(|q| q.name == x)
        .and_then(|q| (q.f)(point))
}

/// How labels name an axis or quantity: its symbol, or the axis itself.
pub fn symbol(x: &str) -> &str {
    PAPERS
        .iter()
        .flat_map(|p| p.quantities)
        .find(|q| q.name == x)
        .map_or(x, |q| q.symbol)
}

/// The value that names a point's series along `axis` (an axis value, or
/// a computed quantity as a number; null when neither is known).
pub fn series_value(point: &Map<String, Value>, axis: &str) -> Value {
    match point.get(axis) {
        Some(v) => v.clone(),
        None => x_value(point, axis).map_or(Value::Null, Value::from),
    }
}

/// The paper of this key.
pub fn find(key: &str) -> Option<&'static Paper> {
    PAPERS.iter().copied().find(|p| p.key == key)
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
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Queue {
    pub fidelity: Preset,
    /// Samples a point, if not the paper's count.
    pub samples: Option<u32>,
    /// The small version.
    pub reduced: bool,
}

impl StudySweep {
    /// The sweep spec that queues it: the same for the page, the API and
    /// `repose reproduce`.
    pub fn spec(&self, paper: &str, q: Queue) -> SweepSpec {
        let (base, axes, samples) = if q.reduced {
            let r = &self.reduced;
            (r.base.clone(), r.axes.clone(), r.samples)
        } else {
            (self.base.clone(), self.axes.clone(), self.samples)
        };
        SweepSpec {
            name: Some(format!("{paper}: {}", self.title)),
            protocol: self.protocol.to_string(),
            base: base.as_object().cloned().unwrap_or_else(Map::new),
            axes,
            samples: q.samples.unwrap_or(samples),
            target_sem: None,
            target_metric: None,
            max_samples: None,
            fidelity: q.fidelity,
            seed_base: 0,
            priority: self.priority,
            study: Some(format!("{paper}/{}", self.key)),
        }
    }
}

/// A figure of a paper.
#[derive(Debug, Clone)]
pub struct Figure {
    /// Key within the paper, e.g. `3` or `7a`.
    pub key: &'static str,
    pub title: &'static str,
    pub caption: &'static str,
    pub x_label: &'static str,
    pub y_label: &'static str,
    pub log_x: bool,
    pub layers: Vec<Layer>,
}

/// A figure as the API lists it.
#[derive(Debug, Clone, Serialize, utoipa::ToSchema)]
pub struct FigureSummary {
    pub key: String,
    pub title: String,
    pub caption: String,
    /// The study sweeps it draws from.
    pub sweeps: Vec<String>,
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

/// One thing a figure draws.
#[derive(Debug, Clone)]
pub enum Layer {
    /// Means of a metric (or the sum of several) along a swept axis, one
    /// series per value of another axis if `series` is set. The label names
    /// the data, or with a series the symbol of its axis ("μ = 0.2").
    Measured {
        sweep: &'static str,
        x: &'static str,
        series: Option<&'static str>,
        y: &'static [&'static str],
        label: &'static str,
    },
    /// A theory curve over the x range of the measured data.
    Curve {
        label: &'static str,
        f: fn(f64) -> Option<f64>,
    },
    /// A theory value at each measured x, from the mean of a metric there
    /// (eq. 4 evaluated with the measured θ_R).
    AtPoints {
        sweep: &'static str,
        x: &'static str,
        input: &'static str,
        label: &'static str,
        f: fn(f64, f64) -> Option<f64>,
    },
    /// Values the paper quotes: `(x, y, error)`.
    Quoted {
        label: &'static str,
        points: &'static [(f64, f64, f64)],
    },
    /// A curve recorded in the report of a sweep's first sample.
    Recorded {
        sweep: &'static str,
        curve: &'static str,
        label: &'static str,
    },
    /// A level line at the mean of a metric at one point of a sweep.
    Level {
        sweep: &'static str,
        at: (&'static str, f64),
        metric: &'static str,
        label: &'static str,
    },
    /// A model fitted to the means of a metric along `x` (weighted by
    /// their standard errors), one fit per value of `series`, over the
    /// points `keep` accepts: the fitted curves and their constants.
    Fit {
        sweep: &'static str,
        x: &'static str,
        series: Option<&'static str>,
        y: &'static str,
        model: &'static Model,
        start: &'static [f64],
        label: &'static str,
        keep: fn(&Point) -> bool,
    },
    /// Series and fits a paper computes from a sweep in its own way (fits
    /// of fitted constants, say).
    Computed {
        sweep: &'static str,
        f: fn(&SweepData) -> (Vec<SeriesData>, Vec<FitData>),
    },
}

impl Layer {
    /// The study sweep this layer reads, if any.
    pub fn sweep(&self) -> Option<&'static str> {
        match self {
            Layer::Measured { sweep, .. }
            | Layer::AtPoints { sweep, .. }
            | Layer::Recorded { sweep, .. }
            | Layer::Level { sweep, .. }
            | Layer::Fit { sweep, .. }
            | Layer::Computed { sweep, .. } => Some(sweep),
            Layer::Curve { .. } | Layer::Quoted { .. } => None,
        }
    }
}

impl Figure {
    /// The study sweeps it reads, without repeats.
    pub fn sweeps(&self) -> Vec<String> {
        let mut out: Vec<String> = Vec::new();
        for s in self.layers.iter().filter_map(Layer::sweep) {
            if !out.iter().any(|o| o == s) {
                out.push(s.to_string());
            }
        }
        out
    }

    /// Whether drawing it needs the report of a sweep's first sample.
    pub fn needs_report(&self, sweep: &str) -> bool {
        self.layers
            .iter()
            .any(|l| matches!(l, Layer::Recorded { sweep: s, .. } if *s == sweep))
    }

    /// The axis the measured layers plot along, and the series axis.
    pub fn axes(&self) -> Option<(&'static str, Option<&'static str>)> {
        self.layers.iter().find_map(|l| match l {
            Layer::Measured { x, series, .. } => Some((*x, *series)),
            _ => None,
        })
    }
}
