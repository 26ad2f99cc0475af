//! A sweep with `target_sem` gets samples at each point until the standard
//! error of its metric reaches the target or the point has `max_samples`,
//! run by real workers on a real SQLite store.

use repose_sweeps::SweepSpec;
use repose_worker::{run_worker, WorkerConfig};
use serde_json::json;

fn spec(extra: serde_json::Value) -> SweepSpec {
    let mut v = json!({
        "protocol": "fill_release",
        "base": {"box": {"width": 1.0, "height": 1.0}},
        "axes": {"contact.mu": [0.1, 0.3]},
        "samples": 3,
        "fidelity": "quick"
    });
    for (k, x) in extra.as_object().unwrap() {
        v[k] = x.clone();
    }
    serde_json::from_value(v).unwrap()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn points_get_samples_until_their_standard_error_reaches_the_target() {
    let store = repose_testkit::sqlite("repose-sem").await;
    let (target, max) = (0.6, 24);
    let s = spec(json!({"target_sem": target, "max_samples": max}));
    let jobs: Vec<_> = s.expand().unwrap().iter().map(|j| j.to_new_job()).collect();
    assert_eq!(jobs.len(), 6);
    let created = store.create_sweep(&s.new_sweep(), &jobs, 3).await.unwrap();
    let (_stop, rx) = tokio::sync::watch::channel(false);
    let workers: Vec<_> = (0..2)
        .map(|k| {
            let mut c = WorkerConfig::new(format!("w{k}"));
            c.exit_when_idle = true;
            tokio::spawn(run_worker(store.clone(), c, rx.clone()))
        })
        .collect();
    let mut written = 0;
    for w in workers {
        let tally = w.await.unwrap();
        assert_eq!((tally.lost, tally.failed), (0, 0), "{tally:?}");
        written += tally.completed;
    }
    // Each job claimed once and its result written once.
    let attempts: i64 = sqlx::query_scalar("SELECT MAX(attempts) FROM jobs")
        .fetch_one(store.pool())
        .await
        .unwrap();
    assert_eq!(attempts, 1);
    let points = store.points(&created.id).await.unwrap();
    let counts = store.point_jobs(&created.id).await.unwrap();
    assert_eq!(points.len(), 2);
    let mut grown = false;
    for (p, c) in points.iter().zip(&counts) {
        let a = p.metrics["theta_r"];
        assert_eq!(c.pending, 0);
        assert!(c.jobs <= max as i64, "{c:?}");
        assert_eq!(p.samples, c.jobs, "every job ran once");
        let met = a.sem.is_some_and(|sem| sem <= target);
        assert!(
            met || c.jobs == max as i64,
            "{:?}: {a:?} after {} jobs",
            p.point,
            c.jobs
        );
        grown |= c.jobs > 3;
        // Seeds run on from the first samples, one per job.
        let samples = store.samples(&created.id).await.unwrap();
        let mut seeds: Vec<i64> = samples
            .iter()
            .filter(|s| s.point == p.point)
            .map(|s| s.seed)
            .collect();
        seeds.sort();
        assert_eq!(seeds, (0..c.jobs).collect::<Vec<_>>());
    }
    assert!(
        grown,
        "no point needed more than its first samples: {points:?}"
    );
    let jobs: i64 = counts.iter().map(|c| c.jobs).sum();
    assert_eq!(written as i64, jobs);
    let recomputed = store.points_recomputed(&created.id).await.unwrap();
    assert_eq!(
        points.iter().map(|p| p.samples).collect::<Vec<_>>(),
        recomputed.iter().map(|p| p.samples).collect::<Vec<_>>()
    );
}

#[test]
fn a_target_is_checked_naming_the_field() {
    for (extra, field) in [
        (json!({"target_sem": -1.0}), "target_sem"),
        (
            json!({"target_sem": 0.5, "target_metric": "colour"}),
            "target_metric",
        ),
        (json!({"target_sem": 0.5, "max_samples": 2}), "max_samples"),
        (json!({"max_samples": 9}), "target_sem"),
        (json!({"target_sem": 0.5, "max_samples": 100000}), "axes"),
    ] {
        let err = spec(extra.clone()).expand().unwrap_err();
        assert_eq!(err.errors[0].field, field, "{extra}: {err}");
    }
    let ok = spec(json!({"target_sem": 0.5}));
    assert_eq!(ok.max_samples_per_point(), 30);
    assert_eq!(ok.target_metric().as_deref(), Some("theta_r"));
}
