//! Fits on figures: a paper's model fitted to the means of a metric along
//! an axis, one fit per series, drawn as a curve over the fitted range
//! and listed with its constants, so that the page, the API and the
//! reproduction report show the same numbers.

use crate::data::{StudyData, SweepData};
use crate::figure::{curve, FitData, Kind, Layer, SeriesData};
use crate::fit::{fit, Datum, Fit, FitError, Model};
use crate::quantity::{series_value, symbol, x_value, Quantity};
use repose_store::{Aggregate, Point};
use serde_json::Value;

/// The fits of one layer (none for layers that are not fits); their
/// curves go to `series`.
pub(crate) fn fits(
    layer: &Layer,
    study: &StudyData,
    log_x: bool,
    quantities: &[Quantity],
    series: &mut Vec<SeriesData>,
) -> Vec<FitData> {
    match layer {
        Layer::Fit {
            sweep,
            x,
            series: by,
            y,
            model,
            start,
            label,
            keep,
        } => {
            let Some(d) = study.get(sweep) else {
                return Vec::new();
            };
            let along = Along {
                x,
                by: *by,
                y,
                keep: *keep,
                quantities,
            };
            along
                .groups(d)
                .into_iter()
                .map(|(value, data)| {
                    let name = match &value {
                        Some(v) => format!(
                            "{label}, {} = {v}",
                            symbol(by.unwrap_or_default(), quantities)
                        ),
                        None => label.to_string(),
                    };
                    fitted(model, start, &name, value, &data, log_x, series)
                })
                .collect()
        }
        Layer::Computed { sweep, f } => {
            let Some(d) = study.get(sweep) else {
                return Vec::new();
            };
            let (more, fits) = f(d);
            series.extend(more);
            fits
        }
        _ => Vec::new(),
    }
}

/// Which means a fit reads.
pub struct Along<'a> {
    pub x: &'a str,
    pub by: Option<&'a str>,
    pub y: &'a str,
    pub keep: fn(&Point) -> bool,
    /// The paper's computed quantities, which `x` and `by` may name.
    pub quantities: &'a [Quantity],
}

impl Along<'_> {
    /// The points of each series value, in order of the value: `(x, mean)`
    /// with the standard error as the weight where every point has one.
    pub fn groups(&self, d: &SweepData) -> Vec<(Option<Value>, Vec<Datum>)> {
        let mut out: Vec<(Option<Value>, Vec<Datum>)> = Vec::new();
        for p in d.points.iter().filter(|p| (self.keep)(p)) {
            let Some(a) = p.metrics.get(self.y).copied().filter(|a| a.n > 0) else {
                continue;
            };
            let (Some(x), Some(y)) = (x_value(&p.point, self.x, self.quantities), a.mean) else {
                continue;
            };
            let value = self.by.map(|s| series_value(&p.point, s, self.quantities));
            let datum = Datum {
                x,
                y,
                sigma: weight(&a),
            };
            match out.iter_mut().find(|(v, _)| *v == value) {
                Some((_, data)) => data.push(datum),
                None => out.push((value, vec![datum])),
            }
        }
        let key = |v: &Option<Value>| v.as_ref().and_then(Value::as_f64).unwrap_or(0.0);
        out.sort_by(|a, b| key(&a.0).total_cmp(&key(&b.0)));
        for (_, data) in &mut out {
            data.sort_by(|a, b| a.x.total_cmp(&b.x));
            weights_all_or_none(data);
        }
        out
    }

    /// Every point's mean of `y` along `x`, as one group.
    pub fn means(x: &str, y: &str, d: &SweepData, quantities: &[Quantity]) -> Vec<Datum> {
        let along = Along {
            x,
            by: None,
            y,
            keep: |_| true,
            quantities,
        };
        along.groups(d).pop().map(|g| g.1).unwrap_or_default()
    }
}

/// Weights only where every point has one: a fit of some weighted and
/// some unweighted points would weigh them on different scales.
pub fn weights_all_or_none(data: &mut [Datum]) {
    if data.iter().any(|d| d.sigma.is_none()) {
        data.iter_mut().for_each(|d| d.sigma = None);
    }
}

/// A point's standard error, if it has a positive one.
fn weight(a: &Aggregate) -> Option<f64> {
    a.sem.filter(|s| *s > 0.0 && s.is_finite())
}

/// Fits one group and draws the curve if the fit succeeds.
pub fn fitted(
    model: &Model,
    start: &[f64],
    name: &str,
    value: Option<Value>,
    data: &[Datum],
    log_x: bool,
    series: &mut Vec<SeriesData>,
) -> FitData {
    let result: Result<Fit, FitError> = fit(model, data, start);
    match result {
        Ok(f) => {
            let lo = data.iter().map(|d| d.x).fold(f64::INFINITY, f64::min);
            let hi = data.iter().map(|d| d.x).fold(f64::NEG_INFINITY, f64::max);
            let p: Vec<f64> = f.params.iter().map(|p| p.value).collect();
            let mut s = curve(name, |x| Some((model.f)(x, &p)), lo, hi, log_x);
            s.kind = Kind::Fit;
            s.series_value = value.clone();
            series.push(s);
            FitData {
                label: name.to_string(),
                series_value: value,
                fit: Some(f),
                error: None,
            }
        }
        Err(e) => FitData {
            label: name.to_string(),
            series_value: value,
            fit: None,
            error: Some(e.to_string()),
        },
    }
}
