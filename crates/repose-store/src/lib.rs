//! # repose-store
//!
//! Sweeps, the job queue and results, on SQLite (one machine; the default)
//! or PostgreSQL (many machines). One schema in `migrations/` serves both:
//! it uses only portable types, and the few statements that differ (how a
//! claim locks) are chosen by [`Backend`].
//!
//! ## Queue semantics
//!
//! * A **claim** takes the next queued job of an active sweep (highest
//!   priority first, then submission order), sets a lease (owner, expiry)
//!   and bumps the attempt count. SQLite claims inside `BEGIN IMMEDIATE`, so
//!   concurrent claimers queue on the write lock instead of failing;
//!   PostgreSQL claims with `FOR UPDATE SKIP LOCKED`.
//! * A running worker **renews** its lease by heartbeat; the heartbeat also
//!   tells it when its sweep was cancelled.
//! * A job whose lease **expired** goes back to the queue (or, past its
//!   maximum number of attempts, is marked failed with the reason) at the
//!   next claim.
//! * **Completion** writes the result and the job's state in one
//!   transaction, and only while the same lease still holds. Results are
//!   keyed by the sample's hash, so no sample is ever stored twice.
//!
//! This crate knows the scene and report only as documents: it stores what
//! the physics crate produced and reads back the few numbers it aggregates.

pub mod spec;

use repose_physics::RunReport;
use serde::Serialize;
use spec::{JobSpec, SweepSpec};
use sqlx::any::{AnyPoolOptions, AnyRow};
use sqlx::{AnyPool, Row};
use std::time::{Duration, SystemTime, UNIX_EPOCH};

pub use spec::Fidelity;

#[derive(Debug, thiserror::Error)]
pub enum StoreError {
    #[error("database: {0}")]
    Database(#[from] sqlx::Error),
    #[error("migration: {0}")]
    Migration(#[from] sqlx::migrate::MigrateError),
    #[error("unsupported database URL `{0}` (use sqlite://FILE or postgres://...)")]
    Url(String),
    #[error("stored document is unreadable: {0}")]
    Document(#[from] serde_json::Error),
}

pub type Result<T> = std::result::Result<T, StoreError>;

/// Which database is behind the pool.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Backend {
    Sqlite,
    Postgres,
}

/// A connection pool to the study's database.
#[derive(Debug, Clone)]
pub struct Store {
    pool: AnyPool,
    backend: Backend,
}

static MIGRATOR: sqlx::migrate::Migrator = sqlx::migrate!("../../migrations");

/// Milliseconds since the Unix epoch.
pub fn now_ms() -> i64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_millis() as i64)
        .unwrap_or(0)
}

/// A job handed to a worker.
#[derive(Debug, Clone)]
pub struct Claim {
    pub job_id: String,
    pub sweep_id: String,
    pub sample_hash: String,
    pub scene: String,
    pub attempts: i64,
    pub lease_expires: i64,
}

/// What a heartbeat learned.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Lease {
    /// Renewed: keep working.
    Held,
    /// The sweep was cancelled: stop and hand the job back.
    Cancelled,
    /// The lease is gone (expired and taken by another worker).
    Lost,
}

/// The outcome of creating a sweep.
#[derive(Debug, Clone, Serialize)]
pub struct Created {
    pub id: String,
    pub jobs: usize,
    /// Jobs whose sample was already computed and is reused, not rerun.
    pub reused: usize,
}

/// Job counts of a sweep by state.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct Progress {
    pub queued: i64,
    pub running: i64,
    pub done: i64,
    pub failed: i64,
    pub cancelled: i64,
}

impl Store {
    /// Connects (creating an SQLite file on first start) and applies the migrations.
    pub async fn open(url: &str) -> Result<Store> {
        sqlx::any::install_default_drivers();
        let backend = if url.starts_with("sqlite:") {
            Backend::Sqlite
        } else if url.starts_with("postgres:") || url.starts_with("postgresql:") {
            Backend::Postgres
        } else {
            return Err(StoreError::Url(url.to_string()));
        };
        let pool = match backend {
            Backend::Sqlite => {
                let url = if url.contains('?') {
                    url.to_string()
                } else {
                    format!("{url}?mode=rwc")
                };
                AnyPoolOptions::new()
                    .max_connections(8)
                    .after_connect(|conn, _| {
                        Box::pin(async move {
                            // WAL lets readers run beside the writer; the busy timeout
                            // makes writers wait for the lock instead of failing.
                            sqlx::query("PRAGMA journal_mode = WAL")
                                .execute(&mut *conn)
                                .await?;
                            sqlx::query("PRAGMA busy_timeout = 30000")
                                .execute(&mut *conn)
                                .await?;
                            sqlx::query("PRAGMA synchronous = NORMAL")
                                .execute(&mut *conn)
                                .await?;
                            sqlx::query("PRAGMA foreign_keys = ON")
                                .execute(&mut *conn)
                                .await?;
                            Ok(())
                        })
                    })
                    .connect(&url)
                    .await?
            }
            Backend::Postgres => {
                AnyPoolOptions::new()
                    .max_connections(16)
                    .connect(url)
                    .await?
            }
        };
        MIGRATOR.run(&pool).await?;
        Ok(Store { pool, backend })
    }

    pub fn backend(&self) -> Backend {
        self.backend
    }

    pub fn pool(&self) -> &AnyPool {
        &self.pool
    }

    /// Statement text for this backend: `$n` placeholders become `?n` on SQLite.
    fn sql(&self, text: &str) -> String {
        match self.backend {
            Backend::Postgres => text.to_string(),
            Backend::Sqlite => text.replace('$', "?"),
        }
    }

    /// Stores a sweep and all its jobs in one transaction. Jobs whose sample
    /// already has a result are created done (reused).
    pub async fn create_sweep(
        &self,
        spec: &SweepSpec,
        jobs: &[JobSpec],
        max_attempts: i64,
    ) -> Result<Created> {
        let id = uuid::Uuid::new_v4().to_string();
        let now = now_ms();
        let mut tx = self.pool.begin().await?;
        sqlx::query(&self.sql(
            "INSERT INTO sweeps (id, name, protocol, spec, priority, state, created_at) VALUES ($1, $2, $3, $4, $5, 'active', $6)",
        ))
        .bind(&id)
        .bind(spec.display_name())
        .bind(spec.protocol.name())
        .bind(serde_json::to_string(spec)?)
        .bind(spec.priority)
        .bind(now)
        .execute(&mut *tx)
        .await?;
        let mut reused = 0;
        for (seq, job) in jobs.iter().enumerate() {
            let known: Option<AnyRow> =
                sqlx::query(&self.sql("SELECT 1 FROM results WHERE sample_hash = $1"))
                    .bind(&job.sample_hash)
                    .fetch_optional(&mut *tx)
                    .await?;
            let state = if known.is_some() {
                reused += 1;
                "done"
            } else {
                "queued"
            };
            sqlx::query(&self.sql(
                "INSERT INTO jobs (id, sweep_id, seq, point, sample, seed, sample_hash, scene, state, attempts, max_attempts, created_at, updated_at) \
                 VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9, 0, $10, $11, $11)",
            ))
            .bind(uuid::Uuid::new_v4().to_string())
            .bind(&id)
            .bind(seq as i64)
            .bind(serde_json::Value::Object(job.point.clone()).to_string())
            .bind(job.sample as i64)
            .bind(job.seed as i64)
            .bind(&job.sample_hash)
            .bind(serde_json::to_string(&job.scene)?)
            .bind(state)
            .bind(max_attempts)
            .bind(now)
            .execute(&mut *tx)
            .await?;
        }
        tx.commit().await?;
        Ok(Created {
            id,
            jobs: jobs.len(),
            reused,
        })
    }

    /// Returns expired leases to the queue (or fails jobs out of attempts).
    async fn expire_leases(&self, conn: &mut sqlx::AnyConnection, now: i64) -> Result<()> {
        sqlx::query(&self.sql(
            "UPDATE jobs SET state = CASE WHEN attempts >= max_attempts THEN 'failed' ELSE 'queued' END, \
             error = CASE WHEN attempts >= max_attempts THEN 'lease expired after ' || CAST(attempts AS TEXT) || ' attempts' ELSE error END, \
             lease_owner = NULL, lease_expires = NULL, updated_at = $1 \
             WHERE state = 'running' AND lease_expires < $1",
        ))
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
        let pick = match self.backend {
            Backend::Sqlite => {
                "SELECT j.id FROM jobs j JOIN sweeps s ON s.id = j.sweep_id \
                 WHERE j.state = 'queued' AND s.state = 'active' ORDER BY s.priority DESC, s.created_at, j.seq LIMIT 1"
            }
            Backend::Postgres => {
                "SELECT j.id FROM jobs j JOIN sweeps s ON s.id = j.sweep_id \
                 WHERE j.state = 'queued' AND s.state = 'active' ORDER BY s.priority DESC, s.created_at, j.seq LIMIT 1 \
                 FOR UPDATE OF j SKIP LOCKED"
            }
        };
        let claim_sql = self.sql(&format!(
            "UPDATE jobs SET state = 'running', lease_owner = $1, lease_expires = $2, attempts = attempts + 1, updated_at = $3 \
             WHERE id = ({pick}) RETURNING id, sweep_id, sample_hash, scene, attempts"
        ));
        let begin = match self.backend {
            Backend::Sqlite => "BEGIN IMMEDIATE",
            Backend::Postgres => "BEGIN",
        };
        sqlx::query(begin).execute(&mut *conn).await?;
        let result = async {
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

    /// Stores a finished sample: the job becomes done and its result is
    /// written, together, and only if `owner` still holds the lease.
    /// Returns false (and writes nothing) when the lease was lost.
    pub async fn complete(
        &self,
        job_id: &str,
        owner: &str,
        sample_hash: &str,
        report: &RunReport,
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
        let repose = report.repose;
        let flux = report.flux.as_ref();
        sqlx::query(&self.sql(
            "INSERT INTO results (sample_hash, job_id, engine, seed, outcome, reason, theta_r_endpoints, theta_r_line, theta_r, \
             theta_t, theta_ms_mean, theta_ms_sd, theta_ms_max, grains_initial, grains_final, grains_lost, iterations, \
             simulated_time, wall_time, report, created_at) \
             VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9, $10, $11, $12, $13, $14, $15, $16, $17, $18, $19, $20, $21) \
             ON CONFLICT (sample_hash) DO NOTHING",
        ))
        .bind(sample_hash)
        .bind(job_id)
        .bind(&report.engine)
        .bind(report.seed as i64)
        .bind(report.outcome.status())
        .bind(report.outcome.reason())
        .bind(repose.map(|a| a.endpoints))
        .bind(repose.map(|a| a.line_fit))
        .bind(repose.map(|a| a.cumulative_fit))
        .bind(report.tilt.map(|t| t.angle))
        .bind(flux.and_then(|f| f.steady).map(|s| s.mean))
        .bind(flux.and_then(|f| f.steady).map(|s| s.sd))
        .bind(flux.and_then(|f| f.max))
        .bind(report.grains.initial as i64)
        .bind(report.grains.remaining as i64)
        .bind(report.grains.lost as i64)
        .bind(report.iterations as i64)
        .bind(report.simulated_time)
        .bind(report.wall_time)
        .bind(serde_json::to_string(report)?)
        .bind(now)
        .execute(&mut *tx)
        .await?;
        tx.commit().await?;
        Ok(true)
    }

    /// Marks the sweep cancelled and its queued jobs cancelled; running
    /// jobs learn it at their next heartbeat. Returns false for an unknown sweep.
    pub async fn cancel_sweep(&self, sweep_id: &str) -> Result<bool> {
        let mut tx = self.pool.begin().await?;
        let r = sqlx::query(&self.sql("UPDATE sweeps SET state = 'cancelled' WHERE id = $1"))
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
        Ok(r.rows_affected() == 1)
    }

    /// Job counts by state for one sweep.
    pub async fn progress(&self, sweep_id: &str) -> Result<Progress> {
        let rows = sqlx::query(
            &self.sql("SELECT state, COUNT(*) AS n FROM jobs WHERE sweep_id = $1 GROUP BY state"),
        )
        .bind(sweep_id)
        .fetch_all(&self.pool)
        .await?;
        let mut p = Progress::default();
        for r in rows {
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
        Ok(p)
    }

    /// Number of stored results with this hash (0 or 1 by construction).
    pub async fn result_count(&self, sample_hash: &str) -> Result<i64> {
        let r = sqlx::query(&self.sql("SELECT COUNT(*) AS n FROM results WHERE sample_hash = $1"))
            .bind(sample_hash)
            .fetch_one(&self.pool)
            .await?;
        Ok(r.get("n"))
    }
}
