-- PostgreSQL roles for a repose cluster. Run as a superuser in the
-- repose database after `repose serve` has created the schema once:
--
--   psql -d repose -f deploy/postgres/roles.sql
--
-- `repose serve` connects as the database's owner: it creates the tables
-- and applies the migrations of a new version. `repose worker` on cluster
-- nodes connects as repose_worker, which may do what a worker does and no
-- more: read sweeps and jobs, claim, renew and finish jobs, write results
-- and their metric rows. It cannot create, cancel or delete sweeps,
-- delete results, or change tables; a worker of a newer version than the
-- schema stops with an error instead of migrating.
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
GRANT SELECT ON sweeps, jobs, results, metric_values, _sqlx_migrations TO repose_worker;
GRANT UPDATE ON jobs TO repose_worker;
GRANT INSERT ON results, metric_values TO repose_worker;
