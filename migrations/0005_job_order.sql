-- The order in which jobs are claimed (sweep priority, then oldest sweep,
-- then job order) kept on the jobs themselves, so that the next job is one
-- index seek away however many are queued. A queued job always belongs to
-- an active sweep: cancelling a sweep cancels its queued jobs with it.

ALTER TABLE jobs ADD COLUMN priority BIGINT NOT NULL DEFAULT 0;
ALTER TABLE jobs ADD COLUMN sweep_created BIGINT NOT NULL DEFAULT 0;

UPDATE jobs SET
    priority = (SELECT s.priority FROM sweeps s WHERE s.id = jobs.sweep_id),
    sweep_created = (SELECT s.created_at FROM sweeps s WHERE s.id = jobs.sweep_id);

CREATE INDEX jobs_next ON jobs (state, priority DESC, sweep_created, sweep_id, seq);
