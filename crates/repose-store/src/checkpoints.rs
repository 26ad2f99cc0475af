//! Checkpoints of running jobs: the latest saved state of a long sample,
//! written by the worker that holds the job's lease and read by whichever
//! worker runs the sample next — the job's own, or another sweep's job of
//! the same sample (a study queued again goes on where the first copy
//! stopped). The physics decides what the bytes hold; the store keeps them
//! whole.

use crate::{now_ms, Result, Store};
use sqlx::Row;

/// The step of the furthest checkpoint of the sample of the job being
/// updated (`jobs`), over every job of that sample.
pub(crate) const FURTHEST_STEP: &str = "SELECT MAX(c.iteration) FROM checkpoints c \
     JOIN jobs s ON s.id = c.job_id WHERE s.sample_hash = jobs.sample_hash";

/// A checkpoint as stored.
#[derive(Debug, Clone, PartialEq)]
pub struct StoredCheckpoint {
    pub job_id: String,
    /// The worker that wrote it.
    pub owner: String,
    /// Simulated time and step at the save.
    pub sim_time: f64,
    pub iteration: i64,
    pub state: Vec<u8>,
    /// Milliseconds since the Unix epoch.
    pub saved_at: i64,
}

impl Store {
    /// Saves (or replaces) the checkpoint of a job, only while `owner`
    /// holds its lease; returns false, writing nothing, otherwise.
    pub async fn save_checkpoint(
        &self,
        job_id: &str,
        owner: &str,
        sim_time: f64,
        iteration: u64,
        state: &[u8],
    ) -> Result<bool> {
        let iteration = i64::try_from(iteration).unwrap_or(i64::MAX);
        let r = sqlx::query(&self.sql(
            "INSERT INTO checkpoints (job_id, owner, sim_time, iteration, state, saved_at) \
             SELECT id, $1, $2, $3, $4, $5 FROM jobs WHERE id = $6 AND lease_owner = $7 AND state = 'running' \
             ON CONFLICT (job_id) DO UPDATE SET owner = excluded.owner, sim_time = excluded.sim_time, \
             iteration = excluded.iteration, state = excluded.state, saved_at = excluded.saved_at",
        ))
        .bind(owner)
        .bind(sim_time)
        .bind(iteration)
        .bind(state)
        .bind(now_ms())
        .bind(job_id)
        .bind(owner)
        .execute(&self.pool)
        .await?;
        Ok(r.rows_affected() == 1)
    }

    /// The latest checkpoint of a job, if one was saved.
    pub async fn checkpoint(&self, job_id: &str) -> Result<Option<StoredCheckpoint>> {
        let row = sqlx::query(&self.sql(
            "SELECT job_id, owner, sim_time, iteration, state, saved_at FROM checkpoints WHERE job_id = $1",
        ))
        .bind(job_id)
        .fetch_optional(&self.pool)
        .await?;
        Ok(row.map(stored))
    }

    /// The checkpoint to resume a sample from: the furthest saved by any job
    /// of it (the same sample queued by several sweeps shares its progress).
    pub async fn furthest_checkpoint(&self, sample_hash: &str) -> Result<Option<StoredCheckpoint>> {
        let row = sqlx::query(&self.sql(
            "SELECT c.job_id, c.owner, c.sim_time, c.iteration, c.state, c.saved_at \
             FROM checkpoints c JOIN jobs j ON j.id = c.job_id WHERE j.sample_hash = $1 \
             ORDER BY c.iteration DESC, c.saved_at DESC LIMIT 1",
        ))
        .bind(sample_hash)
        .fetch_optional(&self.pool)
        .await?;
        Ok(row.map(stored))
    }

    /// A job's resolved scene (JSON) and the furthest checkpoint of its
    /// sample, whichever job saved it: how far the sample has come.
    /// `None` for an unknown job.
    pub async fn job_progress(
        &self,
        job_id: &str,
    ) -> Result<Option<(String, Option<StoredCheckpoint>)>> {
        let row = sqlx::query(&self.sql("SELECT scene, sample_hash FROM jobs WHERE id = $1"))
            .bind(job_id)
            .fetch_optional(&self.pool)
            .await?;
        let Some(row) = row else {
            return Ok(None);
        };
        let hash: String = row.get("sample_hash");
        let checkpoint = self.furthest_checkpoint(&hash).await?;
        Ok(Some((row.get("scene"), checkpoint)))
    }
}

fn stored(r: sqlx::any::AnyRow) -> StoredCheckpoint {
    StoredCheckpoint {
        job_id: r.get("job_id"),
        owner: r.get("owner"),
        sim_time: r.get("sim_time"),
        iteration: r.get("iteration"),
        state: r.get("state"),
        saved_at: r.get("saved_at"),
    }
}
