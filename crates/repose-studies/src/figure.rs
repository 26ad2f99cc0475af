//! A figure as a paper describes it (its layers: what to draw from which
//! sweep, theory curves, quoted values, fits) and a figure's data: what
//! the API serves, the page draws and the reproduction report prints.
//! `draw` computes the one from the other.

use crate::data::SweepData;
use crate::fit::{Fit, Model};
use repose_store::Point;
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::collections::BTreeMap;

/// What a figure shows.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
pub struct FigureData {
    pub paper: String,
    pub figure: String,
    pub title: String,
    pub caption: String,
    pub x_label: String,
    pub y_label: String,
    pub log_x: bool,
    /// The swept axis the measured series plot along, and the series axis.
    pub x: Option<String>,
    pub series_axis: Option<String>,
    pub series: Vec<SeriesData>,
    /// The sweep each study key was read from.
    pub sweeps: BTreeMap<String, String>,
    /// Study sweeps the figure reads that have no data yet.
    pub missing: Vec<String>,
    /// The fits drawn, with their constants.
    #[serde(default)]
    pub fits: Vec<FitData>,
}

/// A fit a figure draws: the fitted constants with their intervals, or
/// why it could not be made.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
pub struct FitData {
    /// What was fitted, e.g. "eq. 1, g̃ = 1".
    pub label: String,
    /// The series it belongs to.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(value_type = Option<Object>)]
    pub series_value: Option<Value>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fit: Option<Fit>,
    /// Why there is no fit (too few points, no convergence).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
}

/// What kind of series it is, for drawing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(rename_all = "snake_case")]
pub enum Kind {
    /// Means with error bars (and the single samples).
    Measured,
    /// A theory curve.
    Theory,
    /// Values quoted from the paper.
    Quoted,
    /// A curve recorded during one run.
    Recorded,
    /// A level line.
    Level,
    /// A curve fitted to measured means.
    Fit,
}

/// One series of a figure.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
pub struct SeriesData {
    pub name: String,
    pub kind: Kind,
    /// The value of the series axis, for measured series split by one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(value_type = Option<Object>)]
    pub series_value: Option<Value>,
    pub points: Vec<PlotPoint>,
    /// A band to shade (e.g. the steady mean ± sd of a recorded curve).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub band: Option<Band>,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
pub struct Band {
    pub lo: f64,
    pub hi: f64,
    pub mean: f64,
}

/// One plotted point: a mean with its statistics, or a plain value.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
pub struct PlotPoint {
    pub x: f64,
    pub y: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sd: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sem: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub n: Option<i64>,
    /// Samples at this point that ended without a result.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub failures: Option<i64>,
    /// The single samples' values.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub samples: Vec<f64>,
    /// A remark the figure marks the point with (e.g. "regime I").
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flag: Option<String>,
}

impl PlotPoint {
    pub fn value(x: f64, y: f64) -> Self {
        PlotPoint {
            x,
            y: Some(y),
            sd: None,
            sem: None,
            n: None,
            failures: None,
            samples: Vec::new(),
            flag: None,
        }
    }
}

/// Why a figure cannot be drawn from a sweep.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FigureError {
    #[error("the sweep does not vary `{0}`")]
    Axis(String),
    #[error("no sample of the sweep measured `{0}`")]
    Metric(String),
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
    /// A model fitted to the means of a metric along `x` (weighted as
    /// [`crate::fitted::weigh`] says), one fit per value of `series`, over the
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

/// The x range the measured and recorded series span.
pub(crate) fn x_range(series: &[SeriesData]) -> Option<(f64, f64)> {
    let xs = series
        .iter()
        .filter(|s| matches!(s.kind, Kind::Measured | Kind::Recorded))
        .flat_map(|s| s.points.iter().map(|p| p.x));
    xs.fold(None, |r, x| match r {
        None => Some((x, x)),
        Some((lo, hi)) => Some((lo.min(x), hi.max(x))),
    })
}

/// A theory curve sampled at 41 points over `[lo, hi]`.
pub(crate) fn curve(
    label: &str,
    f: impl Fn(f64) -> Option<f64>,
    lo: f64,
    hi: f64,
    log: bool,
) -> SeriesData {
    let at = |k: usize| {
        let t = k as f64 / 40.0;
        if log && lo > 0.0 {
            lo * (hi / lo).powf(t)
        } else {
            lo + (hi - lo) * t
        }
    };
    SeriesData {
        name: label.to_string(),
        kind: Kind::Theory,
        series_value: None,
        points: (0..=40)
            .filter_map(|k| Some(PlotPoint::value(at(k), f(at(k))?)))
            .collect(),
        band: None,
    }
}
