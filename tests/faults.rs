//! Faults through a 300-job sweep, on SQLite and on PostgreSQL: worker
//! processes killed with SIGKILL every two to three seconds and started
//! again, the server killed and started again once, and (on PostgreSQL)
//! the database restarted once (checked by its start time). At least
//! three kills must catch a worker inside a job. Every job must end done
//! with exactly one result, none stuck, and the running aggregates must equal the samples.
//! Jobs whose attempts the kills used up are run again with `repose retry`.

use repose_store::Store;
use serde_json::{json, Value};
use std::process::{Child, Command};
use std::time::{Duration, Instant};

#[path = "common/mod.rs"]
mod common;

use common::{post, scratch, signal, worker, Server, BIN};

const JOBS: u64 = 300;

/// Short leases, so that a killed worker's job returns within seconds.
const WORKER_ARGS: [&str; 4] = ["--lease", "3", "--heartbeat", "1"];

/// A sweep of `JOBS` samples of about a tenth of a second each.
fn spec() -> Value {
    json!({
        "protocol": "fill_release",
        "base": {"box": {"width": 4.0, "height": 2.0}},
        "samples": JOBS,
        "fidelity": "quick"
    })
}

/// What the run went through, for the test's output.
#[derive(Debug, Default)]
struct Faults {
    worker_kills: u32,
    /// Kills of a worker that held a running job at that moment.
    kills_mid_job: u32,
    server_restarts: u32,
    database_restarts: u32,
    retried: u64,
}

/// Restarts the local PostgreSQL cluster (Debian's `pg_ctlcluster`).
fn restart_postgres() -> bool {
    let Some(version) = std::fs::read_dir("/etc/postgresql")
        .ok()
        .and_then(|mut d| d.next())
        .and_then(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
    else {
        return false;
    };
    Command::new("pg_ctlcluster")
        .args(["--skip-systemctl-redirect", &version, "main", "restart"])
        .status()
        .is_ok_and(|s| s.success())
}

/// Whether the worker process `pid` holds a running job's lease (its
/// leases are named `host-pid-slot`).
async fn holds_a_job(store: &Store, pid: u32) -> bool {
    let held: Result<i64, _> = sqlx::query_scalar(&format!(
        "SELECT COUNT(*) FROM jobs WHERE state = 'running' AND lease_owner LIKE '%-{pid}-%'"
    ))
    .fetch_one(store.pool())
    .await;
    held.is_ok_and(|n| n > 0)
}

/// When the PostgreSQL server behind `store` started.
async fn postmaster_start(store: &Store) -> String {
    sqlx::query_scalar("SELECT CAST(pg_postmaster_start_time() AS TEXT)")
        .fetch_one(store.pool())
        .await
        .expect("the server answers")
}

fn respawn(workers: &mut [Child], k: usize, database: &str) {
    signal(&workers[k], "KILL");
    let _ = workers[k].wait();
    workers[k] = worker(database, &WORKER_ARGS);
}

/// Runs the sweep through the faults; returns what happened.
async fn through_faults(database: &str, store: &Store, postgres: bool) -> (String, Faults) {
    let mut server = Server::start(database, 0);
    let created = post(&format!("{}/api/sweeps", server.url), &spec()).await;
    let id = created["id"].as_str().expect("sweep queued").to_string();
    let mut workers: Vec<Child> = (0..2).map(|_| worker(database, &WORKER_ARGS)).collect();
    let mut f = Faults::default();
    let start = Instant::now();
    for round in 0u64.. {
        tokio::time::sleep(Duration::from_secs(2 + round % 2)).await;
        let progress = store.progress(&id).await;
        assert!(
            start.elapsed() < Duration::from_secs(300),
            "stuck: {progress:?} {f:?}"
        );
        let Ok(p) = progress else {
            continue; // the database is restarting
        };
        if p.done == JOBS as i64 {
            break;
        }
        if p.failed > 0 {
            let out = Command::new(BIN)
                .args(["retry", &id, "--server", &server.url])
                .output()
                .unwrap();
            assert!(
                out.status.success(),
                "{}",
                String::from_utf8_lossy(&out.stderr)
            );
            f.retried += p.failed as u64;
        }
        let k = (round % 2) as usize;
        if holds_a_job(store, workers[k].id()).await {
            f.kills_mid_job += 1;
        }
        respawn(&mut workers, k, database);
        f.worker_kills += 1;
        if f.server_restarts == 0 && p.done > JOBS as i64 / 4 {
            server.kill();
            server = Server::start(database, 0);
            f.server_restarts += 1;
        }
        if postgres && f.database_restarts == 0 && p.done > JOBS as i64 / 2 {
            let before = postmaster_start(store).await;
            assert!(
                restart_postgres(),
                "pg_ctlcluster could not restart PostgreSQL"
            );
            // It is the server under test that went down and came back.
            let after = postmaster_start(store).await;
            assert_ne!(before, after, "the test's PostgreSQL did not restart");
            f.database_restarts += 1;
        }
    }
    for w in &mut workers {
        let _ = w.kill();
        let _ = w.wait();
    }
    // The restarted server serves the finished sweep.
    let shown = common::get(&format!("{}/api/sweeps/{id}", server.url)).await;
    assert_eq!(shown["progress"]["done"], JOBS, "{shown}");
    (id, f)
}

async fn assert_done_once(store: &Store, id: &str) {
    let p = store.progress(id).await.unwrap();
    assert_eq!(
        (p.done, p.queued, p.running, p.failed),
        (JOBS as i64, 0, 0, 0),
        "{p:?}"
    );
    // One result in all for each job, and each job's own.
    let (results, answered): (i64, i64) = (
        sqlx::query_scalar("SELECT COUNT(*) FROM results")
            .fetch_one(store.pool())
            .await
            .unwrap(),
        sqlx::query_scalar(&format!(
            "SELECT COUNT(*) FROM jobs j JOIN results r ON r.sample_hash = j.sample_hash \
             WHERE j.sweep_id = '{id}'"
        ))
        .fetch_one(store.pool())
        .await
        .unwrap(),
    );
    assert_eq!((results, answered), (JOBS as i64, JOBS as i64));
    let running = store.points(id).await.unwrap();
    let recomputed = store.points_recomputed(id).await.unwrap();
    assert_eq!(running.len(), recomputed.len());
    for (a, b) in running.iter().zip(&recomputed) {
        assert_eq!((a.samples, a.failures), (b.samples, b.failures));
        assert_eq!(a.samples, JOBS as i64);
        for (name, x) in &a.metrics {
            let y = &b.metrics[name];
            assert_eq!(x.n, y.n, "{name}");
            let (mx, my) = (x.mean.unwrap(), y.mean.unwrap());
            assert!(
                (mx - my).abs() <= 1e-9 * (1.0 + my.abs()),
                "{name}: {mx} {my}"
            );
        }
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_job_ends_done_once_through_kills_on_sqlite() {
    let db = format!("sqlite://{}", scratch("faults.db").display());
    let store = Store::open(&db).await.unwrap();
    let (id, f) = through_faults(&db, &store, false).await;
    assert_done_once(&store, &id).await;
    assert!(f.kills_mid_job >= 3 && f.server_restarts == 1, "{f:?}");
    println!("SQLite: {JOBS} jobs done once through {f:?}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_job_ends_done_once_through_kills_and_a_restart_on_postgres() {
    let Some(pg) = common::postgres().await else {
        return;
    };
    let db = pg.url().to_string();
    let store = Store::open(&db).await.unwrap();
    let (id, f) = through_faults(&db, &store, true).await;
    assert_done_once(&store, &id).await;
    assert!(
        f.kills_mid_job >= 3 && f.server_restarts == 1 && f.database_restarts == 1,
        "{f:?}"
    );
    println!("PostgreSQL: {JOBS} jobs done once through {f:?}");
    repose_testkit::drop_postgres(pg, store).await;
}
