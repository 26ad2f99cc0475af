-- Checkpoints of long samples: the latest saved state of a running job,
-- so that a worker that takes the job over after a lost lease continues
-- from it instead of starting again. At most one row per job; it is
-- deleted in the transaction that stores the job's result.

CREATE TABLE checkpoints (
    job_id     TEXT PRIMARY KEY REFERENCES jobs (id),
    owner      TEXT NOT NULL,
    sim_time   DOUBLE PRECISION NOT NULL,
    iteration  BIGINT NOT NULL,
    state      BYTEA NOT NULL,
    saved_at   BIGINT NOT NULL
);
