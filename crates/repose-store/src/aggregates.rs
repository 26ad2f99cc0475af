//! Running aggregates per point (`point_stats`, `point_metrics`): made
//! with a sweep from what is stored already, and added to in the
//! transaction that stores each new result, for every sweep and point
//! whose job has that sample. Reading a sweep's points then costs its
//! number of points, not of samples; [`Store::points_recomputed`] gives the
//! same numbers from the samples themselves, to check them against.

use crate::{parse_point, Aggregate, Point, Result, Store};
use sqlx::Row;
use std::collections::{BTreeMap, HashMap};

/// Outcome counted as a failure: anything but `completed`.
const FAILED: &str = "CAST(SUM(CASE WHEN r.sample_hash IS NULL OR r.outcome = 'completed' THEN 0 ELSE 1 END) AS BIGINT)";

impl Store {
    /// Makes a new sweep's point rows from the results already stored.
    pub(crate) async fn aggregate_sweep(
        &self,
        tx: &mut sqlx::AnyConnection,
        sweep_id: &str,
    ) -> Result<()> {
        sqlx::query(&self.sql(&format!(
            "INSERT INTO point_stats (sweep_id, point, first_seq, samples, failures) \
             SELECT j.sweep_id, j.point, MIN(j.seq), COUNT(r.sample_hash), {FAILED} \
             FROM jobs j LEFT JOIN results r ON r.sample_hash = j.sample_hash \
             WHERE j.sweep_id = $1 GROUP BY j.sweep_id, j.point"
        )))
        .bind(sweep_id)
        .execute(&mut *tx)
        .await?;
        sqlx::query(&self.sql(
            "INSERT INTO point_metrics (sweep_id, point, metric, n, s, q) \
             SELECT j.sweep_id, j.point, m.metric, COUNT(m.value), SUM(m.value), SUM(m.value * m.value) \
             FROM jobs j JOIN metric_values m ON m.sample_hash = j.sample_hash \
             WHERE j.sweep_id = $1 GROUP BY j.sweep_id, j.point, m.metric",
        ))
        .bind(sweep_id)
        .execute(&mut *tx)
        .await?;
        Ok(())
    }

    /// Rebuilds one point's aggregates from its samples.
    pub(crate) async fn aggregate_point(
        &self,
        conn: &mut sqlx::AnyConnection,
        sweep_id: &str,
        point: &str,
    ) -> Result<()> {
        sqlx::query(&self.sql(&format!(
            "UPDATE point_stats SET \
             samples = (SELECT COUNT(*) FROM jobs j JOIN results r ON r.sample_hash = j.sample_hash \
                        WHERE j.sweep_id = $1 AND j.point = $2), \
             failures = (SELECT COALESCE({FAILED}, 0) FROM jobs j JOIN results r ON r.sample_hash = j.sample_hash \
                        WHERE j.sweep_id = $1 AND j.point = $2) \
             WHERE sweep_id = $1 AND point = $2"
        )))
        .bind(sweep_id)
        .bind(point)
        .execute(&mut *conn)
        .await?;
        sqlx::query(&self.sql("DELETE FROM point_metrics WHERE sweep_id = $1 AND point = $2"))
            .bind(sweep_id)
            .bind(point)
            .execute(&mut *conn)
            .await?;
        sqlx::query(&self.sql(
            "INSERT INTO point_metrics (sweep_id, point, metric, n, s, q) \
             SELECT j.sweep_id, j.point, m.metric, COUNT(m.value), SUM(m.value), SUM(m.value * m.value) \
             FROM jobs j JOIN metric_values m ON m.sample_hash = j.sample_hash \
             WHERE j.sweep_id = $1 AND j.point = $2 GROUP BY j.sweep_id, j.point, m.metric",
        ))
        .bind(sweep_id)
        .bind(point)
        .execute(&mut *conn)
        .await?;
        Ok(())
    }

    /// Builds a sweep's running aggregates afresh from its samples (after
    /// rows were loaded around the queue, e.g. by a benchmark or a restore).
    pub async fn rebuild_aggregates(&self, sweep_id: &str) -> Result<()> {
        let mut tx = self.pool.begin().await?;
        for table in ["point_metrics", "point_stats"] {
            sqlx::query(&self.sql(&format!("DELETE FROM {table} WHERE sweep_id = $1")))
                .bind(sweep_id)
                .execute(&mut *tx)
                .await?;
        }
        self.aggregate_sweep(&mut tx, sweep_id).await?;
        tx.commit().await?;
        Ok(())
    }

    /// Adds a newly stored result to the points of every job that has its sample.
    pub(crate) async fn aggregate_result(
        &self,
        tx: &mut sqlx::AnyConnection,
        sample_hash: &str,
        failed: bool,
        metrics: &BTreeMap<String, f64>,
    ) -> Result<()> {
        sqlx::query(&self.sql(
            "UPDATE point_stats SET samples = samples + 1, failures = failures + $1 \
             WHERE (sweep_id, point) IN (SELECT sweep_id, point FROM jobs WHERE sample_hash = $2)",
        ))
        .bind(i64::from(failed))
        .bind(sample_hash)
        .execute(&mut *tx)
        .await?;
        for (metric, value) in metrics.iter().filter(|(_, v)| v.is_finite()) {
            sqlx::query(&self.sql(
                "INSERT INTO point_metrics (sweep_id, point, metric, n, s, q) \
                 SELECT DISTINCT sweep_id, point, $1, 1, $2, $3 FROM jobs WHERE sample_hash = $4 \
                 ON CONFLICT (sweep_id, point, metric) DO UPDATE SET n = point_metrics.n + 1, \
                 s = point_metrics.s + excluded.s, q = point_metrics.q + excluded.q",
            ))
            .bind(metric)
            .bind(*value)
            .bind(value * value)
            .bind(sample_hash)
            .execute(&mut *tx)
            .await?;
        }
        Ok(())
    }

    /// Per-point statistics of every metric, from the running aggregates.
    pub async fn points(&self, sweep_id: &str) -> Result<Vec<Point>> {
        let rows = sqlx::query(&self.sql(
            "SELECT point, samples, failures FROM point_stats \
             WHERE sweep_id = $1 AND samples > 0 ORDER BY first_seq",
        ))
        .bind(sweep_id)
        .fetch_all(&self.pool)
        .await?;
        let sums = sqlx::query(
            &self.sql("SELECT point, metric, n, s, q FROM point_metrics WHERE sweep_id = $1"),
        )
        .bind(sweep_id)
        .fetch_all(&self.pool)
        .await?;
        assemble(rows, sums)
    }

    /// The same statistics computed from the samples (what the running
    /// aggregates must equal).
    pub async fn points_recomputed(&self, sweep_id: &str) -> Result<Vec<Point>> {
        let rows = sqlx::query(&self.sql(&format!(
            "SELECT j.point, COUNT(*) AS samples, {FAILED} AS failures, MIN(j.seq) AS first \
             FROM jobs j JOIN results r ON r.sample_hash = j.sample_hash \
             WHERE j.sweep_id = $1 GROUP BY j.point ORDER BY first"
        )))
        .bind(sweep_id)
        .fetch_all(&self.pool)
        .await?;
        let sums = sqlx::query(&self.sql(
            "SELECT j.point, m.metric, COUNT(m.value) AS n, SUM(m.value) AS s, SUM(m.value * m.value) AS q \
             FROM jobs j JOIN metric_values m ON m.sample_hash = j.sample_hash \
             WHERE j.sweep_id = $1 GROUP BY j.point, m.metric",
        ))
        .bind(sweep_id)
        .fetch_all(&self.pool)
        .await?;
        assemble(rows, sums)
    }
}

/// Points from rows `(point, samples, failures)` and `(point, metric, n, s, q)`.
fn assemble(rows: Vec<sqlx::any::AnyRow>, sums: Vec<sqlx::any::AnyRow>) -> Result<Vec<Point>> {
    let mut metrics: HashMap<String, BTreeMap<String, Aggregate>> = HashMap::new();
    for r in sums {
        let agg = Aggregate::from_sums(r.get("n"), r.get("s"), r.get("q"));
        metrics
            .entry(r.get("point"))
            .or_default()
            .insert(r.get("metric"), agg);
    }
    rows.into_iter()
        .map(|r| {
            let text: String = r.get("point");
            Ok(Point {
                point: parse_point(&text)?,
                samples: r.get("samples"),
                failures: r.get("failures"),
                metrics: metrics.remove(&text).unwrap_or_default(),
            })
        })
        .collect()
}
