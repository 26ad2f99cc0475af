//! Reading a study back: sweeps with their progress, samples with their
//! metrics, and per-point statistics computed in the database from counts,
//! sums and sums of squares of the metric rows.

use crate::{
    parse_point, Aggregate, Cost, Point, Progress, Result, RunCounts, RunningJob, Sample, Store,
    SweepInfo,
};
use serde::{Deserialize, Serialize};
use sqlx::Row;
use std::collections::{BTreeMap, HashMap};

impl Store {
    /// Job counts by state for one sweep.
    pub async fn progress(&self, sweep_id: &str) -> Result<Progress> {
        Ok(self
            .progress_by_sweep(Some(sweep_id))
            .await?
            .remove(sweep_id)
            .unwrap_or_default())
    }

    /// Number of sweeps (also a cheap check that the database answers).
    pub async fn sweeps_count(&self) -> Result<i64> {
        Ok(sqlx::query_scalar("SELECT COUNT(*) FROM sweeps")
            .fetch_one(&self.pool)
            .await?)
    }

    /// Number of stored results with this hash (0 or 1 by construction).
    pub async fn result_count(&self, sample_hash: &str) -> Result<i64> {
        let r = sqlx::query(&self.sql("SELECT COUNT(*) AS n FROM results WHERE sample_hash = $1"))
            .bind(sample_hash)
            .fetch_one(&self.pool)
            .await?;
        Ok(r.get("n"))
    }

    /// All sweeps, newest first, with progress.
    pub async fn sweeps(&self) -> Result<Vec<SweepInfo>> {
        self.sweep_infos(None).await
    }

    /// A sweep's state and spec as submitted, without its progress (for
    /// the worker's top-up after every result).
    pub async fn sweep_spec(&self, id: &str) -> Result<Option<(String, serde_json::Value)>> {
        let row = sqlx::query(&self.sql("SELECT state, spec FROM sweeps WHERE id = $1"))
            .bind(id)
            .fetch_optional(&self.pool)
            .await?;
        row.map(|r| {
            Ok((
                r.get("state"),
                serde_json::from_str(&r.get::<String, _>("spec"))?,
            ))
        })
        .transpose()
    }

    /// One sweep with its progress and ETA, or None.
    pub async fn sweep(&self, id: &str) -> Result<Option<SweepInfo>> {
        Ok(self.sweep_infos(Some(id)).await?.pop())
    }

    /// Every sweep, or only the one named, with its progress, cost, ETA
    /// and running jobs: one query for each of these whatever the number
    /// of sweeps.
    async fn sweep_infos(&self, only: Option<&str>) -> Result<Vec<SweepInfo>> {
        let rows = self
            .fetch(
                                    "SELECT id, name, protocol, spec, priority, state, created_at, study FROM sweeps {only} \
                     ORDER BY created_at DESC, id",
                "WHERE id = $1",
                only,
            )
            .await?;
        let mut progress = self.progress_by_sweep(only).await?;
        let mut costs = self.cost_by_sweep(only).await?;
        let mut running = self.running_by_sweep(only).await?;
        rows.into_iter()
            .map(|row| {
                let id: String = row.get("id");
                let progress = progress.remove(&id).unwrap_or_default();
                let cost = costs.remove(&id).unwrap_or_default();
                Ok(SweepInfo {
                    eta_seconds: eta(&progress, &cost),
                    running: running.remove(&id).unwrap_or_default(),
                    name: row.get("name"),
                    protocol: row.get("protocol"),
                    study: row.get("study"),
                    priority: row.get("priority"),
                    state: row.get("state"),
                    created_at: row.get("created_at"),
                    spec: serde_json::from_str(&row.get::<String, _>("spec"))?,
                    id,
                    progress,
                    cost,
                })
            })
            .collect()
    }

    /// Runs `text` over every sweep, or with `{only}` replaced by `clause`
    /// (whose one parameter is the sweep id) over the one named.
    async fn fetch(
        &self,
        text: &str,
        clause: &str,
        only: Option<&str>,
    ) -> Result<Vec<sqlx::any::AnyRow>> {
        let sql = self.sql(&text.replace("{only}", if only.is_some() { clause } else { "" }));
        let query = sqlx::query(&sql);
        let query = match only {
            Some(id) => query.bind(id.to_string()),
            None => query,
        };
        Ok(query.fetch_all(&self.pool).await?)
    }

    /// Job counts by state, by sweep.
    async fn progress_by_sweep(&self, only: Option<&str>) -> Result<HashMap<String, Progress>> {
        let rows = self
            .fetch(
                "SELECT sweep_id, state, COUNT(*) AS n FROM jobs {only} GROUP BY sweep_id, state",
                "WHERE sweep_id = $1",
                only,
            )
            .await?;
        let mut out: HashMap<String, Progress> = HashMap::new();
        for r in rows {
            let p = out.entry(r.get("sweep_id")).or_default();
            let n: i64 = r.get("n");
            match r.get::<String, _>("state").as_str() {
                "queued" => p.queued = n,
                "running" => p.running = n,
                "done" => p.done = n,
                "failed" => p.failed = n,
                "cancelled" => p.cancelled = n,
                _ => {}
            }
        }
        Ok(out)
    }

    /// What the finished samples took, by sweep.
    async fn cost_by_sweep(&self, only: Option<&str>) -> Result<HashMap<String, Cost>> {
        let rows = self
            .fetch(
                "SELECT j.sweep_id, COUNT(*) AS n, SUM(r.wall_time) AS wall, \
                     CAST(SUM(r.particle_steps) AS BIGINT) AS steps \
                     FROM jobs j JOIN results r ON r.sample_hash = j.sample_hash \
                     WHERE j.state = 'done' {only} GROUP BY j.sweep_id",
                "AND j.sweep_id = $1",
                only,
            )
            .await?;
        Ok(rows
            .into_iter()
            .map(|r| {
                let cost = Cost {
                    samples: r.get("n"),
                    wall_time: r.get::<Option<f64>, _>("wall").unwrap_or(0.0),
                    particle_steps: r.get::<Option<i64>, _>("steps").unwrap_or(0),
                };
                (r.get("sweep_id"), cost)
            })
            .collect())
    }

    /// The running jobs that have saved a checkpoint, oldest job first, by sweep.
    async fn running_by_sweep(
        &self,
        only: Option<&str>,
    ) -> Result<HashMap<String, Vec<RunningJob>>> {
        let rows = self
            .fetch(
                "SELECT j.sweep_id, c.job_id, c.sim_time, c.iteration, c.saved_at \
                     FROM checkpoints c JOIN jobs j ON j.id = c.job_id \
                     WHERE j.state = 'running' {only} ORDER BY j.seq",
                "AND j.sweep_id = $1",
                only,
            )
            .await?;
        let mut out: HashMap<String, Vec<RunningJob>> = HashMap::new();
        for r in rows {
            out.entry(r.get("sweep_id")).or_default().push(RunningJob {
                job_id: r.get("job_id"),
                sim_time: r.get("sim_time"),
                iteration: r.get("iteration"),
                saved_at: r.get("saved_at"),
            });
        }
        Ok(out)
    }

    /// The newest sweep queued for a study sweep (`paper/sweep`) that was not cancelled.
    pub async fn latest_for_study(&self, study: &str) -> Result<Option<String>> {
        Ok(sqlx::query_scalar(&self.sql(
            "SELECT id FROM sweeps WHERE study = $1 AND state <> 'cancelled' ORDER BY created_at DESC, id LIMIT 1",
        ))
        .bind(study)
        .fetch_optional(&self.pool)
        .await?)
    }

    /// The metrics of every stored sample of a sweep, by sample hash.
    async fn metric_rows(&self, sweep_id: &str) -> Result<HashMap<String, BTreeMap<String, f64>>> {
        let rows = sqlx::query(&self.sql(
            "SELECT m.sample_hash, m.metric, m.value FROM jobs j JOIN metric_values m ON m.sample_hash = j.sample_hash \
             WHERE j.sweep_id = $1",
        ))
        .bind(sweep_id)
        .fetch_all(&self.pool)
        .await?;
        let mut out: HashMap<String, BTreeMap<String, f64>> = HashMap::new();
        for r in rows {
            out.entry(r.get("sample_hash"))
                .or_default()
                .insert(r.get("metric"), r.get("value"));
        }
        Ok(out)
    }

    /// Every stored sample of a sweep, in job order.
    pub async fn samples(&self, sweep_id: &str) -> Result<Vec<Sample>> {
        let rows = sqlx::query(&self.sql(
            "SELECT j.id AS job_id, j.sample_hash, j.point, j.sample, j.seed, r.outcome, r.reason, r.grains_initial, \
             r.grains_final, r.grains_lost, r.iterations, r.simulated_time, r.wall_time, r.particle_steps, r.engine \
             FROM jobs j JOIN results r ON r.sample_hash = j.sample_hash WHERE j.sweep_id = $1 ORDER BY j.seq",
        ))
        .bind(sweep_id)
        .fetch_all(&self.pool)
        .await?;
        let mut metrics = self.metric_rows(sweep_id).await?;
        rows.into_iter()
            .map(|r| {
                let hash: String = r.get("sample_hash");
                Ok(Sample {
                    job_id: r.get("job_id"),
                    metrics: metrics.remove(&hash).unwrap_or_default(),
                    sample_hash: hash,
                    point: parse_point(&r.get::<String, _>("point"))?,
                    sample: r.get("sample"),
                    seed: r.get("seed"),
                    outcome: r.get("outcome"),
                    reason: r.get("reason"),
                    counts: RunCounts {
                        grains_initial: r.get("grains_initial"),
                        grains_final: r.get("grains_final"),
                        grains_lost: r.get("grains_lost"),
                        iterations: r.get("iterations"),
                        simulated_time: r.get("simulated_time"),
                        wall_time: r.get("wall_time"),
                        particle_steps: r.get("particle_steps"),
                    },
                    engine: r.get("engine"),
                })
            })
            .collect()
    }

    /// The full run report of one sample, as stored.
    pub async fn report(&self, sample_hash: &str) -> Result<Option<serde_json::Value>> {
        let text: Option<String> = sqlx::query_scalar(
            &self.sql("SELECT report FROM result_reports WHERE sample_hash = $1"),
        )
        .bind(sample_hash)
        .fetch_optional(&self.pool)
        .await?;
        Ok(match text {
            Some(t) => Some(serde_json::from_str(&t)?),
            None => None,
        })
    }
}

/// One plotted point of a figure: x, the series it belongs to, and the
/// statistics of the y metric there.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
pub struct SeriesPoint {
    #[schema(value_type = Object)]
    pub x: serde_json::Value,
    #[schema(value_type = Option<Object>)]
    pub series: Option<serde_json::Value>,
    pub n: i64,
    pub mean: Option<f64>,
    pub sd: Option<f64>,
    pub sem: Option<f64>,
    /// Samples at this point that ended without a result.
    pub failures: i64,
}

/// Why a series cannot be drawn from a sweep.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SeriesError {
    #[error("no sample of the sweep measured `{0}`")]
    Metric(String),
    #[error("the sweep does not vary `{0}`")]
    Axis(String),
}

/// Picks `x` (and optionally a `series` key) from the points' axis values
/// and the statistics of metric `y`, sorted by series then x.
pub fn series(
    points: &[Point],
    x: &str,
    series: Option<&str>,
    y: &str,
) -> std::result::Result<Vec<SeriesPoint>, SeriesError> {
    if !points.iter().any(|p| p.metrics.contains_key(y)) {
        return Err(SeriesError::Metric(y.to_string()));
    }
    for key in std::iter::once(x).chain(series) {
        if !points.iter().any(|p| p.point.contains_key(key)) {
            return Err(SeriesError::Axis(key.to_string()));
        }
    }
    let mut out: Vec<SeriesPoint> = points
        .iter()
        .map(|p| {
            let agg = p.metrics.get(y).copied().unwrap_or(Aggregate::EMPTY);
            SeriesPoint {
                x: p.point.get(x).cloned().unwrap_or(serde_json::Value::Null),
                series: series.map(|s| p.point.get(s).cloned().unwrap_or(serde_json::Value::Null)),
                n: agg.n,
                mean: agg.mean,
                sd: agg.sd,
                sem: agg.sem,
                failures: p.failures,
            }
        })
        .collect();
    let key = |v: &serde_json::Value| v.as_f64().unwrap_or(f64::NAN);
    out.sort_by(|a, b| {
        let sa = a.series.as_ref().map(key).unwrap_or(0.0);
        let sb = b.series.as_ref().map(key).unwrap_or(0.0);
        sa.total_cmp(&sb).then(key(&a.x).total_cmp(&key(&b.x)))
    });
    Ok(out)
}

/// Seconds until a sweep's queued and running jobs are done, from the mean
/// wall time of its finished samples and the number running now: zero when
/// nothing is left, unknown while nothing runs or nothing has finished.
fn eta(progress: &Progress, cost: &Cost) -> Option<f64> {
    let left = progress.queued + progress.running;
    if left == 0 {
        return Some(0.0);
    }
    let mean_wall = (cost.samples > 0).then(|| cost.wall_time / cost.samples as f64)?;
    (progress.running > 0).then(|| mean_wall * left as f64 / progress.running as f64)
}
