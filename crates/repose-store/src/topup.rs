//! Samples added to a sweep while it runs (`target_sem`): how many jobs
//! each point has and how many are still to run, and adding jobs to one
//! point only if nobody else did since it was counted.

use crate::{now_ms, Backend, NewJob, Result, Store};
use sqlx::Row;

/// The jobs of one point of a sweep.
#[derive(Debug, Clone, PartialEq)]
pub struct PointJobs {
    pub point: serde_json::Map<String, serde_json::Value>,
    /// Every job the point ever had (so the next sample index).
    pub jobs: i64,
    /// Of those, queued or running.
    pub pending: i64,
}

impl Store {
    /// Jobs per point of a sweep, in the sweep's order.
    pub async fn point_jobs(&self, sweep_id: &str) -> Result<Vec<PointJobs>> {
        let rows = sqlx::query(&self.sql(
            "SELECT point, COUNT(*) AS jobs, MIN(seq) AS first, \
             CAST(SUM(CASE WHEN state IN ('queued', 'running') THEN 1 ELSE 0 END) AS BIGINT) AS pending \
             FROM jobs WHERE sweep_id = $1 GROUP BY point ORDER BY first",
        ))
        .bind(sweep_id)
        .fetch_all(&self.pool)
        .await?;
        rows.into_iter()
            .map(|r| {
                Ok(PointJobs {
                    point: crate::parse_point(&r.get::<String, _>("point"))?,
                    jobs: r.get("jobs"),
                    pending: r.get("pending"),
                })
            })
            .collect()
    }

    /// Adds `jobs` (all of one point) to a sweep, if that point still has
    /// `expected` jobs; returns whether it added them. Jobs whose sample
    /// is stored already are added done, and the point's aggregates
    /// rebuilt.
    pub async fn add_jobs(
        &self,
        sweep_id: &str,
        jobs: &[NewJob],
        expected: i64,
        max_attempts: i64,
    ) -> Result<bool> {
        let Some(first) = jobs.first() else {
            return Ok(false);
        };
        let point = serde_json::Value::Object(first.point.clone()).to_string();
        let mut conn = self.pool.acquire().await?;
        let begin = match self.backend {
            Backend::Sqlite => "BEGIN IMMEDIATE",
            Backend::Postgres => "BEGIN",
        };
        sqlx::query(begin).execute(&mut *conn).await?;
        let added = self
            .add_jobs_locked(&mut conn, sweep_id, &point, jobs, expected, max_attempts)
            .await;
        let end = if matches!(added, Ok(true)) {
            "COMMIT"
        } else {
            "ROLLBACK"
        };
        sqlx::query(end).execute(&mut *conn).await?;
        added
    }

    async fn add_jobs_locked(
        &self,
        conn: &mut sqlx::AnyConnection,
        sweep_id: &str,
        point: &str,
        jobs: &[NewJob],
        expected: i64,
        max_attempts: i64,
    ) -> Result<bool> {
        let lock = match self.backend {
            Backend::Sqlite => "SELECT 1 FROM point_stats WHERE sweep_id = $1 AND point = $2",
            Backend::Postgres => {
                "SELECT 1 FROM point_stats WHERE sweep_id = $1 AND point = $2 FOR UPDATE"
            }
        };
        sqlx::query(&self.sql(lock))
            .bind(sweep_id)
            .bind(point)
            .fetch_optional(&mut *conn)
            .await?;
        let row = sqlx::query(&self.sql(
            "SELECT (SELECT COUNT(*) FROM jobs WHERE sweep_id = $1 AND point = $2) AS n, \
             (SELECT MAX(seq) FROM jobs WHERE sweep_id = $1) AS last, \
             s.priority, s.created_at FROM sweeps s WHERE s.id = $1",
        ))
        .bind(sweep_id)
        .bind(point)
        .fetch_optional(&mut *conn)
        .await?;
        let Some(row) = row else { return Ok(false) };
        if row.get::<i64, _>("n") != expected {
            return Ok(false);
        }
        let order = crate::queue::JobOrder {
            sweep_id,
            priority: row.get("priority"),
            created: row.get("created_at"),
            max_attempts,
            now: now_ms(),
        };
        let last: Option<i64> = row.get("last");
        let mut reused = 0;
        for (k, job) in jobs.iter().enumerate() {
            let seq = last.unwrap_or(-1) + 1 + k as i64;
            reused += i64::from(self.insert_job(conn, &order, seq, job).await?);
        }
        if reused > 0 {
            self.aggregate_point(conn, sweep_id, point).await?;
        }
        Ok(true)
    }
}
