//! The running aggregates per point equal the statistics recomputed from
//! the samples, on SQLite and PostgreSQL: results arriving in random order
//! with failures and missing metrics, sweeps that share samples, a sweep
//! created after some of its samples were stored (reused), and retries.

use rand_chacha::rand_core::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;
use repose_store::{NewJob, NewSweep, ResultRecord, Store};
use serde_json::json;
use std::time::Duration;

fn sweep(name: &str) -> NewSweep {
    NewSweep {
        name: name.into(),
        protocol: "fill_release".into(),
        spec: json!({}),
        priority: 0,
        study: None,
    }
}

/// Four points × `samples` seeds; the hash of (point, seed) is shared by
/// every sweep that has it.
fn jobs(points: &[f64], samples: u64) -> Vec<NewJob> {
    let mut v = Vec::new();
    for &mu in points {
        for seed in 1..=samples {
            let mut point = serde_json::Map::new();
            point.insert("contact.mu".into(), json!(mu));
            v.push(NewJob {
                point,
                sample: seed as u32,
                seed,
                sample_hash: format!("mu{mu}-seed{seed}"),
                scene: "{}".into(),
            });
        }
    }
    v
}

fn record(rng: &mut ChaCha8Rng, seed: u64) -> ResultRecord {
    let u = |rng: &mut ChaCha8Rng| rng.next_u64() as f64 / u64::MAX as f64;
    let failed = u(rng) < 0.15;
    let mut metrics = std::collections::BTreeMap::new();
    if !failed {
        metrics.insert("theta_r".to_string(), 10.0 + 20.0 * u(rng));
        if u(rng) < 0.7 {
            metrics.insert("theta_r_line".to_string(), -5.0 + 1e3 * u(rng));
        }
    }
    ResultRecord {
        engine: "test".into(),
        seed,
        outcome: if failed { "not_settled" } else { "completed" }.into(),
        reason: failed.then(|| "not settled".to_string()),
        metrics,
        counts: Default::default(),
        report: "{}".into(),
    }
}

/// Claims and completes up to `n` jobs, failing some claims outright.
async fn work(store: &Store, rng: &mut ChaCha8Rng, n: usize) {
    for _ in 0..n {
        let Some(job) = store.claim("w", Duration::from_secs(60)).await.unwrap() else {
            return;
        };
        if rng.next_u64() % 10 == 0 {
            store.fail(&job.job_id, "w", "lost").await.unwrap();
            continue;
        }
        let r = record(rng, job.attempts as u64);
        store
            .complete(&job.job_id, "w", &job.sample_hash, &r)
            .await
            .unwrap();
    }
}

async fn assert_aggregates_match(store: &Store, sweeps: &[String]) {
    for id in sweeps {
        let running = store.points(id).await.unwrap();
        let recomputed = store.points_recomputed(id).await.unwrap();
        assert_eq!(running.len(), recomputed.len(), "{id}");
        for (a, b) in running.iter().zip(&recomputed) {
            assert_eq!(
                (&a.point, a.samples, a.failures),
                (&b.point, b.samples, b.failures)
            );
            assert_eq!(
                a.metrics.keys().collect::<Vec<_>>(),
                b.metrics.keys().collect::<Vec<_>>()
            );
            for (name, x) in &a.metrics {
                let y = &b.metrics[name];
                assert_eq!(x.n, y.n, "{name}");
                let close = |p: Option<f64>, q: Option<f64>| match (p, q) {
                    (Some(p), Some(q)) => (p - q).abs() <= 1e-9 * (1.0 + q.abs()),
                    (p, q) => p == q,
                };
                assert!(
                    close(x.mean, y.mean) && close(x.sd, y.sd),
                    "{name}: {x:?} {y:?}"
                );
            }
        }
    }
}

async fn exercise(store: &Store) {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let a = store
        .create_sweep(&sweep("a"), &jobs(&[0.1, 0.2, 0.3, 0.4], 12), 3)
        .await
        .unwrap();
    work(store, &mut rng, 40).await;
    // B shares half of A's points, some of them stored already.
    let b = store
        .create_sweep(&sweep("b"), &jobs(&[0.3, 0.4, 0.5], 12), 3)
        .await
        .unwrap();
    assert!(b.reused > 0);
    work(store, &mut rng, 40).await;
    store.retry_failed(&a.id).await.unwrap();
    store.retry_failed(&b.id).await.unwrap();
    work(store, &mut rng, 1000).await;
    let ids = [a.id, b.id];
    assert_aggregates_match(store, &ids).await;
    let total: i64 = store
        .points(&ids[0])
        .await
        .unwrap()
        .iter()
        .map(|p| p.samples)
        .sum();
    assert!(total > 40, "{total}");
}

#[tokio::test]
async fn running_aggregates_equal_the_samples_on_sqlite() {
    exercise(&repose_testkit::sqlite("repose-agg").await).await;
}

#[tokio::test]
async fn running_aggregates_equal_the_samples_on_postgres() {
    let Some(db) = repose_testkit::postgres("repose_agg").await else {
        return;
    };
    let store = db.open().await.unwrap();
    exercise(&store).await;
    repose_testkit::drop_postgres(db, store).await;
}
