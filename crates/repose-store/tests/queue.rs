//! Queue semantics against real databases: an SQLite file, and PostgreSQL
//! on 127.0.0.1:5432 (`REPOSE_TEST_POSTGRES` overrides the server URL). With
//! `CI=true` the PostgreSQL tests fail when the server is unreachable;
//! elsewhere they say so and skip.

use repose_store::{Lease, NewJob, NewSweep, ResultRecord, RunCounts, Store};
use serde_json::json;
use std::collections::{BTreeMap, HashSet};
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// A result with the given metrics (the store reads nothing else of a report).
fn record(outcome: &str, metrics: &[(&str, f64)]) -> ResultRecord {
    ResultRecord {
        engine: "test".into(),
        seed: 0,
        outcome: outcome.into(),
        reason: (outcome != "completed").then(|| "flow: test".to_string()),
        metrics: metrics
            .iter()
            .map(|(k, v)| (k.to_string(), *v))
            .collect::<BTreeMap<_, _>>(),
        counts: RunCounts {
            grains_initial: 10,
            grains_final: 8,
            grains_lost: 2,
            iterations: 100,
            simulated_time: 0.1,
            wall_time: 0.01,
            particle_steps: 1000,
        },
        report: json!({"outcome": {"status": outcome}}).to_string(),
    }
}

fn report() -> ResultRecord {
    record("completed", &[("theta_r", 20.0)])
}

/// A sweep over μ with `samples` seeds a point; a sample's identity is its
/// μ and seed, so the same sample in two sweeps hashes alike.
fn sweep(samples: u32, mus: &[f64]) -> (NewSweep, Vec<NewJob>) {
    let jobs = mus
        .iter()
        .flat_map(|mu| {
            (0..samples).map(move |k| NewJob {
                point: json!({"contact.mu": mu}).as_object().cloned().unwrap(),
                sample: k,
                seed: k as u64,
                sample_hash: format!("mu={mu}/seed={k}"),
                scene: json!({"protocol": "fill_release", "seed": k, "contact": {"mu": mu}})
                    .to_string(),
            })
        })
        .collect();
    let spec = json!({"protocol": "fill_release", "axes": {"contact.mu": mus}, "samples": samples});
    (
        NewSweep {
            name: "test".into(),
            protocol: "fill_release".into(),
            spec,
            priority: 0,
            study: None,
        },
        jobs,
    )
}

/// Runs `test` on a fresh SQLite store, then on a fresh PostgreSQL one.
async fn each_backend<F, Fut>(test: F)
where
    F: Fn(Store) -> Fut,
    Fut: std::future::Future<Output = ()>,
{
    test(repose_testkit::sqlite("repose-store").await).await;
    if let Some(db) = repose_testkit::postgres("repose_test").await {
        let store = db.open().await.unwrap();
        test(store.clone()).await;
        repose_testkit::drop_postgres(db, store).await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 4)]
async fn concurrent_workers_complete_every_job_exactly_once() {
    each_backend(|store| async move {
        let (spec, jobs) = sweep(10, &[0.1, 0.2, 0.3, 0.4]);
        let created = store.create_sweep(&spec, &jobs, 3).await.unwrap();
        assert_eq!((created.jobs, created.reused), (40, 0));
        let report = report();
        let done = Arc::new(Mutex::new(Vec::new()));
        let mut workers = Vec::new();
        for w in 0..4 {
            let store = store.clone();
            let done = done.clone();
            let report = report.clone();
            workers.push(tokio::spawn(async move {
                let owner = format!("worker-{w}");
                while let Some(c) = store.claim(&owner, Duration::from_secs(60)).await.unwrap() {
                    assert!(store
                        .complete(&c.job_id, &owner, &c.sample_hash, &report)
                        .await
                        .unwrap());
                    done.lock().unwrap().push(c.job_id);
                }
            }));
        }
        for w in workers {
            w.await.unwrap();
        }
        let done = done.lock().unwrap().clone();
        let unique: HashSet<_> = done.iter().collect();
        assert_eq!(done.len(), 40, "every job once");
        assert_eq!(unique.len(), 40, "no job twice");
        let p = store.progress(&created.id).await.unwrap();
        assert_eq!((p.done, p.queued, p.running), (40, 0, 0));
        for j in &jobs {
            assert_eq!(store.result_count(&j.sample_hash).await.unwrap(), 1);
        }
    })
    .await;
}

/// Eight sweeps queue the same six samples; eight workers claim at once,
/// again and again, completing nothing: each sample is claimed once, by
/// one worker, however the claims interleave.
#[tokio::test(flavor = "multi_thread", worker_threads = 4)]
async fn workers_claiming_at_once_never_run_two_copies_of_a_sample() {
    each_backend(|store| async move {
        let (spec, jobs) = sweep(3, &[0.1, 0.2]);
        for _ in 0..8 {
            store.create_sweep(&spec, &jobs, 3).await.unwrap();
        }
        let start = Arc::new(tokio::sync::Barrier::new(8));
        let mut workers = Vec::new();
        for w in 0..8 {
            let (store, start) = (store.clone(), start.clone());
            workers.push(tokio::spawn(async move {
                let owner = format!("worker-{w}");
                let mut claimed = Vec::new();
                start.wait().await;
                while let Some(c) = store.claim(&owner, Duration::from_secs(60)).await.unwrap() {
                    claimed.push(c.sample_hash);
                }
                claimed
            }));
        }
        let mut claimed = Vec::new();
        for w in workers {
            claimed.extend(w.await.unwrap());
        }
        claimed.sort();
        let unique: HashSet<_> = claimed.iter().collect();
        assert_eq!(unique.len(), 6, "{claimed:?}");
        assert_eq!(claimed.len(), 6, "a sample claimed twice: {claimed:?}");
    })
    .await;
}

#[tokio::test]
async fn an_expired_lease_goes_back_to_the_queue_and_the_old_owner_cannot_complete() {
    each_backend(|store| async move {
        let (spec, jobs) = sweep(1, &[0.2]);
        store.create_sweep(&spec, &jobs, 2).await.unwrap();
        let first = store
            .claim("crashed", Duration::from_millis(1))
            .await
            .unwrap()
            .unwrap();
        tokio::time::sleep(Duration::from_millis(20)).await;
        let second = store
            .claim("rescuer", Duration::from_secs(60))
            .await
            .unwrap()
            .unwrap();
        assert_eq!(first.job_id, second.job_id);
        assert_eq!(second.attempts, 2);
        let report = report();
        assert!(!store
            .complete(&first.job_id, "crashed", &first.sample_hash, &report)
            .await
            .unwrap());
        assert_eq!(
            store
                .heartbeat(&first.job_id, "crashed", Duration::from_secs(1))
                .await
                .unwrap(),
            Lease::Lost
        );
        assert!(store
            .complete(&second.job_id, "rescuer", &second.sample_hash, &report)
            .await
            .unwrap());
        assert_eq!(store.result_count(&first.sample_hash).await.unwrap(), 1);
    })
    .await;
}

/// The sweep's one job is failed for lost leases after two attempts, and
/// nothing is left to claim.
async fn assert_failed_after_two_attempts(store: &Store, sweep: &str) {
    assert!(store
        .claim("next", Duration::from_secs(1))
        .await
        .unwrap()
        .is_none());
    let p = store.progress(sweep).await.unwrap();
    assert_eq!((p.failed, p.queued, p.running), (1, 0, 0));
    let error: String = sqlx::query_scalar("SELECT error FROM jobs")
        .fetch_one(store.pool())
        .await
        .unwrap();
    assert!(error.contains("lease expired after 2 attempts"), "{error}");
}

#[tokio::test]
async fn a_job_out_of_attempts_is_failed_with_the_reason() {
    each_backend(|store| async move {
        let (spec, jobs) = sweep(1, &[0.2]);
        let created = store.create_sweep(&spec, &jobs, 2).await.unwrap();
        for _ in 0..2 {
            store
                .claim("flaky", Duration::from_millis(1))
                .await
                .unwrap()
                .unwrap();
            tokio::time::sleep(Duration::from_millis(20)).await;
        }
        assert_failed_after_two_attempts(&store, &created.id).await;
    })
    .await;
}

/// Claims the sweep's one job with a lease that runs out at once, saves a
/// checkpoint at `step` if given, and lets the lease lapse.
async fn interrupted(store: &Store, step: Option<u64>) -> i64 {
    let c = store
        .claim("preempted", Duration::from_millis(1))
        .await
        .unwrap()
        .expect("the job is queued");
    if let Some(step) = step {
        let saved = store
            .save_checkpoint(&c.job_id, "preempted", step as f64 * 1e-3, step, b"state")
            .await
            .unwrap();
        assert!(saved, "the holder of the lease saves");
    }
    tokio::time::sleep(Duration::from_millis(20)).await;
    c.attempts
}

#[tokio::test]
async fn an_interruption_after_a_new_checkpoint_does_not_use_up_an_attempt() {
    each_backend(|store| async move {
        let (spec, jobs) = sweep(1, &[0.2]);
        let created = store.create_sweep(&spec, &jobs, 2).await.unwrap();
        // Five interruptions, each after a checkpoint further on: every
        // claim is the first attempt again.
        for step in 1..=5u64 {
            assert_eq!(
                interrupted(&store, Some(100 * step)).await,
                1,
                "claim {step}"
            );
        }
        // Saving the step it resumed from again is no progress, and a holder
        // that saves nothing is no progress either: those count.
        assert_eq!(interrupted(&store, Some(500)).await, 1);
        assert_eq!(interrupted(&store, None).await, 2);
        assert_failed_after_two_attempts(&store, &created.id).await;
        // Given fresh attempts, it still goes on from its last checkpoint.
        assert!(matches!(
            store.retry_failed(&created.id).await.unwrap(),
            repose_store::Retry::Queued(1)
        ));
        let c = store
            .claim("rescuer", Duration::from_secs(60))
            .await
            .unwrap()
            .unwrap();
        assert_eq!(c.attempts, 1);
        let kept = store.checkpoint(&c.job_id).await.unwrap().unwrap();
        assert_eq!(kept.iteration, 500);
    })
    .await;
}

#[tokio::test]
async fn cancelling_a_sweep_stops_claims_and_tells_running_workers() {
    each_backend(|store| async move {
        let (spec, jobs) = sweep(3, &[0.2]);
        let created = store.create_sweep(&spec, &jobs, 3).await.unwrap();
        let running = store
            .claim("w", Duration::from_secs(60))
            .await
            .unwrap()
            .unwrap();
        assert_eq!(
            store.cancel_sweep(&created.id).await.unwrap(),
            repose_store::Cancel::Cancelled
        );
        assert_eq!(
            store.cancel_sweep("no-such-sweep").await.unwrap(),
            repose_store::Cancel::Unknown
        );
        assert!(store
            .claim("w2", Duration::from_secs(60))
            .await
            .unwrap()
            .is_none());
        assert_eq!(
            store
                .heartbeat(&running.job_id, "w", Duration::from_secs(60))
                .await
                .unwrap(),
            Lease::Cancelled
        );
        assert!(store.release(&running.job_id, "w").await.unwrap());
        let p = store.progress(&created.id).await.unwrap();
        assert_eq!((p.cancelled, p.running, p.queued), (3, 0, 0));
    })
    .await;
}

#[tokio::test]
async fn a_finished_sweep_is_left_as_it_is_by_a_cancel() {
    each_backend(|store| async move {
        let report = report();
        let (spec, jobs) = sweep(2, &[0.2]);
        let created = store.create_sweep(&spec, &jobs, 3).await.unwrap();
        while let Some(c) = store.claim("w", Duration::from_secs(60)).await.unwrap() {
            store
                .complete(&c.job_id, "w", &c.sample_hash, &report)
                .await
                .unwrap();
        }
        let before = store.sweep(&created.id).await.unwrap().unwrap().state;
        assert_eq!(
            store.cancel_sweep(&created.id).await.unwrap(),
            repose_store::Cancel::Idle
        );
        let after = store.sweep(&created.id).await.unwrap().unwrap();
        assert_eq!(after.state, before);
        assert_ne!(after.state, "cancelled");
        let p = store.progress(&created.id).await.unwrap();
        assert_eq!((p.done, p.cancelled), (2, 0));
    })
    .await;
}

#[tokio::test]
async fn a_sweep_reuses_samples_already_computed_and_priority_orders_claims() {
    each_backend(|store| async move {
        let report = report();
        let (first, jobs) = sweep(2, &[0.2]);
        store.create_sweep(&first, &jobs, 3).await.unwrap();
        while let Some(c) = store.claim("w", Duration::from_secs(60)).await.unwrap() {
            store
                .complete(&c.job_id, "w", &c.sample_hash, &report)
                .await
                .unwrap();
        }
        // The same two samples plus two new ones.
        let (again, again_jobs) = sweep(4, &[0.2]);
        let created = store.create_sweep(&again, &again_jobs, 3).await.unwrap();
        assert_eq!((created.jobs, created.reused), (4, 2));
        // A later sweep of higher priority is claimed first.
        let (mut urgent, urgent_jobs) = sweep(1, &[0.3]);
        urgent.priority = 10;
        let u = store.create_sweep(&urgent, &urgent_jobs, 3).await.unwrap();
        let c = store
            .claim("w", Duration::from_secs(60))
            .await
            .unwrap()
            .unwrap();
        assert_eq!(c.sweep_id, u.id);
    })
    .await;
}

#[tokio::test]
async fn point_statistics_match_the_samples_they_summarise() {
    each_backend(|store| async move {
        let (spec, jobs) = sweep(5, &[0.1, 0.3]);
        let created = store.create_sweep(&spec, &jobs, 3).await.unwrap();
        let mut k = 0.0;
        while let Some(c) = store.claim("w", Duration::from_secs(60)).await.unwrap() {
            k += 1.0;
            // Samples without a result come first and in the middle: NULL
            // and non-NULL reasons must bind in either order.
            let r = if k == 1.0 || k == 4.0 {
                // a sample without a result: counted apart, no metric
                record("not_settled", &[])
            } else {
                record(
                    "completed",
                    &[
                        ("theta_r_endpoints", 30.0 - k),
                        ("theta_r_line", 20.0 + 0.5 * k),
                        ("theta_r", 10.0 + k * k),
                    ],
                )
            };
            store
                .complete(&c.job_id, "w", &c.sample_hash, &r)
                .await
                .unwrap();
        }
        let samples = store.samples(&created.id).await.unwrap();
        assert_eq!(samples.len(), 10);
        let points = store.points(&created.id).await.unwrap();
        assert_eq!(points.len(), 2);
        for p in &points {
            let mine: Vec<&repose_store::Sample> =
                samples.iter().filter(|s| s.point == p.point).collect();
            let values: Vec<f64> = mine
                .iter()
                .filter_map(|s| s.metrics.get("theta_r").copied())
                .collect();
            let n = values.len() as f64;
            let mean = values.iter().sum::<f64>() / n;
            let sd = (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
            let got = p.metrics["theta_r"];
            assert_eq!(got.n as usize, values.len());
            assert!((got.mean.unwrap() - mean).abs() < 1e-9);
            assert!((got.sd.unwrap() - sd).abs() < 1e-9);
            assert!((got.sem.unwrap() - sd / n.sqrt()).abs() < 1e-9);
            assert_eq!(
                p.failures as usize,
                mine.iter().filter(|s| s.outcome != "completed").count()
            );
            // No sample measured θ_T: the point has no entry for it.
            assert!(!p.metrics.contains_key("theta_t"));
            // A sample without a result has no metrics at all.
            for s in &mine {
                assert_eq!(s.outcome == "completed", s.metrics.len() == 3, "{s:?}");
            }
        }
        assert_eq!(points.iter().map(|p| p.failures).sum::<i64>(), 2);
        let s = repose_store::series(&points, "contact.mu", None, "theta_r").unwrap();
        assert_eq!(s.len(), 2);
        assert_eq!(s[0].x, json!(0.1));
        assert!(repose_store::series(&points, "box.width", None, "theta_r").is_err());
        assert!(repose_store::series(&points, "contact.mu", None, "volume").is_err());
    })
    .await;
}

#[tokio::test]
async fn the_sweep_list_gives_each_sweep_its_own_progress_cost_and_eta() {
    each_backend(|store| async move {
        let (spec, jobs) = sweep(3, &[0.1]);
        let first = store.create_sweep(&spec, &jobs, 3).await.unwrap();
        for _ in 0..2 {
            let c = store
                .claim("w", Duration::from_secs(60))
                .await
                .unwrap()
                .unwrap();
            assert!(store
                .complete(&c.job_id, "w", &c.sample_hash, &report())
                .await
                .unwrap());
        }
        store
            .claim("w", Duration::from_secs(60))
            .await
            .unwrap()
            .unwrap();
        let (spec, jobs) = sweep(4, &[0.7]);
        let second = store.create_sweep(&spec, &jobs, 3).await.unwrap();

        let listed = store.sweeps().await.unwrap();
        assert_eq!(listed.len(), 2);
        for info in &listed {
            let alone = store.sweep(&info.id).await.unwrap().unwrap();
            assert_eq!(info, &alone, "the list and the sweep's own page agree");
        }
        let of = |id: &str| listed.iter().find(|s| s.id == id).unwrap();
        let a = of(&first.id);
        assert_eq!(
            (a.progress.done, a.progress.running, a.progress.queued),
            (2, 1, 0)
        );
        assert_eq!((a.cost.samples, a.cost.particle_steps), (2, 2000));
        // One job left, one running, 0.01 s a finished sample.
        assert!((a.eta_seconds.unwrap() - 0.01).abs() < 1e-12);
        let b = of(&second.id);
        assert_eq!((b.progress.queued, b.progress.done), (4, 0));
        assert_eq!(b.cost.samples, 0);
        assert_eq!(b.eta_seconds, None, "nothing finished and nothing running");
        assert!(store.sweep("no-such-sweep").await.unwrap().is_none());
    })
    .await;
}

#[tokio::test]
async fn a_sample_queued_by_two_sweeps_runs_once_from_its_furthest_checkpoint() {
    each_backend(|store| async move {
        let (first, jobs) = sweep(1, &[0.2]);
        let a = store.create_sweep(&first, &jobs, 3).await.unwrap();
        let j1 = store
            .claim("w1", Duration::from_secs(60))
            .await
            .unwrap()
            .unwrap();
        assert!(store
            .save_checkpoint(&j1.job_id, "w1", 0.1, 100, b"at 100")
            .await
            .unwrap());
        // The same sample queued again, more urgently, while it runs.
        let (mut again, again_jobs) = sweep(1, &[0.2]);
        again.priority = 10;
        let b = store.create_sweep(&again, &again_jobs, 3).await.unwrap();
        assert_eq!(b.reused, 0, "no result yet");
        assert!(
            store
                .claim("w2", Duration::from_secs(60))
                .await
                .unwrap()
                .is_none(),
            "a sample runs on one worker at a time"
        );
        // Handed back, the urgent copy goes on from the first one's checkpoint.
        assert!(store.release(&j1.job_id, "w1").await.unwrap());
        let j2 = store
            .claim("w2", Duration::from_secs(60))
            .await
            .unwrap()
            .unwrap();
        assert_eq!(j2.sweep_id, b.id);
        let from = store.furthest_checkpoint(&j2.sample_hash).await.unwrap();
        assert_eq!(
            from.map(|c| (c.iteration, c.state)),
            Some((100, b"at 100".to_vec()))
        );
        assert!(store
            .save_checkpoint(&j2.job_id, "w2", 0.2, 200, b"at 200")
            .await
            .unwrap());
        assert!(store.release(&j2.job_id, "w2").await.unwrap());
        // Whichever copy runs next goes on from the furthest checkpoint.
        let c = store
            .claim("w1", Duration::from_secs(60))
            .await
            .unwrap()
            .unwrap();
        assert_eq!(c.job_id, j2.job_id, "priority still orders the claims");
        let resumed = store.furthest_checkpoint(&c.sample_hash).await.unwrap();
        assert_eq!(resumed.map(|c| c.iteration), Some(200));
        assert!(store
            .complete(&c.job_id, "w1", &c.sample_hash, &report())
            .await
            .unwrap());
        // One run, both sweeps done with its result, no checkpoint left.
        for sweep in [&a.id, &b.id] {
            let p = store.progress(sweep).await.unwrap();
            assert_eq!((p.done, p.queued, p.running), (1, 0, 0), "sweep {sweep}");
            let points = store.points(sweep).await.unwrap();
            assert_eq!(points[0].samples, 1);
        }
        assert!(store
            .furthest_checkpoint(&c.sample_hash)
            .await
            .unwrap()
            .is_none());
        assert!(store
            .claim("w1", Duration::from_secs(60))
            .await
            .unwrap()
            .is_none());
    })
    .await;
}

#[tokio::test]
async fn a_study_sweep_with_the_same_spec_and_samples_is_found_again() {
    each_backend(|store| async move {
        let (mut new, jobs) = sweep(2, &[0.1, 0.2]);
        // A sweep of no study is never matched: each POST is its own sweep.
        store.create_sweep(&new, &jobs, 3).await.unwrap();
        assert!(store.same_sweep(&new, &jobs).await.unwrap().is_none());
        new.study = Some("lh93/fig2".into());
        assert!(store.same_sweep(&new, &jobs).await.unwrap().is_none());
        let created = store.create_sweep(&new, &jobs, 3).await.unwrap();
        let claim = store
            .claim("w", Duration::from_secs(60))
            .await
            .unwrap()
            .unwrap();
        let done = store
            .complete(&claim.job_id, "w", &claim.sample_hash, &report())
            .await
            .unwrap();
        assert!(done);
        let found = store.same_sweep(&new, &jobs).await.unwrap().unwrap();
        assert_eq!(found.id, created.id);
        assert_eq!((found.jobs, found.reused), (4, 1));
        // Other samples under the same spec (another engine's hashes), or
        // jobs in another order, are another sweep.
        let mut renamed = jobs.clone();
        renamed[3].sample_hash.push_str("/v2");
        assert!(store.same_sweep(&new, &renamed).await.unwrap().is_none());
        let reversed: Vec<NewJob> = jobs.iter().rev().cloned().collect();
        assert!(store.same_sweep(&new, &reversed).await.unwrap().is_none());
        let mut other = new.clone();
        other.spec["samples"] = json!(3);
        assert!(store.same_sweep(&other, &jobs).await.unwrap().is_none());
    })
    .await;
}
