//! CSV exports of samples and points: one header line, axis values in
//! `axis:<key>` columns, one column per metric (or per statistic of a
//! metric), empty cells for missing values.

use crate::{Point, Sample};
use serde_json::{Map, Value};
use std::collections::BTreeSet;

/// The axes any of the points varies, sorted.
fn axes<'a>(points: impl Iterator<Item = &'a Map<String, Value>>) -> Vec<String> {
    let set: BTreeSet<String> = points.flat_map(|p| p.keys().cloned()).collect();
    set.into_iter().collect()
}

fn axis_cells(point: &Map<String, Value>, keys: &[String]) -> Vec<String> {
    keys.iter()
        .map(|k| match point.get(k) {
            Some(Value::String(s)) => s.clone(),
            Some(v) => v.to_string(),
            None => String::new(),
        })
        .collect()
}

fn cell(v: Option<f64>) -> String {
    v.map(|x| x.to_string()).unwrap_or_default()
}

/// `metrics` first, in their order, then any other metric a row carries.
fn metric_columns<'a>(
    declared: &[String],
    present: impl Iterator<Item = &'a String>,
) -> Vec<String> {
    let mut out: Vec<String> = declared.to_vec();
    let extra: BTreeSet<&String> = present.filter(|m| !declared.contains(m)).collect();
    out.extend(extra.into_iter().cloned());
    out
}

fn write(rows: Vec<Vec<String>>) -> String {
    let mut w = csv::Writer::from_writer(Vec::new());
    for row in rows {
        // Writing to memory cannot fail.
        let _ = w.write_record(&row);
    }
    String::from_utf8(w.into_inner().unwrap_or_default()).unwrap_or_default()
}

/// One row per sample; `metrics` names the columns to lead with (the
/// protocol's declared metrics).
pub fn samples_csv(samples: &[Sample], metrics: &[String]) -> String {
    let keys = axes(samples.iter().map(|s| &s.point));
    let metrics = metric_columns(metrics, samples.iter().flat_map(|s| s.metrics.keys()));
    let mut header: Vec<String> = keys.iter().map(|k| format!("axis:{k}")).collect();
    header.extend(["sample", "seed", "outcome", "reason"].map(String::from));
    header.extend(metrics.iter().cloned());
    header.extend(
        [
            "grains_initial",
            "grains_final",
            "grains_lost",
            "iterations",
            "simulated_time",
            "wall_time",
            "particle_steps",
            "engine",
            "sample_hash",
        ]
        .map(String::from),
    );
    let mut rows = vec![header];
    for s in samples {
        let mut row = axis_cells(&s.point, &keys);
        row.extend([
            s.sample.to_string(),
            s.seed.to_string(),
            s.outcome.clone(),
            s.reason.clone().unwrap_or_default(),
        ]);
        row.extend(metrics.iter().map(|m| cell(s.metrics.get(m).copied())));
        let c = &s.counts;
        row.extend([
            c.grains_initial.to_string(),
            c.grains_final.to_string(),
            c.grains_lost.to_string(),
            c.iterations.to_string(),
            c.simulated_time.to_string(),
            c.wall_time.to_string(),
            c.particle_steps.to_string(),
            s.engine.clone(),
            s.sample_hash.clone(),
        ]);
        rows.push(row);
    }
    write(rows)
}

/// One row per point: n, mean, sd and sem of every metric.
pub fn points_csv(points: &[Point], metrics: &[String]) -> String {
    let keys = axes(points.iter().map(|p| &p.point));
    let metrics = metric_columns(metrics, points.iter().flat_map(|p| p.metrics.keys()));
    let mut header: Vec<String> = keys.iter().map(|k| format!("axis:{k}")).collect();
    header.push("samples".into());
    header.push("failures".into());
    for m in &metrics {
        for stat in ["n", "mean", "sd", "sem"] {
            header.push(format!("{m}_{stat}"));
        }
    }
    let mut rows = vec![header];
    for p in points {
        let mut row = axis_cells(&p.point, &keys);
        row.push(p.samples.to_string());
        row.push(p.failures.to_string());
        for m in &metrics {
            let a = p.metrics.get(m).copied().unwrap_or(crate::Aggregate::EMPTY);
            row.extend([a.n.to_string(), cell(a.mean), cell(a.sd), cell(a.sem)]);
        }
        rows.push(row);
    }
    write(rows)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Aggregate;
    use std::collections::BTreeMap;

    #[test]
    fn cells_with_commas_and_quotes_are_quoted_and_read_back() {
        let sample = Sample {
            job_id: "j".into(),
            sample_hash: "h".into(),
            point: serde_json::json!({"contact.mu": 0.2})
                .as_object()
                .cloned()
                .unwrap_or_default(),
            sample: 0,
            seed: 1,
            outcome: "failed".into(),
            reason: Some("flow: grain 3 \"ran\", far".into()),
            metrics: BTreeMap::from([("theta_x".to_string(), 1.5)]),
            counts: crate::RunCounts {
                grains_initial: 1,
                grains_final: 1,
                grains_lost: 0,
                iterations: 10,
                simulated_time: 0.1,
                wall_time: 0.01,
                particle_steps: 10,
            },
            engine: "e".into(),
        };
        let text = samples_csv(&[sample], &["theta_r".to_string()]);
        let mut r = csv::Reader::from_reader(text.as_bytes());
        let header: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
        let row = r.records().next().unwrap().unwrap();
        let get = |k: &str| row[header.iter().position(|h| h == k).unwrap()].to_string();
        assert_eq!(get("reason"), "flow: grain 3 \"ran\", far");
        assert_eq!(get("theta_r"), "");
        assert_eq!(get("theta_x"), "1.5");
        assert_eq!(get("axis:contact.mu"), "0.2");
    }

    #[test]
    fn points_have_four_statistics_per_metric() {
        let p = Point {
            point: Map::new(),
            samples: 3,
            failures: 1,
            metrics: BTreeMap::from([(
                "theta_r".to_string(),
                Aggregate::from_sums(2, Some(4.0), Some(10.0)),
            )]),
        };
        let text = points_csv(&[p], &["theta_r".to_string()]);
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(
            lines[0],
            "samples,failures,theta_r_n,theta_r_mean,theta_r_sd,theta_r_sem"
        );
        assert!(lines[1].starts_with("3,1,2,2,1.414"), "{}", lines[1]);
    }
}
