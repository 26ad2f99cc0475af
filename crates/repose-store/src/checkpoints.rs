//! Checkpoints of running jobs: the latest saved state of a long sample,
//! written by the worker that holds the job's lease and read by whichever
//! worker runs the job next. The physics decides what the bytes hold; the
//! store keeps them whole.

use crate::{now_ms, Result, Store};
use sqlx::Row;

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
        Ok(row.map(|r| StoredCheckpoint {
            job_id: r.get("job_id"),
            owner: r.get("owner"),
            sim_time: r.get("sim_time"),
            iteration: r.get("iteration"),
            state: r.get("state"),
            saved_at: r.get("saved_at"),
        }))
    }
}
