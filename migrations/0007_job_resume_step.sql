-- The step of the checkpoint a claim continued from (NULL: the claim started
-- the sample afresh). A lease that expires after its holder saved a later
-- checkpoint made progress, so the queue gives that attempt back instead of
-- counting it towards the job's limit.

ALTER TABLE jobs ADD COLUMN resume_step BIGINT;
