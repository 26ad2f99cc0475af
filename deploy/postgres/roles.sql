-- PostgreSQL roles for a repose cluster. Run as a superuser in the
-- repose database after `repose serve` has created the schema once:
--
--   psql -d repose -f deploy/postgres/roles.sql
--
-- `repose serve` connects as the database's owner: it creates the tables
-- and applies the migrations of a new version. `repose worker` on cluster
-- nodes connects as repose_worker, which may do what a worker does and no
-- more: read sweeps and jobs, claim, renew and finish jobs, write results,
-- their reports, metric rows and points' running aggregates, and add jobs to
-- the points of a sweep that chases a standard error (`target_sem`). It
-- cannot create, cancel or delete sweeps, delete results or jobs, or
-- change tables; a worker of a newer version than the schema stops with an
-- error instead of migrating.
--
-- Give the role a password (ALTER ROLE repose_worker PASSWORD '...') or a
-- certificate, and allow it in pg_hba.conf, unless the cluster's network
-- is trusted.

DO $$
BEGIN
    IF NOT EXISTS (SELECT FROM pg_roles WHERE rolname = 'repose_worker') THEN
        CREATE ROLE repose_worker LOGIN;
    END IF;
END
$$;

GRANT USAGE ON SCHEMA public TO repose_worker;
GRANT SELECT ON sweeps, jobs, results, result_reports, metric_values, point_stats,
    point_metrics, _sqlx_migrations TO repose_worker;
-- claim, renew, finish; the running aggregates of each point
GRANT UPDATE ON jobs, point_stats, point_metrics TO repose_worker;
GRANT INSERT ON results, result_reports, metric_values, point_metrics TO repose_worker;
-- the samples a `target_sem` sweep adds to its points
GRANT INSERT ON jobs TO repose_worker;
GRANT DELETE ON point_metrics TO repose_worker;
-- checkpoints of long samples: saved while running, dropped with the result
GRANT SELECT, INSERT, UPDATE, DELETE ON checkpoints TO repose_worker;
