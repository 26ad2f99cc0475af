//! Drawing a figure: its data computed from the stored points and samples
//! of the sweeps behind it, with its theory curves evaluated here.

use crate::data::{same, StudyData, SweepData};
use crate::figure::{
    curve, x_range, Figure, FigureData, FigureError, Kind, Layer, PlotPoint, SeriesData,
};
use crate::paper::Paper;
use crate::quantity::{series_value, x_value, Quantity};
use repose_store::Aggregate;
use serde_json::Value;
use std::collections::BTreeMap;

impl Figure {
    /// The figure from the data of its study sweeps; sweeps without data
    /// are listed as missing and their layers left out.
    pub fn data(&self, paper: &Paper, study: &StudyData) -> FigureData {
        let q = paper.quantities;
        let (x, series_axis) = self.axes().unzip();
        let mut out = FigureData {
            paper: paper.key.to_string(),
            figure: self.key.to_string(),
            title: self.title.to_string(),
            caption: self.caption.to_string(),
            x_label: self.x_label.to_string(),
            y_label: self.y_label.to_string(),
            log_x: self.log_x,
            x: x.map(String::from),
            series_axis: series_axis.flatten().map(String::from),
            series: Vec::new(),
            sweeps: BTreeMap::new(),
            missing: Vec::new(),
            fits: Vec::new(),
        };
        for key in self.sweeps() {
            match study.get(&key) {
                Some(d) => {
                    out.sweeps.insert(key, d.id.clone());
                }
                None => out.missing.push(key),
            }
        }
        for layer in &self.layers {
            out.series.extend(self.layer(layer, study, q));
            out.fits.extend(crate::fitted::fits(
                layer,
                study,
                self.log_x,
                q,
                &mut out.series,
            ));
        }
        let range = x_range(&out.series).filter(|(lo, hi)| hi > lo);
        for layer in &self.layers {
            if let (Layer::Curve { label, f }, Some((lo, hi))) = (layer, range) {
                out.series.push(curve(label, *f, lo, hi, self.log_x));
            }
        }
        level_lines(&self.layers, study, range, &mut out.series);
        out
    }

    /// Whether the figure can be drawn from this one sweep: its measured
    /// layers' axes are swept and their metrics measured.
    pub fn fits(&self, quantities: &[Quantity], sweep: &SweepData) -> Result<(), FigureError> {
        for layer in &self.layers {
            if let Layer::Measured { x, series, y, .. } = layer {
                for axis in std::iter::once(*x).chain(*series) {
                    if !sweep
                        .points
                        .iter()
                        .any(|p| x_value(&p.point, axis, quantities).is_some())
                    {
                        return Err(FigureError::Axis(axis.to_string()));
                    }
                }
                for m in y.iter() {
                    if !sweep.points.iter().any(|p| p.metrics.contains_key(*m)) {
                        return Err(FigureError::Metric(m.to_string()));
                    }
                }
            }
        }
        Ok(())
    }

    /// The figure drawn from one sweep for every study key it reads.
    pub fn from_sweep(&self, paper: &Paper, sweep: SweepData) -> Result<FigureData, FigureError> {
        self.fits(paper.quantities, &sweep)?;
        let mut study = StudyData::default();
        for key in self.sweeps() {
            study.sweeps.insert(key, sweep.clone());
        }
        Ok(self.data(paper, &study))
    }

    fn layer(&self, layer: &Layer, study: &StudyData, q: &[Quantity]) -> Vec<SeriesData> {
        match layer {
            Layer::Measured {
                sweep,
                x,
                series,
                y,
                label,
            } => study
                .get(sweep)
                .map(|d| measured(d, (x, *series), y, label, q))
                .unwrap_or_default(),
            Layer::AtPoints {
                sweep,
                x,
                input,
                label,
                f,
            } => study
                .get(sweep)
                .map(|d| vec![at_points(d, x, input, label, *f, q)])
                .unwrap_or_default(),
            Layer::Quoted { label, points } => vec![SeriesData {
                name: label.to_string(),
                kind: Kind::Quoted,
                series_value: None,
                points: points
                    .iter()
                    .map(|(x, y, e)| PlotPoint {
                        sd: Some(*e),
                        ..PlotPoint::value(*x, *y)
                    })
                    .collect(),
                band: None,
            }],
            Layer::Recorded {
                sweep,
                curve,
                label,
            } => study
                .get(sweep)
                .and_then(|d| recorded(d, curve, label))
                .into_iter()
                .collect(),
            Layer::Curve { .. }
            | Layer::Level { .. }
            | Layer::Fit { .. }
            | Layer::Computed { .. } => Vec::new(),
        }
    }
}

/// Statistics of the sum of several metrics at a point (sd and sem in quadrature).
fn summed(p: &repose_store::Point, y: &[&str]) -> Option<Aggregate> {
    let aggs: Vec<Aggregate> = y
        .iter()
        .map(|m| p.metrics.get(*m).copied().filter(|a| a.n > 0))
        .collect::<Option<_>>()?;
    let quad = |f: fn(&Aggregate) -> Option<f64>| -> Option<f64> {
        aggs.iter()
            .map(|a| f(a).map(|v| v * v))
            .sum::<Option<f64>>()
            .map(f64::sqrt)
    };
    Some(Aggregate {
        n: aggs.iter().map(|a| a.n).min().unwrap_or(0),
        mean: aggs.iter().map(|a| a.mean).sum(),
        sd: quad(|a| a.sd),
        sem: quad(|a| a.sem),
    })
}

/// Means of `y` (summed over its metrics) along `x`, one series per
/// value of `series`.
pub(crate) fn measured(
    d: &SweepData,
    (x, series): (&str, Option<&str>),
    y: &[&str],
    label: &str,
    q: &[Quantity],
) -> Vec<SeriesData> {
    // Series values in order of first appearance, then sorted numerically.
    let mut values: Vec<Option<Value>> = Vec::new();
    for p in &d.points {
        let v = series.map(|s| series_value(&p.point, s, q));
        if !values.contains(&v) {
            values.push(v);
        }
    }
    let key = |v: &Option<Value>| v.as_ref().and_then(Value::as_f64).unwrap_or(0.0);
    values.sort_by(|a, b| key(a).total_cmp(&key(b)));
    values
        .into_iter()
        .map(|value| {
            let mut points: Vec<PlotPoint> = d
                .points
                .iter()
                .filter(|p| series.map(|s| series_value(&p.point, s, q)) == value)
                .filter_map(|p| {
                    let xv = x_value(&p.point, x, q)?;
                    let agg = summed(p, y).unwrap_or(Aggregate::EMPTY);
                    Some(PlotPoint {
                        x: xv,
                        y: agg.mean,
                        sd: agg.sd,
                        sem: agg.sem,
                        n: Some(agg.n),
                        failures: Some(p.failures),
                        samples: sample_values(d, &p.point, y),
                        flag: None,
                    })
                })
                .collect();
            points.sort_by(|a, b| a.x.total_cmp(&b.x));
            let name = match &value {
                Some(v) => format!("{label} = {v}"),
                None => label.to_string(),
            };
            SeriesData {
                name,
                kind: Kind::Measured,
                series_value: value,
                points,
                band: None,
            }
        })
        .collect()
}

/// The values of the single samples at a point (summed over `y`).
fn sample_values(d: &SweepData, point: &serde_json::Map<String, Value>, y: &[&str]) -> Vec<f64> {
    d.samples
        .iter()
        .filter(|s| &s.point == point)
        .filter_map(|s| {
            y.iter()
                .map(|m| s.metrics.get(*m).copied())
                .sum::<Option<f64>>()
        })
        .collect()
}

fn at_points(
    d: &SweepData,
    x: &str,
    input: &str,
    label: &str,
    f: fn(f64, f64) -> Option<f64>,
    q: &[Quantity],
) -> SeriesData {
    let points = d
        .along(x, None, input, q)
        .into_iter()
        .filter_map(|(xv, a)| Some(PlotPoint::value(xv, f(xv, a.mean?)?)))
        .collect();
    SeriesData {
        name: label.to_string(),
        kind: Kind::Theory,
        series_value: None,
        points,
        band: None,
    }
}

fn recorded(d: &SweepData, curve: &str, label: &str) -> Option<SeriesData> {
    let report = d.report.as_ref()?;
    let c = report["series"]
        .as_array()?
        .iter()
        .find(|c| c["name"] == curve)?;
    let points = c["points"]
        .as_array()?
        .iter()
        .filter_map(|p| Some(PlotPoint::value(p[0].as_f64()?, p[1].as_f64()?)))
        .collect();
    let band = serde_json::from_value(c["band"].clone()).ok();
    Some(SeriesData {
        name: label.to_string(),
        kind: Kind::Recorded,
        series_value: None,
        points,
        band,
    })
}

fn level_lines(
    layers: &[Layer],
    study: &StudyData,
    range: Option<(f64, f64)>,
    out: &mut Vec<SeriesData>,
) {
    let Some((lo, hi)) = range else { return };
    for layer in layers {
        let Layer::Level {
            sweep,
            at,
            metric,
            label,
        } = layer
        else {
            continue;
        };
        let level = study
            .get(sweep)
            .and_then(|d| d.points.iter().find(|p| same(p.point.get(at.0), at.1)))
            .and_then(|p| p.metrics.get(*metric))
            .and_then(|a| a.mean);
        if let Some(y) = level {
            out.push(SeriesData {
                name: label.to_string(),
                kind: Kind::Level,
                series_value: None,
                points: vec![PlotPoint::value(lo, y), PlotPoint::value(hi, y)],
                band: None,
            });
        }
    }
}
