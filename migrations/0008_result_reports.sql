-- A sample's full run report (its energy trace and final state, up to a
-- megabyte for a 3D heap) moves out of the results table into its own.
-- A results row is then a few hundred bytes, so the queries that sum or
-- count results (a sweep's cost and progress, the listing of sweeps) read
-- that much a sample instead of stepping through every report. Every
-- stored report is copied before its column is dropped.

CREATE TABLE result_reports (
    sample_hash TEXT PRIMARY KEY REFERENCES results (sample_hash),
    report      TEXT NOT NULL
);

INSERT INTO result_reports (sample_hash, report)
SELECT sample_hash, report FROM results;

ALTER TABLE results DROP COLUMN report;
