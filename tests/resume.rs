//! A long sample survives its worker: a heap's worker saves a checkpoint
//! every second and is killed with SIGKILL mid-pour; a second worker takes
//! the job over once the lease runs out, continues from the checkpoint,
//! and stores the result an uninterrupted run of the same scene gives, bit
//! for bit. On SQLite and on PostgreSQL. A worker stopped with SIGTERM
//! saves the heap before it hands the job back, however long ago its last
//! checkpoint was.

use repose_physics::report::simulated_numbers;
use repose_physics::{Quiet, Scene};
use repose_store::Store;
use repose_sweeps::SweepSpec;
use serde_json::{json, Value};
use std::io::Read;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

#[path = "common/mod.rs"]
mod common;

use common::{create, scratch, signal, Server, BIN};

/// A heap of a few seconds: 3000 grains poured on a 20 d plate.
fn spec() -> SweepSpec {
    serde_json::from_value(json!({
        "protocol": "heap",
        "base": {
            "material": {"surface_energy": 0.0},
            "heap": {"plate": 20.0, "max_grains": 3000, "settle_max": 100.0}
        },
        "seed_base": 7,
        "fidelity": "quick"
    }))
    .unwrap()
}

fn start_worker(database: &str) -> Child {
    worker_saving_every(database, "1")
}

/// A worker on `database` that saves a running sample every `seconds`.
fn worker_saving_every(database: &str, seconds: &str) -> Child {
    Command::new(BIN)
        .args(["worker", "--database", database])
        .args([
            "--lease",
            "3",
            "--heartbeat",
            "1",
            "--checkpoint-every",
            seconds,
        ])
        .env("REPOSE_LOG", "repose_worker=info")
        .stderr(Stdio::piped())
        .spawn()
        .expect("repose worker starts")
}

/// Every simulated number of a report (how it was computed left out), as
/// the text JSON writes it: equal text means equal bits.
fn numbers(report: &str) -> Value {
    simulated_numbers(serde_json::from_str(report).unwrap())
}

async fn wait_for<T, F: std::future::Future<Output = Option<T>>>(
    what: &str,
    mut probe: impl FnMut() -> F,
) -> T {
    let start = Instant::now();
    loop {
        if let Some(t) = probe().await {
            return t;
        }
        assert!(start.elapsed() < Duration::from_secs(120), "no {what}");
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
}

/// Lets `worker` finish the store's one sample, stops it, and returns
/// its log.
async fn finish(store: &Store, sweep: &str, mut worker: Child) -> String {
    wait_for("result", || async {
        let p = store.progress(sweep).await.unwrap();
        (p.done == 1).then_some(())
    })
    .await;
    signal(&worker, "KILL");
    let _ = worker.wait();
    let mut log = String::new();
    worker
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut log)
        .unwrap();
    log
}

async fn resumes_after_a_kill(database: &str) {
    let store = Store::open(database).await.unwrap();
    let (created, _) = create(&store, &spec(), 3).await;
    let job: String = sqlx::query_scalar("SELECT id FROM jobs")
        .fetch_one(store.pool())
        .await
        .unwrap();

    let mut first = start_worker(database);
    // Two checkpoints in, the first worker dies without a word.
    let saved = wait_for("first checkpoint", || async {
        store.checkpoint(&job).await.unwrap()
    })
    .await;
    let later = wait_for("later checkpoint", || async {
        let c = store.checkpoint(&job).await.unwrap()?;
        (c.iteration > saved.iteration).then_some(c)
    })
    .await;
    // The sweep tells how far its running job has come.
    let running = store.sweep(&created.id).await.unwrap().unwrap().running;
    assert_eq!(running.len(), 1, "{running:?}");
    assert_eq!(running[0].job_id, job);
    assert!(running[0].iteration >= later.iteration && running[0].sim_time >= later.sim_time);
    signal(&first, "KILL");
    let _ = first.wait();
    assert_eq!(store.progress(&created.id).await.unwrap().done, 0);

    let log = finish(&store, &created.id, start_worker(database)).await;

    let stored: String = sqlx::query_scalar("SELECT report FROM result_reports")
        .fetch_one(store.pool())
        .await
        .unwrap();
    assert!(store.checkpoint(&job).await.unwrap().is_none());
    assert!(store
        .sweep(&created.id)
        .await
        .unwrap()
        .unwrap()
        .running
        .is_empty());
    let whole = uninterrupted(&store).await;
    assert!(whole.outcome.is_completed(), "{:?}", whole.outcome);
    let resumed_at = log
        .lines()
        .find(|l| l.contains("continuing from the checkpoint"))
        .unwrap_or_else(|| panic!("the second worker did not resume:\n{log}"));
    // The first worker may have saved once more between the probe and the kill.
    let step: u64 = resumed_at
        .split("step=")
        .nth(1)
        .and_then(|s| s.split_whitespace().next())
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("no step in {resumed_at}"));
    assert!(
        step >= later.iteration as u64 && step < whole.iterations,
        "{resumed_at}"
    );
    assert!(
        numbers(&stored) == numbers(&serde_json::to_string(&whole).unwrap()),
        "the resumed result differs from the uninterrupted run"
    );
    println!(
        "{database}: worker killed after its checkpoint at step {} of {} ({:.2} of {:.2} s simulated, {} bytes); the next resumed at step {step}",
        later.iteration, whole.iterations, later.sim_time, whole.simulated_time, later.state.len()
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_killed_workers_heap_resumes_bit_for_bit_on_sqlite() {
    let db = format!("sqlite://{}", scratch("resume.db").display());
    resumes_after_a_kill(&db).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_killed_workers_heap_resumes_bit_for_bit_on_postgres() {
    let Some(pg) = common::postgres().await else {
        return;
    };
    resumes_after_a_kill(pg.url()).await;
    let store = Store::open(pg.url()).await.unwrap();
    repose_testkit::drop_postgres(pg, store).await;
}

/// Every simulated number of the scene of the store's one job, run here
/// without a stop.
async fn uninterrupted(store: &Store) -> repose_physics::RunReport {
    let scene: String = sqlx::query_scalar("SELECT scene FROM jobs")
        .fetch_one(store.pool())
        .await
        .unwrap();
    let scene = Scene::from_stored(serde_json::from_str(&scene).unwrap()).unwrap();
    repose_physics::run(&scene, &mut Quiet).unwrap()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_heap_handed_back_on_sigterm_is_saved_first_and_resumes_bit_for_bit() {
    let database = format!("sqlite://{}", scratch("hand-back.db").display());
    let store = Store::open(&database).await.unwrap();
    let (created, _) = create(&store, &spec(), 3).await;
    // Checkpoints ten minutes apart: none falls due during the run.
    let mut first = worker_saving_every(&database, "600");
    wait_for("the pour under way", || async {
        let p = store.progress(&created.id).await.unwrap();
        (p.running == 1).then_some(())
    })
    .await;
    tokio::time::sleep(Duration::from_secs(2)).await;
    signal(&first, "TERM");
    let status = first.wait().unwrap();
    assert!(status.success());
    let job: String = sqlx::query_scalar("SELECT id FROM jobs")
        .fetch_one(store.pool())
        .await
        .unwrap();
    let saved = store
        .checkpoint(&job)
        .await
        .unwrap()
        .expect("a checkpoint saved on the way out");
    let p = store.progress(&created.id).await.unwrap();
    assert_eq!((p.queued, p.running, p.done), (1, 0, 0));
    let grains = saved_grains_served(&database, &job);

    let log = finish(&store, &created.id, worker_saving_every(&database, "600")).await;
    assert!(
        log.contains(&format!(
            "continuing from the checkpoint job={job} step={}",
            saved.iteration
        )),
        "{log}"
    );
    let stored: String = sqlx::query_scalar("SELECT report FROM result_reports")
        .fetch_one(store.pool())
        .await
        .unwrap();
    let whole = uninterrupted(&store).await;
    assert!(saved.iteration > 0 && (saved.iteration as u64) < whole.iterations);
    // Stopped mid-pour: fewer grains than the whole run poured.
    let poured = whole.metric("grains_poured").unwrap();
    assert!(
        grains > 0 && (grains as f64) < poured,
        "{grains} of {poured}"
    );
    assert!(
        numbers(&stored) == numbers(&serde_json::to_string(&whole).unwrap()),
        "the resumed result differs from the uninterrupted run"
    );
}

/// Where the grains of `job`'s checkpoint are, read through the server
/// (`repose grains`) without resuming it: checked against the scene (below
/// the domain's top, most over the plate, every radius the scene's)
/// and handed to `repose measure-heap`, which reads a heap from it.
/// Returns how many grains the checkpoint holds.
fn saved_grains_served(database: &str, job: &str) -> usize {
    let server = Server::start(database, 0);
    let out = scratch("grains.txt");
    let run = |args: &[&str]| {
        Command::new(BIN)
            .args(args)
            .args(["--server", &server.url])
            .output()
            .unwrap()
    };
    let written = run(&["grains", job, "-o", out.to_str().unwrap()]);
    assert!(written.status.success(), "{written:?}");
    let text = std::fs::read_to_string(&out).unwrap();
    let d = 1e-3;
    let rows: Vec<Vec<f64>> = (text.lines())
        .filter(|l| !l.starts_with('#'))
        .map(|l| l.split_whitespace().map(|x| x.parse().unwrap()).collect())
        .collect();
    assert!(
        text.starts_with(&format!("# job {job}: checkpoint at ")),
        "{text}"
    );
    for g in &rows {
        assert!(g.len() == 4 && g[2] < 30.0 * d && g[3] == d / 2.0, "{g:?}");
    }
    // Most lie over the plate (a few roll off its edges and fall).
    let over = |g: &&Vec<f64>| g[0].abs() < 10.0 * d && g[1].abs() < 10.0 * d && g[2] > 0.0;
    let on = rows.iter().filter(over).count();
    assert!(
        10 * on >= 9 * rows.len(),
        "{on} of {} over the plate",
        rows.len()
    );
    let measured = Command::new(BIN)
        .args([
            "measure-heap",
            "--diameter",
            "1e-3",
            "--plate",
            "20",
            "--json",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(measured.status.success(), "{measured:?}");
    let metrics: Value = serde_json::from_slice(&measured.stdout).unwrap();
    assert!(metrics["heap_grains"].as_f64().unwrap() > 0.0, "{metrics}");
    let unknown = run(&["grains", "no-such-job"]);
    assert!(!unknown.status.success());
    assert!(String::from_utf8_lossy(&unknown.stderr).contains("no job with that id"));
    rows.len()
}
