//! Faults through a 300-job sweep, on SQLite and on PostgreSQL: worker
//! processes killed with SIGKILL every two to three seconds and started
//! again, the server killed and started again once, and (on PostgreSQL)
//! the database restarted once. Every job must end done with exactly one
//! result, none stuck, and the running aggregates must equal the samples.
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
        let Ok(p) = store.progress(&id).await else {
            continue; // the database is restarting
        };
        if p.done == JOBS as i64 {
            break;
        }
        assert!(
            start.elapsed() < Duration::from_secs(300),
            "stuck: {p:?} {f:?}"
        );
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
        respawn(&mut workers, (round % 2) as usize, database);
        f.worker_kills += 1;
        if f.server_restarts == 0 && p.done > JOBS as i64 / 4 {
            server.kill();
            server = Server::start(database, 0);
            f.server_restarts += 1;
        }
        if postgres && f.database_restarts == 0 && p.done > JOBS as i64 / 2 {
            assert!(
                restart_postgres(),
                "pg_ctlcluster could not restart PostgreSQL"
            );
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
    let (results, distinct): (i64, i64) = (
        sqlx::query_scalar("SELECT COUNT(*) FROM results")
            .fetch_one(store.pool())
            .await
            .unwrap(),
        sqlx::query_scalar("SELECT COUNT(DISTINCT sample_hash) FROM jobs")
            .fetch_one(store.pool())
            .await
            .unwrap(),
    );
    assert_eq!((results, distinct), (JOBS as i64, JOBS as i64));
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
    assert!(f.worker_kills >= 3 && f.server_restarts == 1, "{f:?}");
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
        f.worker_kills >= 3 && f.server_restarts == 1 && f.database_restarts == 1,
        "{f:?}"
    );
    println!("PostgreSQL: {JOBS} jobs done once through {f:?}");
    repose_testkit::drop_postgres(pg, store).await;
}
