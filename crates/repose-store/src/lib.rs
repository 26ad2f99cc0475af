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

pub mod export;
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

/// What a sweep's finished samples took: the sum of their run times (s,
/// one core each) and of their particle-steps.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Default)]
pub struct Cost {
    pub samples: i64,
    pub wall_time: f64,
    pub particle_steps: i64,
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
                            for pragma in [
                                "PRAGMA journal_mode = WAL",
                                "PRAGMA busy_timeout = 30000",
                                "PRAGMA synchronous = NORMAL",
                                "PRAGMA foreign_keys = ON",
                            ] {
                                sqlx::query(pragma).execute(&mut *conn).await?;
                            }
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
             simulated_time, wall_time, report, created_at, particle_steps) \
             VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9, $10, $11, $12, $13, $14, $15, $16, $17, $18, $19, $20, $21, $22) \
             ON CONFLICT (sample_hash) DO NOTHING",
        ))
        // Not a cached statement: through `sqlx::Any`, a NULL bound to a
        // prepared PostgreSQL statement whose parameter was typed by an
        // earlier non-NULL bind is rejected ("incorrect binary data format").
        // Runs without an angle (failed outcomes) bind NULLs, so each insert
        // is prepared with its own parameters.
        .persistent(false)
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
        .bind(i64::try_from(report.particle_steps).unwrap_or(i64::MAX))
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
}

/// The angles a result carries, by the names the API and exports use.
pub const METRICS: &[(&str, &str)] = &[
    (
        "theta_r",
        "θ_R, method 3 (parabola through the running sum), degrees",
    ),
    (
        "theta_r_line",
        "θ_R, method 2 (least-squares line), degrees",
    ),
    (
        "theta_r_endpoints",
        "θ_R, method 1 (first and last columns), degrees",
    ),
    ("theta_t", "tilting angle θ_T, degrees"),
    (
        "theta_ms_mean",
        "steady mean pile angle of the flux protocol, degrees",
    ),
    (
        "theta_ms_max",
        "largest steady pile angle of the flux protocol, degrees",
    ),
];

/// Mean, sample standard deviation and standard error of one metric at one point.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Aggregate {
    pub n: i64,
    pub mean: Option<f64>,
    /// Sample standard deviation (n − 1): the paper's error bar.
    pub sd: Option<f64>,
    pub sem: Option<f64>,
}

impl Aggregate {
    /// From the count, sum and sum of squares.
    fn from_sums(n: i64, sum: Option<f64>, sum_sq: Option<f64>) -> Aggregate {
        if n == 0 {
            return Aggregate {
                n,
                mean: None,
                sd: None,
                sem: None,
            };
        }
        let (s, q) = (sum.unwrap_or(0.0), sum_sq.unwrap_or(0.0));
        let mean = s / n as f64;
        let sd = (n > 1).then(|| ((q - s * mean) / (n - 1) as f64).max(0.0).sqrt());
        Aggregate {
            n,
            mean: Some(mean),
            sd,
            sem: sd.map(|sd| sd / (n as f64).sqrt()),
        }
    }
}

/// One point of a sweep: its axis values and the statistics of its samples.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Point {
    pub point: serde_json::Map<String, serde_json::Value>,
    /// Samples with a stored result.
    pub samples: i64,
    /// Of those, samples whose run ended without a result (not settled, failed, …).
    pub failures: i64,
    pub metrics: std::collections::BTreeMap<String, Aggregate>,
}

/// One stored sample of a sweep.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Sample {
    pub job_id: String,
    pub sample_hash: String,
    pub point: serde_json::Map<String, serde_json::Value>,
    pub sample: i64,
    pub seed: i64,
    pub outcome: String,
    pub reason: Option<String>,
    pub theta_r: Option<f64>,
    pub theta_r_line: Option<f64>,
    pub theta_r_endpoints: Option<f64>,
    pub theta_t: Option<f64>,
    pub theta_ms_mean: Option<f64>,
    pub theta_ms_sd: Option<f64>,
    pub theta_ms_max: Option<f64>,
    pub grains_initial: i64,
    pub grains_final: i64,
    pub grains_lost: i64,
    pub iterations: i64,
    pub simulated_time: f64,
    pub wall_time: f64,
    /// Grains × steps the run took.
    pub particle_steps: i64,
    pub engine: String,
}

/// A sweep as listed.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SweepInfo {
    pub id: String,
    pub name: String,
    pub protocol: String,
    pub priority: i64,
    pub state: String,
    pub created_at: i64,
    pub spec: serde_json::Value,
    pub progress: Progress,
    /// Estimated seconds until the queued and running jobs are done, from
    /// the mean wall time of this sweep's finished samples and the number of
    /// jobs running now (none while nothing runs or nothing has finished).
    pub eta_seconds: Option<f64>,
    /// What its finished samples took.
    pub cost: Cost,
}

fn parse_point(text: &str) -> Result<serde_json::Map<String, serde_json::Value>> {
    match serde_json::from_str(text)? {
        serde_json::Value::Object(m) => Ok(m),
        _ => Ok(serde_json::Map::new()),
    }
}

impl Store {
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

    /// All sweeps, newest first, with progress.
    pub async fn sweeps(&self) -> Result<Vec<SweepInfo>> {
        let ids: Vec<String> =
            sqlx::query_scalar(&self.sql("SELECT id FROM sweeps ORDER BY created_at DESC, id"))
                .fetch_all(&self.pool)
                .await?;
        let mut out = Vec::with_capacity(ids.len());
        for id in ids {
            if let Some(s) = self.sweep(&id).await? {
                out.push(s);
            }
        }
        Ok(out)
    }

    /// One sweep with its progress and ETA, or None.
    pub async fn sweep(&self, id: &str) -> Result<Option<SweepInfo>> {
        let Some(row) = sqlx::query(&self.sql(
            "SELECT id, name, protocol, spec, priority, state, created_at FROM sweeps WHERE id = $1",
        ))
        .bind(id)
        .fetch_optional(&self.pool)
        .await?
        else {
            return Ok(None);
        };
        let progress = self.progress(id).await?;
        let cost_row = sqlx::query(&self.sql(
            "SELECT COUNT(*) AS n, SUM(r.wall_time) AS wall, CAST(SUM(r.particle_steps) AS BIGINT) AS steps \
             FROM jobs j JOIN results r ON r.sample_hash = j.sample_hash \
             WHERE j.sweep_id = $1 AND j.state = 'done'",
        ))
        .bind(id)
        .fetch_one(&self.pool)
        .await?;
        let cost = Cost {
            samples: cost_row.get("n"),
            wall_time: cost_row.get::<Option<f64>, _>("wall").unwrap_or(0.0),
            particle_steps: cost_row.get::<Option<i64>, _>("steps").unwrap_or(0),
        };
        let mean_wall = (cost.samples > 0).then(|| cost.wall_time / cost.samples as f64);
        let left = progress.queued + progress.running;
        let eta_seconds = match (mean_wall, progress.running) {
            (_, _) if left == 0 => Some(0.0),
            (Some(w), r) if r > 0 => Some(w * left as f64 / r as f64),
            _ => None,
        };
        Ok(Some(SweepInfo {
            id: row.get("id"),
            name: row.get("name"),
            protocol: row.get("protocol"),
            priority: row.get("priority"),
            state: row.get("state"),
            created_at: row.get("created_at"),
            spec: serde_json::from_str(&row.get::<String, _>("spec"))?,
            progress,
            eta_seconds,
            cost,
        }))
    }

    /// Every stored sample of a sweep, in job order.
    pub async fn samples(&self, sweep_id: &str) -> Result<Vec<Sample>> {
        let rows = sqlx::query(&self.sql(
            "SELECT j.id AS job_id, j.sample_hash, j.point, j.sample, j.seed, r.outcome, r.reason, r.theta_r, r.theta_r_line, \
             r.theta_r_endpoints, r.theta_t, r.theta_ms_mean, r.theta_ms_sd, r.theta_ms_max, r.grains_initial, r.grains_final, \
             r.grains_lost, r.iterations, r.simulated_time, r.wall_time, r.particle_steps, r.engine \
             FROM jobs j JOIN results r ON r.sample_hash = j.sample_hash WHERE j.sweep_id = $1 ORDER BY j.seq",
        ))
        .bind(sweep_id)
        .fetch_all(&self.pool)
        .await?;
        rows.into_iter()
            .map(|r| {
                Ok(Sample {
                    job_id: r.get("job_id"),
                    sample_hash: r.get("sample_hash"),
                    point: parse_point(&r.get::<String, _>("point"))?,
                    sample: r.get("sample"),
                    seed: r.get("seed"),
                    outcome: r.get("outcome"),
                    reason: r.get("reason"),
                    theta_r: r.get("theta_r"),
                    theta_r_line: r.get("theta_r_line"),
                    theta_r_endpoints: r.get("theta_r_endpoints"),
                    theta_t: r.get("theta_t"),
                    theta_ms_mean: r.get("theta_ms_mean"),
                    theta_ms_sd: r.get("theta_ms_sd"),
                    theta_ms_max: r.get("theta_ms_max"),
                    grains_initial: r.get("grains_initial"),
                    grains_final: r.get("grains_final"),
                    grains_lost: r.get("grains_lost"),
                    iterations: r.get("iterations"),
                    simulated_time: r.get("simulated_time"),
                    wall_time: r.get("wall_time"),
                    particle_steps: r.get("particle_steps"),
                    engine: r.get("engine"),
                })
            })
            .collect()
    }

    /// Per-point statistics of every metric, computed in the database from
    /// counts, sums and sums of squares.
    pub async fn points(&self, sweep_id: &str) -> Result<Vec<Point>> {
        let mut columns = String::new();
        for (m, _) in METRICS {
            columns.push_str(&format!(
                ", COUNT(r.{m}) AS {m}_n, SUM(r.{m}) AS {m}_s, SUM(r.{m} * r.{m}) AS {m}_q"
            ));
        }
        let rows = sqlx::query(&self.sql(&format!(
            "SELECT j.point, MIN(j.seq) AS first, COUNT(*) AS samples, \
             CAST(SUM(CASE WHEN r.outcome = 'completed' THEN 0 ELSE 1 END) AS BIGINT) AS failures{columns} \
             FROM jobs j JOIN results r ON r.sample_hash = j.sample_hash \
             WHERE j.sweep_id = $1 GROUP BY j.point ORDER BY first"
        )))
        .bind(sweep_id)
        .fetch_all(&self.pool)
        .await?;
        rows.into_iter()
            .map(|r| {
                let metrics = METRICS
                    .iter()
                    .map(|(m, _)| {
                        let agg = Aggregate::from_sums(
                            r.get(format!("{m}_n").as_str()),
                            r.get(format!("{m}_s").as_str()),
                            r.get(format!("{m}_q").as_str()),
                        );
                        (m.to_string(), agg)
                    })
                    .collect();
                Ok(Point {
                    point: parse_point(&r.get::<String, _>("point"))?,
                    samples: r.get("samples"),
                    failures: r.get("failures"),
                    metrics,
                })
            })
            .collect()
    }

    /// The full run report of one sample.
    pub async fn report(&self, sample_hash: &str) -> Result<Option<serde_json::Value>> {
        let text: Option<String> =
            sqlx::query_scalar(&self.sql("SELECT report FROM results WHERE sample_hash = $1"))
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
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SeriesPoint {
    pub x: serde_json::Value,
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
    #[error("unknown metric `{0}`")]
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
    if !METRICS.iter().any(|(m, _)| *m == y) {
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
            let agg = p.metrics[y];
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

/// The paper's figures as (x, series, y) choices over a sweep's axes.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Figure {
    pub name: &'static str,
    pub title: &'static str,
    pub x: &'static str,
    pub series: Option<&'static str>,
    pub y: &'static str,
}

pub const FIGURES: &[Figure] = &[
    Figure {
        name: "2a",
        title: "θ_R against the box height H (paper: W = 2, μ = 0.2)",
        x: "box.height",
        series: None,
        y: "theta_r",
    },
    Figure {
        name: "2b",
        title: "θ_R against the box width W for several μ (paper: H/W = 2)",
        x: "box.width",
        series: Some("contact.mu"),
        y: "theta_r",
    },
    Figure {
        name: "3",
        title: "θ_R against μ (paper: W = H = 4)",
        x: "contact.mu",
        series: None,
        y: "theta_r",
    },
    Figure {
        name: "4",
        title: "θ_T against μ (paper: W = H = 4)",
        x: "contact.mu",
        series: None,
        y: "theta_t",
    },
];

pub fn figure(name: &str) -> Option<&'static Figure> {
    FIGURES.iter().find(|f| f.name == name)
}
