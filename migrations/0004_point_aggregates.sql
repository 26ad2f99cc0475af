-- Running aggregates per point, kept in the transaction that stores each
-- result, so that a sweep's points and figures are read in time
-- proportional to its points, not its samples. A point's row is made
-- with its sweep; `samples` counts its stored results, `failures` those
-- that ended without a result. Per metric: count, sum and sum of squares.

CREATE TABLE point_stats (
    sweep_id   TEXT NOT NULL REFERENCES sweeps (id),
    point      TEXT NOT NULL,
    first_seq  BIGINT NOT NULL,
    samples    BIGINT NOT NULL,
    failures   BIGINT NOT NULL,
    PRIMARY KEY (sweep_id, point)
);

CREATE TABLE point_metrics (
    sweep_id   TEXT NOT NULL,
    point      TEXT NOT NULL,
    metric     TEXT NOT NULL,
    n          BIGINT NOT NULL,
    s          DOUBLE PRECISION NOT NULL,
    q          DOUBLE PRECISION NOT NULL,
    PRIMARY KEY (sweep_id, point, metric),
    FOREIGN KEY (sweep_id, point) REFERENCES point_stats (sweep_id, point)
);

-- What is stored already.
INSERT INTO point_stats (sweep_id, point, first_seq, samples, failures)
    SELECT j.sweep_id, j.point, MIN(j.seq),
           COUNT(r.sample_hash),
           CAST(SUM(CASE WHEN r.sample_hash IS NULL OR r.outcome = 'completed' THEN 0 ELSE 1 END) AS BIGINT)
    FROM jobs j LEFT JOIN results r ON r.sample_hash = j.sample_hash
    GROUP BY j.sweep_id, j.point;

INSERT INTO point_metrics (sweep_id, point, metric, n, s, q)
    SELECT j.sweep_id, j.point, m.metric, COUNT(m.value), SUM(m.value), SUM(m.value * m.value)
    FROM jobs j JOIN metric_values m ON m.sample_hash = j.sample_hash
    GROUP BY j.sweep_id, j.point, m.metric;

-- A result's jobs, found by its sample.
CREATE INDEX IF NOT EXISTS jobs_by_hash_point ON jobs (sample_hash, sweep_id, point);
