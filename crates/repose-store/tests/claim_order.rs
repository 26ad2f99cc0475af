//! Jobs are claimed by sweep priority, then oldest sweep first, then in
//! job order; a cancelled sweep's jobs are never claimed. On SQLite and on
//! PostgreSQL, whose claim takes its own path (a lock and `SKIP LOCKED`).

use repose_store::{NewJob, NewSweep, Store};
use serde_json::json;
use std::time::Duration;

fn sweep(name: &str, priority: i64) -> NewSweep {
    NewSweep {
        name: name.into(),
        protocol: "free_run".into(),
        spec: json!({}),
        priority,
        study: None,
    }
}

fn jobs(tag: &str, n: u64) -> Vec<NewJob> {
    (0..n)
        .map(|k| NewJob {
            point: serde_json::Map::new(),
            sample: k as u32,
            seed: k,
            sample_hash: format!("{tag}-{k}"),
            scene: "{}".into(),
        })
        .collect()
}

#[tokio::test]
async fn claims_follow_priority_then_age_then_job_order_on_sqlite() {
    claims_follow_priority_then_age_then_job_order(repose_testkit::sqlite("repose-order").await)
        .await;
}

#[tokio::test]
async fn claims_follow_priority_then_age_then_job_order_on_postgres() {
    if let Some(db) = repose_testkit::postgres("repose_order").await {
        let store = db.open().await.unwrap();
        claims_follow_priority_then_age_then_job_order(store.clone()).await;
        repose_testkit::drop_postgres(db, store).await;
    }
}

async fn claims_follow_priority_then_age_then_job_order(store: Store) {
    store
        .create_sweep(&sweep("old", 0), &jobs("old", 3), 3)
        .await
        .unwrap();
    tokio::time::sleep(Duration::from_millis(5)).await;
    store
        .create_sweep(&sweep("urgent", 5), &jobs("urgent", 2), 3)
        .await
        .unwrap();
    tokio::time::sleep(Duration::from_millis(5)).await;
    store
        .create_sweep(&sweep("young", 0), &jobs("young", 2), 3)
        .await
        .unwrap();
    let cancelled = store
        .create_sweep(&sweep("gone", 9), &jobs("gone", 2), 3)
        .await
        .unwrap();
    assert_eq!(
        store.cancel_sweep(&cancelled.id).await.unwrap(),
        repose_store::Cancel::Cancelled
    );
    let mut order = Vec::new();
    while let Some(c) = store.claim("w", Duration::from_secs(60)).await.unwrap() {
        order.push(c.sample_hash);
    }
    assert_eq!(
        order,
        ["urgent-0", "urgent-1", "old-0", "old-1", "old-2", "young-0", "young-1"]
    );
}
