-- The work each sample took in the engine's own unit (grains × steps), so a
-- sweep's cost can be summed independently of the machine that ran it.
ALTER TABLE results ADD COLUMN particle_steps BIGINT NOT NULL DEFAULT 0;
