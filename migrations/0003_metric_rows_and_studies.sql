-- Metrics become rows: one per sample and metric, whatever the protocol, so
-- a new protocol's metrics need no column of their own. Every value of the
-- former per-angle columns is copied over before the columns go.
CREATE TABLE metric_values (
    sample_hash TEXT NOT NULL REFERENCES results (sample_hash),
    metric      TEXT NOT NULL,
    value       DOUBLE PRECISION NOT NULL,
    PRIMARY KEY (sample_hash, metric)
);

INSERT INTO metric_values (sample_hash, metric, value)
    SELECT sample_hash, 'theta_r', theta_r FROM results WHERE theta_r IS NOT NULL;
INSERT INTO metric_values (sample_hash, metric, value)
    SELECT sample_hash, 'theta_r_line', theta_r_line FROM results WHERE theta_r_line IS NOT NULL;
INSERT INTO metric_values (sample_hash, metric, value)
    SELECT sample_hash, 'theta_r_endpoints', theta_r_endpoints FROM results WHERE theta_r_endpoints IS NOT NULL;
INSERT INTO metric_values (sample_hash, metric, value)
    SELECT sample_hash, 'theta_t', theta_t FROM results WHERE theta_t IS NOT NULL;
INSERT INTO metric_values (sample_hash, metric, value)
    SELECT sample_hash, 'theta_ms_mean', theta_ms_mean FROM results WHERE theta_ms_mean IS NOT NULL;
INSERT INTO metric_values (sample_hash, metric, value)
    SELECT sample_hash, 'theta_ms_sd', theta_ms_sd FROM results WHERE theta_ms_sd IS NOT NULL;
INSERT INTO metric_values (sample_hash, metric, value)
    SELECT sample_hash, 'theta_ms_max', theta_ms_max FROM results WHERE theta_ms_max IS NOT NULL;

ALTER TABLE results DROP COLUMN theta_r_endpoints;
ALTER TABLE results DROP COLUMN theta_r_line;
ALTER TABLE results DROP COLUMN theta_r;
ALTER TABLE results DROP COLUMN theta_t;
ALTER TABLE results DROP COLUMN theta_ms_mean;
ALTER TABLE results DROP COLUMN theta_ms_sd;
ALTER TABLE results DROP COLUMN theta_ms_max;

-- The paper's study sweep a sweep was queued for (`paper/sweep`), so a
-- figure can find the newest data behind it.
ALTER TABLE sweeps ADD COLUMN study TEXT;
CREATE INDEX sweeps_by_study ON sweeps (study, created_at);
