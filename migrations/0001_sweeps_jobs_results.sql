-- One schema for SQLite and PostgreSQL: portable types only (TEXT for JSON,
-- BIGINT for integers and unix-millisecond times, DOUBLE PRECISION for reals).

CREATE TABLE sweeps (
    id          TEXT PRIMARY KEY,
    name        TEXT NOT NULL,
    protocol    TEXT NOT NULL,
    spec        TEXT NOT NULL,            -- the sweep as submitted (JSON)
    priority    BIGINT NOT NULL DEFAULT 0,
    state       TEXT NOT NULL,            -- active | cancelled
    created_at  BIGINT NOT NULL
);

CREATE TABLE jobs (
    id            TEXT PRIMARY KEY,
    sweep_id      TEXT NOT NULL REFERENCES sweeps (id),
    seq           BIGINT NOT NULL,        -- order within the sweep
    point         TEXT NOT NULL,          -- axis values of the job's point (JSON object)
    sample        BIGINT NOT NULL,        -- sample index within the point
    seed          BIGINT NOT NULL,
    sample_hash   TEXT NOT NULL,          -- hash of canonical scene + seed + engine version
    scene         TEXT NOT NULL,          -- the fully resolved scene (JSON)
    state         TEXT NOT NULL,          -- queued | running | done | failed | cancelled
    attempts      BIGINT NOT NULL DEFAULT 0,
    max_attempts  BIGINT NOT NULL,
    lease_owner   TEXT,
    lease_expires BIGINT,
    error         TEXT,
    created_at    BIGINT NOT NULL,
    updated_at    BIGINT NOT NULL
);

CREATE INDEX jobs_by_state ON jobs (state, sweep_id, seq);
CREATE INDEX jobs_by_hash ON jobs (sample_hash);
CREATE INDEX jobs_by_sweep ON jobs (sweep_id, seq);

-- Exactly one result per sample, whichever sweep asked for it.
CREATE TABLE results (
    sample_hash      TEXT PRIMARY KEY,
    job_id           TEXT NOT NULL,
    engine           TEXT NOT NULL,
    seed             BIGINT NOT NULL,
    outcome          TEXT NOT NULL,       -- completed | not_settled | no_onset | failed | cancelled
    reason           TEXT,
    theta_r_endpoints DOUBLE PRECISION,   -- θ_R by method 1
    theta_r_line     DOUBLE PRECISION,    -- method 2
    theta_r          DOUBLE PRECISION,    -- method 3
    theta_t          DOUBLE PRECISION,
    theta_ms_mean    DOUBLE PRECISION,
    theta_ms_sd      DOUBLE PRECISION,
    theta_ms_max     DOUBLE PRECISION,
    grains_initial   BIGINT NOT NULL,
    grains_final     BIGINT NOT NULL,
    grains_lost      BIGINT NOT NULL,
    iterations       BIGINT NOT NULL,
    simulated_time   DOUBLE PRECISION NOT NULL,
    wall_time        DOUBLE PRECISION NOT NULL,
    report           TEXT NOT NULL,       -- the full run report (JSON)
    created_at       BIGINT NOT NULL
);
