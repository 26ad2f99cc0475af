//! The queue: sweeps and their jobs go in, workers claim jobs under a
//! lease, and each job ends done (its result written in the same
//! transaction), handed back, or failed.

use crate::checkpoints::FURTHEST_STEP;
use crate::{
    now_ms, Backend, Claim, Created, Lease, NewJob, NewSweep, Result, ResultRecord, Store,
    StoreError,
};
use sqlx::any::AnyRow;
use sqlx::Row;
use std::time::Duration;

/// The PostgreSQL advisory lock that claims hold until they commit.
const CLAIM_LOCK: i64 = 0x7265_706f_7365;

impl Store {
    /// Stores a sweep and all its jobs in one transaction. Jobs whose sample
    /// already has a result are created done (reused).
    pub async fn create_sweep(
        &self,
        sweep: &NewSweep,
        jobs: &[NewJob],
        max_attempts: i64,
    ) -> Result<Created> {
        let id = uuid::Uuid::new_v4().to_string();
        let now = now_ms();
        let mut tx = self.pool.begin().await?;
        sqlx::query(&self.sql(
            "INSERT INTO sweeps (id, name, protocol, spec, priority, state, created_at, study) VALUES ($1, $2, $3, $4, $5, 'active', $6, $7)",
        ))
        .persistent(false)
        .bind(&id)
        .bind(&sweep.name)
        .bind(&sweep.protocol)
        .bind(sweep.spec.to_string())
        .bind(sweep.priority)
        .bind(now)
        .bind(sweep.study.as_deref())
        .execute(&mut *tx)
        .await?;
        let order = JobOrder {
            sweep_id: &id,
            priority: sweep.priority,
            created: now,
            max_attempts,
            now,
        };
        let mut reused = 0;
        for (seq, job) in jobs.iter().enumerate() {
            reused += usize::from(self.insert_job(&mut tx, &order, seq as i64, job).await?);
        }
        self.aggregate_sweep(&mut tx, &id).await?;
        tx.commit().await?;
        Ok(Created {
            id,
            jobs: jobs.len(),
            reused,
        })
    }

    /// The newest sweep queued for the same study with the same spec, if its
    /// jobs are `jobs`' samples in their order and none has failed: queueing
    /// a study sweep again (an interim report, a second click) returns it
    /// rather than a twin holding the same samples. A sweep whose samples
    /// changed (another engine) or that has failed jobs gets a new one, which
    /// queues what is missing. `jobs` of the answer counts the sweep's jobs,
    /// `reused` those done.
    pub async fn same_sweep(&self, sweep: &NewSweep, jobs: &[NewJob]) -> Result<Option<Created>> {
        let Some(study) = &sweep.study else {
            return Ok(None);
        };
        let id: Option<String> = sqlx::query_scalar(&self.sql(
            "SELECT id FROM sweeps WHERE study = $1 AND spec = $2 AND state <> 'cancelled' \
             ORDER BY created_at DESC, id LIMIT 1",
        ))
        .bind(study)
        .bind(sweep.spec.to_string())
        .fetch_optional(&self.pool)
        .await?;
        let Some(id) = id else {
            return Ok(None);
        };
        let rows = sqlx::query(
            &self.sql("SELECT sample_hash, state FROM jobs WHERE sweep_id = $1 ORDER BY seq"),
        )
        .bind(&id)
        .fetch_all(&self.pool)
        .await?;
        let same = rows.len() == jobs.len()
            && rows
                .iter()
                .zip(jobs)
                .all(|(r, j)| r.get::<String, _>("sample_hash") == j.sample_hash);
        let state = |r: &AnyRow| r.get::<String, _>("state");
        if !same || rows.iter().any(|r| state(r) == "failed") {
            return Ok(None);
        }
        let done = rows.iter().filter(|r| state(r) == "done").count();
        Ok(Some(Created {
            id,
            jobs: rows.len(),
            reused: done,
        }))
    }

    /// Inserts one job of a sweep; a job whose sample already has a result
    /// is created done (reused). Returns whether it was reused.
    pub(crate) async fn insert_job(
        &self,
        conn: &mut sqlx::AnyConnection,
        order: &JobOrder<'_>,
        seq: i64,
        job: &NewJob,
    ) -> Result<bool> {
        let known: Option<AnyRow> =
            sqlx::query(&self.sql("SELECT 1 FROM results WHERE sample_hash = $1"))
                .bind(&job.sample_hash)
                .fetch_optional(&mut *conn)
                .await?;
        let state = if known.is_some() { "done" } else { "queued" };
        sqlx::query(&self.sql(
            "INSERT INTO jobs (id, sweep_id, seq, point, sample, seed, sample_hash, scene, state, attempts, max_attempts, \
             created_at, updated_at, priority, sweep_created) \
             VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9, 0, $10, $11, $11, $12, $13)",
        ))
        .bind(uuid::Uuid::new_v4().to_string())
        .bind(order.sweep_id)
        .bind(seq)
        .bind(serde_json::Value::Object(job.point.clone()).to_string())
        .bind(job.sample as i64)
        .bind(job.seed as i64)
        .bind(&job.sample_hash)
        .bind(&job.scene)
        .bind(state)
        .bind(order.max_attempts)
        .bind(order.now)
        .bind(order.priority)
        .bind(order.created)
        .execute(&mut *conn)
        .await?;
        Ok(known.is_some())
    }

    /// Returns expired leases to the queue, or fails jobs out of attempts.
    /// An attempt whose holder saved a checkpoint past the one it resumed
    /// from made progress and is not counted: a long sample interrupted
    /// again and again still gets to finish, while one that dies before its
    /// first new checkpoint uses up its attempts as any other job.
    async fn expire_leases(&self, conn: &mut sqlx::AnyConnection, now: i64) -> Result<()> {
        const ADVANCED: &str = "EXISTS (SELECT 1 FROM checkpoints c WHERE c.job_id = jobs.id \
             AND c.iteration > COALESCE(jobs.resume_step, -1))";
        let spent = format!("(NOT {ADVANCED} AND attempts >= max_attempts)");
        sqlx::query(&self.sql(&format!(
            "UPDATE jobs SET state = CASE WHEN {spent} THEN 'failed' ELSE 'queued' END, \
             error = CASE WHEN {spent} THEN 'lease expired after ' || CAST(attempts AS TEXT) || ' attempts' ELSE error END, \
             attempts = CASE WHEN {ADVANCED} THEN attempts - 1 ELSE attempts END, \
             lease_owner = NULL, lease_expires = NULL, updated_at = $1 \
             WHERE state = 'running' AND lease_expires < $1"
        )))
        .bind(now)
        .execute(&mut *conn)
        .await?;
        Ok(())
    }

    /// Claims the next job for `owner` with a lease of `lease`.
    pub async fn claim(&self, owner: &str, lease: Duration) -> Result<Option<Claim>> {
        let now = now_ms();
        let expires = now + lease.as_millis() as i64;
        let mut conn = self.pool.acquire().await?;
        // One seek in `jobs_next`: queued jobs belong to active sweeps only.
        // A sample another job is already running (the same sample queued
        // by two sweeps) waits: it ends done with that job's result.
        let pick = "SELECT q.id FROM jobs q WHERE q.state = 'queued' \
             AND NOT EXISTS (SELECT 1 FROM jobs r WHERE r.sample_hash = q.sample_hash AND r.state = 'running') \
             ORDER BY q.priority DESC, q.sweep_created, q.sweep_id, q.seq LIMIT 1";
        let lock = match self.backend {
            Backend::Sqlite => "",
            Backend::Postgres => " FOR UPDATE SKIP LOCKED",
        };
        // The step it resumes from: the furthest checkpoint of its sample.
        let claim_sql = self.sql(&format!(
            "UPDATE jobs SET state = 'running', lease_owner = $1, lease_expires = $2, attempts = attempts + 1, updated_at = $3, \
             resume_step = ({FURTHEST_STEP}) \
             WHERE id = ({pick}{lock}) RETURNING id, sweep_id, sample_hash, scene, attempts"
        ));
        let begin = match self.backend {
            Backend::Sqlite => "BEGIN IMMEDIATE",
            Backend::Postgres => "BEGIN",
        };
        sqlx::query(begin).execute(&mut *conn).await?;
        let result = async {
            if self.backend == Backend::Postgres {
                // Claims take turns, as SQLite's write lock makes them: a
                // claim then sees every sample that one just before it
                // started, so no two workers run copies of one sample.
                sqlx::query(&format!("SELECT pg_advisory_xact_lock({CLAIM_LOCK})"))
                    .execute(&mut *conn)
                    .await?;
            }
            self.expire_leases(&mut conn, now).await?;
            let row = sqlx::query(&claim_sql)
                .bind(owner)
                .bind(expires)
                .bind(now)
                .fetch_optional(&mut *conn)
                .await?;
            Ok::<_, StoreError>(row)
        }
        .await;
        match result {
            Ok(row) => {
                sqlx::query("COMMIT").execute(&mut *conn).await?;
                Ok(row.map(|r| Claim {
                    job_id: r.get("id"),
                    sweep_id: r.get("sweep_id"),
                    sample_hash: r.get("sample_hash"),
                    scene: r.get("scene"),
                    attempts: r.get("attempts"),
                    lease_expires: expires,
                }))
            }
            Err(e) => {
                let _ = sqlx::query("ROLLBACK").execute(&mut *conn).await;
                Err(e)
            }
        }
    }

    /// Renews the lease of a running job; says whether to go on.
    pub async fn heartbeat(&self, job_id: &str, owner: &str, lease: Duration) -> Result<Lease> {
        let now = now_ms();
        let row = sqlx::query(&self.sql(
            "UPDATE jobs SET lease_expires = $1, updated_at = $2 WHERE id = $3 AND lease_owner = $4 AND state = 'running' \
             RETURNING (SELECT state FROM sweeps WHERE sweeps.id = jobs.sweep_id) AS sweep_state",
        ))
        .bind(now + lease.as_millis() as i64)
        .bind(now)
        .bind(job_id)
        .bind(owner)
        .fetch_optional(&self.pool)
        .await?;
        Ok(match row {
            None => Lease::Lost,
            Some(r) if r.get::<String, _>("sweep_state") == "cancelled" => Lease::Cancelled,
            Some(_) => Lease::Held,
        })
    }

    /// Hands a running job back to the queue without counting the attempt
    /// (graceful shutdown, or a cancelled sweep).
    pub async fn release(&self, job_id: &str, owner: &str) -> Result<bool> {
        let r = sqlx::query(&self.sql(
            "UPDATE jobs SET state = CASE WHEN (SELECT state FROM sweeps WHERE sweeps.id = jobs.sweep_id) = 'cancelled' \
             THEN 'cancelled' ELSE 'queued' END, attempts = attempts - 1, lease_owner = NULL, lease_expires = NULL, updated_at = $1 \
             WHERE id = $2 AND lease_owner = $3 AND state = 'running'",
        ))
        .bind(now_ms())
        .bind(job_id)
        .bind(owner)
        .execute(&self.pool)
        .await?;
        Ok(r.rows_affected() == 1)
    }

    /// Stores a finished sample: the job becomes done and its result and
    /// metric rows are written, together, and only if `owner` still holds
    /// the lease. Returns false (and writes nothing) when the lease was lost.
    pub async fn complete(
        &self,
        job_id: &str,
        owner: &str,
        sample_hash: &str,
        result: &ResultRecord,
    ) -> Result<bool> {
        let now = now_ms();
        let mut tx = self.pool.begin().await?;
        let updated = sqlx::query(&self.sql(
            "UPDATE jobs SET state = 'done', lease_owner = NULL, lease_expires = NULL, error = NULL, updated_at = $1 \
             WHERE id = $2 AND lease_owner = $3 AND state = 'running'",
        ))
        .bind(now)
        .bind(job_id)
        .bind(owner)
        .execute(&mut *tx)
        .await?;
        if updated.rows_affected() != 1 {
            tx.rollback().await?;
            return Ok(false);
        }
        let inserted = sqlx::query(&self.sql(
            "INSERT INTO results (sample_hash, job_id, engine, seed, outcome, reason, grains_initial, grains_final, grains_lost, \
             iterations, simulated_time, wall_time, created_at, particle_steps) \
             VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9, $10, $11, $12, $13, $14) \
             ON CONFLICT (sample_hash) DO NOTHING",
        ))
        // Not a cached statement: through `sqlx::Any`, a NULL bound to a
        // prepared PostgreSQL statement whose parameter was typed by an
        // earlier non-NULL bind is rejected ("incorrect binary data format").
        // Completed runs bind a NULL reason, so each insert is prepared with
        // its own parameters.
        .persistent(false)
        .bind(sample_hash)
        .bind(job_id)
        .bind(&result.engine)
        .bind(result.seed as i64)
        .bind(&result.outcome)
        .bind(result.reason.as_deref())
        .bind(result.counts.grains_initial)
        .bind(result.counts.grains_final)
        .bind(result.counts.grains_lost)
        .bind(result.counts.iterations)
        .bind(result.counts.simulated_time)
        .bind(result.counts.wall_time)
        .bind(now)
        .bind(result.counts.particle_steps)
        .execute(&mut *tx)
        .await?;
        // The same sample queued by other sweeps is done with this result,
        // and no checkpoint of it is needed any more.
        sqlx::query(&self.sql(
            "DELETE FROM checkpoints WHERE job_id IN (SELECT id FROM jobs WHERE sample_hash = $1)",
        ))
        .bind(sample_hash)
        .execute(&mut *tx)
        .await?;
        sqlx::query(&self.sql(
            "UPDATE jobs SET state = 'done', updated_at = $1 WHERE sample_hash = $2 AND state = 'queued'",
        ))
        .bind(now)
        .bind(sample_hash)
        .execute(&mut *tx)
        .await?;
        if inserted.rows_affected() == 1 {
            self.record_new(&mut tx, sample_hash, result).await?;
        }
        tx.commit().await?;
        Ok(true)
    }

    /// What a sample stored for the first time brings besides its row:
    /// its report, its metric values and their running aggregates.
    async fn record_new(
        &self,
        tx: &mut sqlx::AnyConnection,
        sample_hash: &str,
        result: &ResultRecord,
    ) -> Result<()> {
        sqlx::query(&self.sql("INSERT INTO result_reports (sample_hash, report) VALUES ($1, $2)"))
            .bind(sample_hash)
            .bind(&result.report)
            .execute(&mut *tx)
            .await?;
        let failed = result.outcome != "completed";
        self.aggregate_result(&mut *tx, sample_hash, failed, &result.metrics)
            .await?;
        for (metric, value) in result.metrics.iter().filter(|(_, v)| v.is_finite()) {
            sqlx::query(
                &self.sql(
                    "INSERT INTO metric_values (sample_hash, metric, value) VALUES ($1, $2, $3)",
                ),
            )
            .bind(sample_hash)
            .bind(metric)
            .bind(*value)
            .execute(&mut *tx)
            .await?;
        }
        Ok(())
    }

    /// A sweep's state (`active`, `cancelled`, ...), or None for an unknown
    /// sweep, read on the pool or inside a transaction.
    async fn sweep_state<'e, E>(&self, on: E, sweep_id: &str) -> Result<Option<String>>
    where
        E: sqlx::Executor<'e, Database = sqlx::Any>,
    {
        Ok(
            sqlx::query_scalar(&self.sql("SELECT state FROM sweeps WHERE id = $1"))
                .bind(sweep_id)
                .fetch_optional(on)
                .await?,
        )
    }

    /// Marks the sweep cancelled and its queued jobs cancelled; running
    /// jobs learn it at their next heartbeat. A sweep with nothing queued
    /// or running (finished, or cancelled before) is left as it is, so a
    /// finished sweep keeps its state and its failed jobs can be retried.
    pub async fn cancel_sweep(&self, sweep_id: &str) -> Result<Cancel> {
        let mut tx = self.pool.begin().await?;
        if self.sweep_state(&mut *tx, sweep_id).await?.is_none() {
            return Ok(Cancel::Unknown);
        }
        let pending: i64 = sqlx::query_scalar(&self.sql(
            "SELECT COUNT(*) FROM jobs WHERE sweep_id = $1 AND state IN ('queued', 'running')",
        ))
        .bind(sweep_id)
        .fetch_one(&mut *tx)
        .await?;
        if pending == 0 {
            return Ok(Cancel::Idle);
        }
        sqlx::query(&self.sql("UPDATE sweeps SET state = 'cancelled' WHERE id = $1"))
            .bind(sweep_id)
            .execute(&mut *tx)
            .await?;
        sqlx::query(&self.sql(
            "UPDATE jobs SET state = 'cancelled', updated_at = $1 WHERE sweep_id = $2 AND state = 'queued'",
        ))
        .bind(now_ms())
        .bind(sweep_id)
        .execute(&mut *tx)
        .await?;
        tx.commit().await?;
        Ok(Cancel::Cancelled)
    }

    /// Puts the failed jobs of a sweep (attempts used up by lost workers,
    /// scenes that could not be run) back in the queue with fresh attempts;
    /// finished jobs stay as they are. A cancelled sweep is not revived.
    pub async fn retry_failed(&self, sweep_id: &str) -> Result<Retry> {
        match self.sweep_state(&self.pool, sweep_id).await?.as_deref() {
            None => return Ok(Retry::Unknown),
            Some("cancelled") => return Ok(Retry::Cancelled),
            Some(_) => {}
        }
        let r = sqlx::query(&self.sql(
            "UPDATE jobs SET state = 'queued', attempts = 0, error = NULL, lease_owner = NULL, \
             lease_expires = NULL, updated_at = $1 WHERE sweep_id = $2 AND state = 'failed'",
        ))
        .bind(now_ms())
        .bind(sweep_id)
        .execute(&self.pool)
        .await?;
        Ok(Retry::Queued(r.rows_affected()))
    }

    /// Ends a running job without a result (its scene could not be run at all).
    pub async fn fail(&self, job_id: &str, owner: &str, reason: &str) -> Result<bool> {
        let r = sqlx::query(&self.sql(
            "UPDATE jobs SET state = 'failed', error = $1, lease_owner = NULL, lease_expires = NULL, updated_at = $2 \
             WHERE id = $3 AND lease_owner = $4 AND state = 'running'",
        ))
        .bind(reason)
        .bind(now_ms())
        .bind(job_id)
        .bind(owner)
        .execute(&self.pool)
        .await?;
        Ok(r.rows_affected() == 1)
    }
}

/// What [`Store::cancel_sweep`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Cancel {
    Unknown,
    /// Nothing was queued or running: the sweep is as it was.
    Idle,
    Cancelled,
}

/// What [`Store::retry_failed`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Retry {
    Unknown,
    Cancelled,
    /// This many failed jobs are queued again.
    Queued(u64),
}

/// What every job of a sweep carries for the claim order.
pub(crate) struct JobOrder<'a> {
    pub sweep_id: &'a str,
    pub priority: i64,
    /// The sweep's creation time.
    pub created: i64,
    pub max_attempts: i64,
    pub now: i64,
}
