//! CSV exports of samples and points (one header line, comma-separated,
//! empty cells for missing values, axis values in `axis:<key>` columns).

use crate::{Point, Sample, METRICS};
use std::collections::BTreeSet;
use std::fmt::Write;

fn cell(v: Option<f64>) -> String {
    v.map(|x| format!("{x}")).unwrap_or_default()
}

fn quote(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

fn axes<'a>(
    points: impl Iterator<Item = &'a serde_json::Map<String, serde_json::Value>>,
) -> Vec<String> {
    let set: BTreeSet<String> = points.flat_map(|p| p.keys().cloned()).collect();
    set.into_iter().collect()
}

fn axis_cells(point: &serde_json::Map<String, serde_json::Value>, keys: &[String]) -> String {
    keys.iter()
        .map(|k| match point.get(k) {
            Some(serde_json::Value::String(s)) => quote(s),
            Some(v) => quote(&v.to_string()),
            None => String::new(),
        })
        .collect::<Vec<_>>()
        .join(",")
}

/// One row per sample.
pub fn samples_csv(samples: &[Sample]) -> String {
    let keys = axes(samples.iter().map(|s| &s.point));
    let mut out = String::new();
    let mut header: Vec<String> = keys.iter().map(|k| format!("axis:{k}")).collect();
    header.extend(
        [
            "sample",
            "seed",
            "outcome",
            "reason",
            "theta_r",
            "theta_r_line",
            "theta_r_endpoints",
            "theta_t",
            "theta_ms_mean",
            "theta_ms_sd",
            "theta_ms_max",
            "grains_initial",
            "grains_final",
            "grains_lost",
            "iterations",
            "simulated_time",
            "wall_time",
            "engine",
            "sample_hash",
        ]
        .map(String::from),
    );
    let _ = writeln!(out, "{}", header.join(","));
    for s in samples {
        let mut row = Vec::new();
        if !keys.is_empty() {
            row.push(axis_cells(&s.point, &keys));
        }
        row.extend([
            s.sample.to_string(),
            s.seed.to_string(),
            s.outcome.clone(),
            quote(s.reason.as_deref().unwrap_or("")),
            cell(s.theta_r),
            cell(s.theta_r_line),
            cell(s.theta_r_endpoints),
            cell(s.theta_t),
            cell(s.theta_ms_mean),
            cell(s.theta_ms_sd),
            cell(s.theta_ms_max),
            s.grains_initial.to_string(),
            s.grains_final.to_string(),
            s.grains_lost.to_string(),
            s.iterations.to_string(),
            s.simulated_time.to_string(),
            s.wall_time.to_string(),
            quote(&s.engine),
            s.sample_hash.clone(),
        ]);
        let _ = writeln!(out, "{}", row.join(","));
    }
    out
}

/// One row per point: n, mean, sd and sem of every metric.
pub fn points_csv(points: &[Point]) -> String {
    let keys = axes(points.iter().map(|p| &p.point));
    let mut header: Vec<String> = keys.iter().map(|k| format!("axis:{k}")).collect();
    header.push("samples".into());
    header.push("failures".into());
    for (m, _) in METRICS {
        for stat in ["n", "mean", "sd", "sem"] {
            header.push(format!("{m}_{stat}"));
        }
    }
    let mut out = String::new();
    let _ = writeln!(out, "{}", header.join(","));
    for p in points {
        let mut row = Vec::new();
        if !keys.is_empty() {
            row.push(axis_cells(&p.point, &keys));
        }
        row.push(p.samples.to_string());
        row.push(p.failures.to_string());
        for (m, _) in METRICS {
            let a = p.metrics[*m];
            row.extend([a.n.to_string(), cell(a.mean), cell(a.sd), cell(a.sem)]);
        }
        let _ = writeln!(out, "{}", row.join(","));
    }
    out
}
