//! The stored data a figure or a comparison is computed from: for each
//! study sweep, its points, its samples and (where a figure draws a
//! recorded curve) the report of its first sample.

use crate::quantity::{x_value, Quantity};
use repose_store::{Aggregate, Point, Sample};
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::collections::BTreeMap;

/// What one sweep has stored.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct SweepData {
    pub id: String,
    pub points: Vec<Point>,
    pub samples: Vec<Sample>,
    /// The report of the first sample, when a figure needs its curves.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub report: Option<Value>,
}

/// The data of a paper's sweeps, by study key (`fig347`).
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct StudyData {
    pub sweeps: BTreeMap<String, SweepData>,
}

impl StudyData {
    pub fn get(&self, key: &str) -> Option<&SweepData> {
        self.sweeps.get(key)
    }
}

/// Whether an axis value equals `want` (numbers compared loosely).
pub fn same(v: Option<&Value>, want: f64) -> bool {
    v.and_then(Value::as_f64)
        .is_some_and(|x| (x - want).abs() <= 1e-9 * want.abs().max(1.0))
}

impl SweepData {
    /// The point whose axis values match `want`.
    pub fn at(&self, want: &[(&str, f64)]) -> Option<&Point> {
        self.points
            .iter()
            .find(|p| want.iter().all(|(k, v)| same(p.point.get(*k), *v)))
    }

    /// A metric's statistics at the point matching `want`, if measured there.
    pub fn stat(&self, want: &[(&str, f64)], metric: &str) -> Option<Aggregate> {
        self.at(want)?
            .metrics
            .get(metric)
            .copied()
            .filter(|a| a.n > 0)
    }

    /// `(x, statistics)` along one axis (or a computed quantity),
    /// optionally at one value of another, sorted by x.
    pub fn along(
        &self,
        x: &str,
        fixed: Option<(&str, f64)>,
        metric: &str,
        quantities: &[Quantity],
    ) -> Vec<(f64, Aggregate)> {
        let mut v: Vec<(f64, Aggregate)> = self
            .points
            .iter()
            .filter(|p| fixed.is_none_or(|(k, val)| same(p.point.get(k), val)))
            .filter_map(|p| {
                let a = p.metrics.get(metric).copied().filter(|a| a.n > 0)?;
                Some((x_value(&p.point, x, quantities)?, a))
            })
            .collect();
        v.sort_by(|a, b| a.0.total_cmp(&b.0));
        v
    }

    /// Samples whose run ended without a result.
    pub fn failures(&self) -> i64 {
        self.points.iter().map(|p| p.failures).sum()
    }
}
