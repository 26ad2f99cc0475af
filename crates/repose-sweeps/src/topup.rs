//! Samples until the error bar is small enough: a sweep with `target_sem`
//! gets more samples at each point whose standard error of the target
//! metric is above the target, up to `max_samples`. Whoever stores a
//! result (a worker) calls [`top_up`]; it adds a batch sized by the
//! point's current scatter once the point's earlier jobs have all run,
//! and the store adds it only if no other worker did meanwhile.

use crate::spec::SweepSpec;
use repose_physics::scene::SceneError;
use repose_store::{Aggregate, Store, StoreError};

#[derive(Debug, thiserror::Error)]
pub enum TopUpError {
    #[error(transparent)]
    Store(#[from] StoreError),
    #[error("the stored sweep spec is unreadable: {0}")]
    Spec(#[from] serde_json::Error),
    #[error("{0}")]
    Scene(#[from] SceneError),
}

/// How many more jobs a point needs: none when its standard error is at
/// the target or it has `max` jobs; else enough for `(sd / target)²`
/// measured samples at its rate of success, at least one.
pub fn more_needed(stats: Option<&Aggregate>, jobs: i64, target: f64, max: i64) -> i64 {
    let room = max - jobs;
    if room <= 0 {
        return 0;
    }
    let n = stats.map_or(0, |a| a.n);
    let (Some(sd), Some(sem)) = (stats.and_then(|a| a.sd), stats.and_then(|a| a.sem)) else {
        return (2 - n).clamp(1, room);
    };
    if sem <= target {
        return 0;
    }
    let wanted = ((sd / target).powi(2)).ceil() as i64;
    let success = n.max(1) as f64 / jobs.max(1) as f64;
    let more = ((wanted - n) as f64 / success).ceil() as i64;
    more.clamp(1, room)
}

/// Adds the samples a sweep's points need; returns how many jobs it added.
pub async fn top_up(store: &Store, sweep_id: &str, max_attempts: i64) -> Result<u64, TopUpError> {
    let Some((state, spec)) = store.sweep_spec(sweep_id).await? else {
        return Ok(0);
    };
    let spec: SweepSpec = serde_json::from_value(spec)?;
    let (Some(target), Some(metric)) = (spec.target_sem, spec.target_metric()) else {
        return Ok(0);
    };
    if state == "cancelled" {
        return Ok(0);
    }
    let max = spec.max_samples_per_point() as i64;
    // Jobs first, then the statistics: a point seen with no job pending
    // had every result stored before, so the statistics read after it
    // include them all (read the other way round, a result stored in
    // between would leave stale statistics beside a finished point, and a
    // sample would be added for nothing).
    let point_jobs = store.point_jobs(sweep_id).await?;
    let points = store.points(sweep_id).await?;
    let mut added = 0;
    for pj in point_jobs {
        if pj.pending > 0 {
            continue;
        }
        let stats = points
            .iter()
            .find(|p| p.point == pj.point)
            .and_then(|p| p.metrics.get(&metric));
        let more = more_needed(stats, pj.jobs, target, max);
        if more == 0 {
            continue;
        }
        let jobs: Vec<_> = spec
            .more_samples(&pj.point, pj.jobs as u32, more as u32)?
            .iter()
            .map(|j| j.to_new_job())
            .collect();
        if store
            .add_jobs(sweep_id, &jobs, pj.jobs, max_attempts)
            .await?
        {
            added += jobs.len() as u64;
        }
    }
    Ok(added)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn agg(n: i64, sd: f64) -> Aggregate {
        Aggregate {
            n,
            mean: Some(20.0),
            sd: Some(sd),
            sem: Some(sd / (n as f64).sqrt()),
        }
    }

    #[test]
    fn a_batch_is_sized_by_the_scatter_and_bounded_by_the_maximum() {
        // sd 3 against a target of 1: nine samples wanted, four measured.
        assert_eq!(more_needed(Some(&agg(4, 3.0)), 4, 1.0, 30), 5);
        // Half the runs fail: twice the jobs.
        assert_eq!(more_needed(Some(&agg(4, 3.0)), 8, 1.0, 30), 10);
        assert_eq!(more_needed(Some(&agg(4, 3.0)), 4, 1.0, 6), 2);
        assert_eq!(more_needed(Some(&agg(9, 3.0)), 9, 1.0, 30), 0);
        assert_eq!(more_needed(Some(&agg(4, 3.0)), 30, 1.0, 30), 0);
        // No spread yet: one more sample, or enough for two.
        assert_eq!(more_needed(None, 3, 1.0, 30), 2);
        assert_eq!(
            more_needed(
                Some(&Aggregate {
                    n: 1,
                    mean: Some(1.0),
                    sd: None,
                    sem: None
                }),
                3,
                1.0,
                30
            ),
            1
        );
    }
}
