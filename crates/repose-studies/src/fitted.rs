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
    /// weighted as [`weigh`] says.
    pub fn groups(&self, d: &SweepData) -> Vec<(Option<Value>, Vec<Datum>)> {
        let mut out: Vec<(Option<Value>, Vec<Measured>)> = Vec::new();
        for p in d.points.iter().filter(|p| (self.keep)(p)) {
            let Some(a) = p.metrics.get(self.y).copied().filter(|a| a.n > 0) else {
                continue;
            };
            let (Some(x), Some(y)) = (x_value(&p.point, self.x, self.quantities), a.mean) else {
                continue;
            };
            let value = self.by.map(|s| series_value(&p.point, s, self.quantities));
            let datum = Datum { x, y, sigma: None };
            match out.iter_mut().find(|(v, _)| *v == value) {
                Some((_, data)) => data.push((datum, a)),
                None => out.push((value, vec![(datum, a)])),
            }
        }
        let key = |v: &Option<Value>| v.as_ref().and_then(Value::as_f64).unwrap_or(0.0);
        out.sort_by(|a, b| key(&a.0).total_cmp(&key(&b.0)));
        out.into_iter()
            .map(|(value, mut data)| {
                data.sort_by(|a, b| a.0.x.total_cmp(&b.0.x));
                (value, weigh(&data))
            })
            .collect()
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

/// A point's mean before it is weighed, with the samples behind it.
type Measured = (Datum, Aggregate);

/// Weights only where every point has one: a fit of some weighted and
/// some unweighted points would weigh them on different scales.
pub fn weights_all_or_none(data: &mut [Datum]) {
    if data.iter().any(|d| d.sigma.is_none()) {
        data.iter_mut().for_each(|d| d.sigma = None);
    }
}

/// The samples every point of a group needs before each point's own
/// standard error weighs it. A standard error of n samples rests on n − 1
/// degrees of freedom: of two samples it can come out near zero by chance
/// (two seeds that happen to agree) and outweigh the rest of the fit by
/// orders of magnitude, so one more sample could flip a fit's constants.
/// At ten the variance's own relative error is under half.
pub const OWN_ERROR_SAMPLES: i64 = 10;

/// The weights of a group's means. Where every point rests on at least
/// [`OWN_ERROR_SAMPLES`] samples and has a positive standard error, each
/// is weighed by its own. Otherwise the points share the group's pooled
/// variance s², so a mean of n samples has the error s/√n, and as the fit
/// reads errors as relative weights, 1/√n is that weight.
pub fn weigh(data: &[Measured]) -> Vec<Datum> {
    let positive = |s: Option<f64>| s.filter(|s| *s > 0.0 && s.is_finite());
    let own = data
        .iter()
        .all(|(_, a)| a.n >= OWN_ERROR_SAMPLES && positive(a.sem).is_some());
    data.iter()
        .map(|(d, a)| Datum {
            sigma: if own {
                positive(a.sem)
            } else {
                Some(1.0 / (a.n as f64).sqrt())
            },
            ..*d
        })
        .collect()
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::tests::LINE;

    fn point(x: f64, y: f64, n: i64, sem: f64) -> (Datum, Aggregate) {
        let datum = Datum { x, y, sigma: None };
        let a = Aggregate {
            n,
            mean: Some(y),
            sd: Some(sem * (n as f64).sqrt()),
            sem: Some(sem),
        };
        (datum, a)
    }

    #[test]
    fn few_samples_a_point_share_the_pooled_variance() {
        // Two samples a point, and two seeds of the third point happened to
        // agree: its own standard error would pin the line through it.
        let data = [
            point(0.0, 0.0, 2, 0.5),
            point(1.0, 1.0, 2, 0.5),
            point(2.0, 3.0, 2, 1e-6),
            point(3.0, 3.0, 2, 0.5),
        ];
        let weighed = weigh(&data);
        assert!(weighed.iter().all(|d| d.sigma == Some(1.0 / 2f64.sqrt())));
        let pooled = fit(&LINE, &weighed, &[0.0, 1.0]).unwrap();
        let plain: Vec<Datum> = data.iter().map(|(d, _)| *d).collect();
        let unweighted = fit(&LINE, &plain, &[0.0, 1.0]).unwrap();
        for (p, u) in pooled.params.iter().zip(&unweighted.params) {
            assert!((p.value - u.value).abs() < 1e-9, "{p:?} {u:?}");
        }
        let mut own = plain.clone();
        own.iter_mut()
            .zip(&data)
            .for_each(|(d, (_, a))| d.sigma = a.sem);
        let pinned = fit(&LINE, &own, &[0.0, 1.0]).unwrap();
        let at_two = |f: &Fit| f.params[0].value + 2.0 * f.params[1].value;
        assert!((at_two(&pinned) - 3.0).abs() < 1e-3, "{pinned:?}");
        assert!((at_two(&pooled) - 3.0).abs() > 0.3, "{pooled:?}");
    }

    #[test]
    fn unequal_counts_weigh_by_the_count_and_many_samples_by_their_own_error() {
        let few = weigh(&[point(0.0, 0.0, 1, 0.0), point(1.0, 1.0, 4, 0.2)]);
        assert_eq!(few[0].sigma, Some(1.0));
        assert_eq!(few[1].sigma, Some(0.5));
        let many = weigh(&[point(0.0, 0.0, 10, 0.3), point(1.0, 1.0, 20, 0.1)]);
        assert_eq!(many[0].sigma, Some(0.3));
        assert_eq!(many[1].sigma, Some(0.1));
        // One point short of the count puts the whole group on the pool.
        let mixed = weigh(&[point(0.0, 0.0, 9, 0.3), point(1.0, 1.0, 20, 0.1)]);
        assert_eq!(mixed[0].sigma, Some(1.0 / 3.0));
    }
}
