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
//! This crate knows scenes and reports only as documents: it stores what
//! the engine produced, one row per measured metric beside the report, and
//! aggregates the metrics by name. It does not depend on the physics crate;
//! what a protocol measures is whatever metrics its results carry.

mod aggregates;
mod checkpoints;
pub mod export;
mod query;
mod queue;
mod scratch;
mod topup;

use serde::{Deserialize, Serialize};
use sqlx::any::AnyPoolOptions;
use sqlx::{AnyConnection, AnyPool, Connection};
use std::collections::BTreeMap;
use std::time::{SystemTime, UNIX_EPOCH};

pub use checkpoints::StoredCheckpoint;
pub use query::{series, SeriesError, SeriesPoint};
pub use queue::{Cancel, Retry};
pub use scratch::ScratchDatabase;
pub use topup::PointJobs;

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
    #[error("{0}")]
    Unsupported(&'static str),
    #[error("no store at {0}: start `repose serve --database` on it first, which creates it")]
    Missing(String),
    #[error(
        "the store is at schema {found} and this build needs {needed}: {}",
        if found < needed {
            "start this build's `repose serve` on it once, which migrates it"
        } else {
            "it was migrated by a newer build; run that build's workers"
        }
    )]
    Schema { found: i64, needed: i64 },
}

pub type Result<T> = std::result::Result<T, StoreError>;

/// Attempts a job gets before it is marked failed.
pub const DEFAULT_MAX_ATTEMPTS: i64 = 3;

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

/// A sweep to store: what the API and the studies hand over.
#[derive(Debug, Clone, PartialEq)]
pub struct NewSweep {
    pub name: String,
    pub protocol: String,
    /// The sweep as submitted (JSON).
    pub spec: serde_json::Value,
    pub priority: i64,
    /// The study sweep it queues (`paper/sweep`), if any.
    pub study: Option<String>,
}

/// One job of a new sweep.
#[derive(Debug, Clone, PartialEq)]
pub struct NewJob {
    /// The axis values of this job's point.
    pub point: serde_json::Map<String, serde_json::Value>,
    pub sample: u32,
    pub seed: u64,
    /// Identity of the sample (the same scene, seed and engine hash alike).
    pub sample_hash: String,
    /// The fully resolved scene, as stored and run: JSON text, which a
    /// large sweep holds in a fifth of the memory of a parsed document.
    pub scene: String,
}

/// What a run took and left: grain counts, steps and times.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize, utoipa::ToSchema)]
pub struct RunCounts {
    pub grains_initial: i64,
    pub grains_final: i64,
    pub grains_lost: i64,
    pub iterations: i64,
    /// Simulated time, s.
    pub simulated_time: f64,
    /// Wall-clock time of the run, s.
    pub wall_time: f64,
    /// Grains × steps the run took.
    pub particle_steps: i64,
}

/// What a finished sample stores: its outcome, its metrics by name, what it
/// cost, and the full report as a document.
#[derive(Debug, Clone, PartialEq)]
pub struct ResultRecord {
    pub engine: String,
    pub seed: u64,
    pub outcome: String,
    pub reason: Option<String>,
    pub metrics: BTreeMap<String, f64>,
    pub counts: RunCounts,
    /// The full report (JSON text).
    pub report: String,
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
#[derive(Debug, Clone, Serialize, Deserialize, utoipa::ToSchema)]
pub struct Created {
    pub id: String,
    pub jobs: usize,
    /// Jobs whose sample was already computed and is reused, not rerun.
    pub reused: usize,
}

/// What a sweep's finished samples took: the sum of their run times (s,
/// one core each) and of their particle-steps.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default, utoipa::ToSchema)]
pub struct Cost {
    pub samples: i64,
    pub wall_time: f64,
    pub particle_steps: i64,
}

/// Job counts of a sweep by state.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize, utoipa::ToSchema)]
pub struct Progress {
    pub queued: i64,
    pub running: i64,
    pub done: i64,
    pub failed: i64,
    pub cancelled: i64,
}

/// The newest migration this build knows.
fn latest_version() -> i64 {
    MIGRATOR.iter().map(|m| m.version).max().unwrap_or(0)
}

/// The file an SQLite URL names (`sqlite://PATH?options`), none for an
/// in-memory database or another backend.
fn sqlite_file(url: &str) -> Option<&str> {
    let rest = url.strip_prefix("sqlite:")?;
    let rest = rest.strip_prefix("//").unwrap_or(rest);
    let path = rest.split('?').next().unwrap_or(rest);
    (!path.is_empty() && !path.starts_with(":memory:")).then_some(path)
}

impl Store {
    /// Connects (creating an SQLite file on first start) and applies the
    /// migrations the database lacks.
    pub async fn open(url: &str) -> Result<Store> {
        let store = Store::connect(url).await?;
        if !store.schema_is_current().await {
            MIGRATOR.run(&store.pool).await?;
        }
        Ok(store)
    }

    /// Connects to a store that exists and is at this build's schema,
    /// creating and migrating nothing: for workers, which share a store a
    /// server owns. A mistyped SQLite path would otherwise start an empty
    /// store that no server feeds, and a worker of another build would run
    /// its queries against tables it does not know.
    pub async fn open_existing(url: &str) -> Result<Store> {
        if let Some(path) = sqlite_file(url) {
            if !std::path::Path::new(path).is_file() {
                return Err(StoreError::Missing(path.to_string()));
            }
        }
        let store = Store::connect(url).await?;
        let needed = latest_version();
        let found = store.schema_version().await;
        if found != needed {
            store.pool.close().await;
            return Err(StoreError::Schema { found, needed });
        }
        Ok(store)
    }

    /// Connects without touching the schema, whatever version it is at: for
    /// reading a store another build may be serving (a backup), which a
    /// migration would change under it.
    pub async fn connect(url: &str) -> Result<Store> {
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
                // A file that is no database fails every connection alike,
                // and the pool would retry it until its acquire timeout
                // (30 s) and then say only that it timed out: one plain
                // connection reads the file first, and its error is final.
                let mut probe = AnyConnection::connect(&url).await?;
                sqlx::query("PRAGMA schema_version")
                    .execute(&mut probe)
                    .await?;
                probe.close().await?;
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
        Ok(Store { pool, backend })
    }

    /// Whether every migration this build knows has been applied. A
    /// current schema is not touched, so that workers can connect as a
    /// role that may read and write rows but not change tables
    /// (`deploy/postgres/roles.sql`).
    async fn schema_is_current(&self) -> bool {
        self.schema_version().await >= latest_version()
    }

    /// The newest migration applied to the database, 0 for none (or no
    /// migrations table at all).
    async fn schema_version(&self) -> i64 {
        let applied: std::result::Result<Option<i64>, sqlx::Error> =
            sqlx::query_scalar("SELECT MAX(version) FROM _sqlx_migrations WHERE success")
                .fetch_one(&self.pool)
                .await;
        applied.ok().flatten().unwrap_or(0)
    }

    /// Writes a consistent copy of an SQLite store to the file `path`
    /// (`VACUUM INTO`: one read transaction, so writers carry on and the
    /// copy is of one moment) and returns the copy's numbers of sweeps,
    /// jobs and results, read back from the copy.
    pub async fn backup_into(&self, path: &str) -> Result<(i64, i64, i64)> {
        if self.backend != Backend::Sqlite {
            return Err(StoreError::Unsupported(
                "a PostgreSQL store is backed up with pg_dump",
            ));
        }
        sqlx::query("VACUUM INTO ?1")
            .bind(path)
            .execute(&self.pool)
            .await?;
        // The copy keeps the schema of the store it copies.
        let copy = Store::connect(&format!("sqlite://{path}")).await?;
        let mut counts = [0i64; 3];
        for (n, table) in counts.iter_mut().zip(["sweeps", "jobs", "results"]) {
            *n = sqlx::query_scalar(&format!("SELECT COUNT(*) FROM {table}"))
                .fetch_one(&copy.pool)
                .await?;
        }
        copy.pool.close().await;
        Ok((counts[0], counts[1], counts[2]))
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
}

/// Mean, sample standard deviation and standard error of one metric at one point.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
pub struct Aggregate {
    pub n: i64,
    pub mean: Option<f64>,
    /// Sample standard deviation (n − 1): the paper's error bar.
    pub sd: Option<f64>,
    pub sem: Option<f64>,
}

impl Aggregate {
    /// No samples.
    pub const EMPTY: Aggregate = Aggregate {
        n: 0,
        mean: None,
        sd: None,
        sem: None,
    };

    /// From the count, sum and sum of squares.
    pub fn from_sums(n: i64, sum: Option<f64>, sum_sq: Option<f64>) -> Aggregate {
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
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
pub struct Point {
    #[schema(value_type = Object)]
    pub point: serde_json::Map<String, serde_json::Value>,
    /// Samples with a stored result.
    pub samples: i64,
    /// Of those, samples whose run ended without a result (not settled, failed, …).
    pub failures: i64,
    /// Statistics of every metric the point's samples measured, by name.
    pub metrics: BTreeMap<String, Aggregate>,
}

/// One stored sample of a sweep.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
pub struct Sample {
    pub job_id: String,
    pub sample_hash: String,
    #[schema(value_type = Object)]
    pub point: serde_json::Map<String, serde_json::Value>,
    pub sample: i64,
    pub seed: i64,
    pub outcome: String,
    pub reason: Option<String>,
    /// The metrics this sample measured, by name.
    pub metrics: BTreeMap<String, f64>,
    #[serde(flatten)]
    pub counts: RunCounts,
    pub engine: String,
}

/// A sweep as listed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
pub struct SweepInfo {
    pub id: String,
    pub name: String,
    pub protocol: String,
    /// The study sweep it queues (`paper/sweep`), if any.
    pub study: Option<String>,
    pub priority: i64,
    pub state: String,
    pub created_at: i64,
    #[schema(value_type = Object)]
    pub spec: serde_json::Value,
    pub progress: Progress,
    /// Estimated seconds until the queued and running jobs are done, from
    /// the mean wall time of this sweep's finished samples and the number of
    /// jobs running now (none while nothing runs or nothing has finished).
    pub eta_seconds: Option<f64>,
    /// What its finished samples took.
    pub cost: Cost,
    /// How far each running job that has saved a checkpoint has come (a
    /// long sample's only sign of progress before its result).
    pub running: Vec<RunningJob>,
}

/// A running job's latest checkpoint.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
pub struct RunningJob {
    pub job_id: String,
    /// Simulated time at the checkpoint, s.
    pub sim_time: f64,
    /// Steps taken by then.
    pub iteration: i64,
    /// When it was saved, milliseconds since the Unix epoch.
    pub saved_at: i64,
}

pub(crate) fn parse_point(text: &str) -> Result<serde_json::Map<String, serde_json::Value>> {
    match serde_json::from_str(text)? {
        serde_json::Value::Object(m) => Ok(m),
        _ => Ok(serde_json::Map::new()),
    }
}
